"""limber.sweep's output file: rows are whole lines, and a resumed sweep sets aside a line a kill or
a full disk cut short (or glued to the next row) and runs its configuration again; the file names
its grid, so another grid's table is refused, not resumed; one sweep writes a file at a time; a
FIFO, a folder or a missing folder as the output or the grid is refused by name in one line; the
summary counts the rows that lack their reference."""
import csv
import fcntl
import io
import os
import resource
import signal
import subprocess

import pandas as pd
import pytest

import limber.sweep
from sweep_helpers import LIMIT, SCENES, command, grid_file, rows, run, scene, wait_until

GRID = {"duration": 0.2, "sample_interval": 0.05, "scenes": [{"scene": str(SCENES / "chain.json"), "name": "chain-5"}],
        "methods": [{"method": "featherstone", "integrator": ["rk4", "semi-implicit"], "dt": [0.01, 0.005, 0.0025]}],
        "reference": {"method": "featherstone", "integrator": "rk4", "dt": 0.00125}}


def deterministic(table):
    return table[[c for c in table.columns if c not in limber.sweep.MEASURED]]


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """The grid's table, and its output file's text."""
    out = tmp_path_factory.mktemp("whole") / "out.csv"
    return limber.sweep.sweep(GRID, workers=1, out=out), out.read_text(), (out.parent / "out.csv.sweep").read_text()


def damaged(tmp_path, whole, edit):
    """An output file of the whole sweep, `edit`ed (a function of its lines), with its .sweep."""
    out = tmp_path / "out.csv"
    out.write_text(edit(whole[1].splitlines(keepends=True)))
    (tmp_path / "out.csv.sweep").write_text(whole[2])
    return out


def resume(out):
    with pytest.warns(limber.sweep.SweepWarning) as notes:
        table = limber.sweep.sweep(GRID, workers=1, out=out)
    return table, [str(n.message) for n in notes]


def test_rows_are_whole_lines_that_read_back_to_the_same_bits(whole):
    table, text, _ = whole
    assert text.endswith("\n") and len(text.splitlines()) == 1 + 6
    reread = pd.read_csv(io.StringIO(text), float_precision="round_trip", keep_default_na=False, na_values=["nan"])
    pd.testing.assert_frame_equal(deterministic(reread), deterministic(table), check_exact=True, check_dtype=False)


@pytest.mark.parametrize("cut", [1, 12, 40])
def test_a_last_line_cut_short_is_set_aside_and_its_configuration_runs_again(tmp_path, whole, cut):
    out = damaged(tmp_path, whole, lambda lines: "".join(lines[:-1]) + lines[-1][:cut])
    table, notes = resume(out)
    assert notes == [f"{out} line 7: cut short: no newline at its end; moved to {out}.damaged, and its configuration runs again"]
    assert whole[1].splitlines()[-1][:cut] in (tmp_path / "out.csv.damaged").read_text()
    pd.testing.assert_frame_equal(deterministic(table), deterministic(whole[0]), check_exact=True)
    reread = pd.read_csv(out, float_precision="round_trip", keep_default_na=False, na_values=["nan"])
    pd.testing.assert_frame_equal(deterministic(reread.sort_values("index").reset_index(drop=True)),
                                  deterministic(whole[0]), check_exact=True, check_dtype=False)


def test_a_row_glued_to_a_cut_one_is_set_aside_and_both_configurations_run_again(tmp_path, whole):
    # What a sweep killed mid-row and resumed by an older limber.sweep left: line 3 is row 1 cut
    # short with row 5's line glued on, rows 2 to 4 after it.
    def glue(lines):
        return "".join(lines[:2]) + lines[2][:30] + lines[6] + "".join(lines[3:6])
    out = damaged(tmp_path, whole, glue)
    table, notes = resume(out)
    assert len(notes) == 1 and notes[0].startswith(f"{out} line 3: ")
    pd.testing.assert_frame_equal(deterministic(table), deterministic(whole[0]), check_exact=True)
    assert len(rows(out)) == 6 and sorted(int(r.split(",")[0]) for r in rows(out)) == list(range(6))


def test_a_row_with_a_number_that_does_not_parse_is_set_aside(tmp_path, whole):
    def spoil(lines):
        fields = next(csv.reader([lines[4]]))
        fields[list(whole[0].columns).index("energy_drift")] = "0.0x1"
        return "".join(lines[:4]) + ",".join(fields) + "\n" + "".join(lines[5:])
    out = damaged(tmp_path, whole, spoil)
    table, notes = resume(out)
    assert notes == [f"{out} line 5: energy_drift: not a number: '0.0x1'; moved to {out}.damaged, and its configuration runs again"]
    pd.testing.assert_frame_equal(deterministic(table), deterministic(whole[0]), check_exact=True)


@pytest.mark.parametrize("status", ["timeout", "worker_died"])
def test_rows_a_rerun_may_change_run_again_and_others_are_kept(tmp_path, whole, status):
    columns = list(whole[0].columns)

    def field(line, column, value):  # `line` with `column` set to `value`
        fields = next(csv.reader([line]))
        fields[columns.index(column)] = value
        return ",".join(fields) + "\n"

    def mark(lines):  # row 2 as a sweep that gave up on it leaves it; row 3 marked, to show it is kept
        return "".join(lines[:3]) + field(lines[3], "status", status) + field(lines[4], "error", "kept") + "".join(lines[5:])
    out = damaged(tmp_path, whole, mark)
    ran = []
    table = limber.sweep.sweep(GRID, workers=1, out=out, progress=lambda done, total: ran.append(done))
    assert ran == [6] and list(table["status"]) == ["ok"] * 6 and table["error"].iloc[3] == "kept"
    assert table["steps_per_second"].iloc[2] != whole[0]["steps_per_second"].iloc[2]  # measured again
    assert len(rows(out)) == 6


def test_a_grid_whose_timeout_changed_resumes_its_table(tmp_path, whole):
    out = damaged(tmp_path, whole, "".join)
    ran = []
    table = limber.sweep.sweep(dict(GRID, timeout=60), workers=1, out=out, progress=lambda done, total: ran.append(done))
    assert ran == [] and out.read_text() == whole[1]
    pd.testing.assert_frame_equal(deterministic(table), deterministic(whole[0]), check_exact=True)


def test_a_full_disk_stops_the_sweep_with_whole_lines_and_it_resumes(tmp_path):
    # RLIMIT_FSIZE makes write(2) fail past a size as a full disk does (Python ignores SIGXFSZ).
    grid = grid_file(tmp_path, dict(GRID, scenes=[{"scene": scene(tmp_path, "chain.json")}]))
    out = tmp_path / "out.csv"
    size = len(header()) + 450  # the header and about two rows; the .sweep beside it is smaller

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
    done = subprocess.run(command(grid, out, "--workers", "1"), capture_output=True, text=True, timeout=LIMIT, preexec_fn=limit)
    assert done.returncode == 2, done.stderr
    assert f"{out}: cannot write a row: " in done.stderr and "Traceback" not in done.stderr
    assert 1 <= len(rows(out)) < 6  # whole lines only
    done = run(command(grid, out, "--workers", "1"))
    assert done.returncode == 0, done.stderr
    assert sorted(int(r.split(",")[0]) for r in rows(out)) == list(range(6))


def header():
    return ",".join(["index", "scene", "method", "integrator", "dt", *limber.sweep.METRICS]) + "\n"


def test_a_table_of_another_grid_is_refused_and_left_as_it_was(tmp_path, whole):
    # Same columns, other time steps: before, it was resumed, running nothing.
    other = dict(GRID, methods=[{"method": "featherstone", "integrator": ["rk4", "semi-implicit"], "dt": [0.02, 0.01, 0.005]}])
    out = damaged(tmp_path, whole, "".join)
    with pytest.raises(limber.sweep.OutputError, match="holds another grid's table .*it is not resumed or written over"):
        limber.sweep.sweep(other, workers=1, out=out)
    assert out.read_text() == whole[1] and (tmp_path / "out.csv.sweep").read_text() == whole[2]

    # Without its .sweep (written by hand, or by an older limber.sweep) nothing says which grid it is.
    (tmp_path / "out.csv.sweep").unlink()
    with pytest.raises(limber.sweep.OutputError, match="does not say which grid it is a table of"):
        limber.sweep.sweep(GRID, workers=1, out=out)
    assert out.read_text() == whole[1] and not (tmp_path / "out.csv.sweep").exists()

    other_columns = tmp_path / "other.csv"
    other_columns.write_text("index,something\n0,1\n")
    with pytest.raises(limber.sweep.OutputError, match="not resumed or written over"):
        limber.sweep.sweep(GRID, workers=1, out=other_columns)
    assert other_columns.read_text() == "index,something\n0,1\n"


def test_a_second_sweep_on_one_output_file_is_refused_by_name(tmp_path):
    # Two quick configurations, then one of 2·10⁷ steps: the first sweep is still running it.
    grid = grid_file(tmp_path, dict(GRID, scenes=[{"scene": scene(tmp_path, "chain.json")}], reference=None,
                                    methods=[{"method": "featherstone", "dt": [0.01, 0.005, 1e-8]}]))
    out = tmp_path / "out.csv"
    first = subprocess.Popen(command(grid, out, "--workers", "1"), stderr=subprocess.PIPE, text=True)
    try:
        wait_until(lambda: out.exists() and len(rows(out)) >= 2, "the first sweep's quick rows")
        second = run(command(grid, out, "--workers", "1"))
        assert second.returncode == 2, second.stderr
        assert second.stderr == (f"limber.sweep: {out}: another sweep is writing it ({out}.sweep is locked); wait for it "
                                 "to end, or choose another output file\n")
        first.terminate()
        _, stderr = first.communicate(timeout=LIMIT)
        assert first.returncode == 128 + signal.SIGTERM, stderr
    finally:
        first.kill()
        first.wait()
    assert [int(r.split(",")[0]) for r in rows(out)] == [0, 1]  # each once


def test_a_lock_held_refuses_the_sweep_before_it_runs_anything(tmp_path):
    out = tmp_path / "out.csv"
    with open(tmp_path / "out.csv.sweep", "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        with pytest.raises(limber.sweep.OutputError, match="another sweep is writing it"):
            limber.sweep.sweep(GRID, workers=1, out=out)
    assert not out.exists()


def test_a_fifo_folder_or_missing_folder_is_refused_in_one_line(tmp_path):
    grid = grid_file(tmp_path, dict(GRID, scenes=[{"scene": scene(tmp_path, "chain.json")}]))
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "folder").mkdir()
    for out, problem in [(tmp_path / "fifo", "is a FIFO, not a regular file"), (tmp_path / "folder", "is a folder, not a regular file"),
                         (tmp_path / "no" / "out.csv", "its folder does not exist")]:
        done = run(command(grid, out, "--workers", "1"))
        assert done.returncode == 2 and done.stderr == f"limber.sweep: {out}: {problem}\n"
    done = run(command(tmp_path / "fifo", tmp_path / "out.csv", "--workers", "1"))
    assert done.returncode == 2 and done.stderr == f"limber.sweep: {tmp_path / 'fifo'}: is a FIFO, not a regular file\n"
    assert not (tmp_path / "out.csv").exists()


def test_an_output_file_that_cannot_be_written_is_refused_in_one_line(tmp_path):
    grid = grid_file(tmp_path, dict(GRID, scenes=[{"scene": scene(tmp_path, "chain.json")}]))
    done = run(command(grid, "/proc/limber-sweep-test.csv", "--workers", "1"))  # no one, not even root, creates files there
    assert done.returncode == 2 and done.stderr.startswith("limber.sweep: /proc/limber-sweep-test.csv") and done.stderr.count("\n") == 1


def test_the_summary_counts_the_rows_without_their_reference(tmp_path):
    grid = dict(GRID, scenes=[{"scene": scene(tmp_path, "chain.json")}], reference={"method": "featherstone", "iterations": 3})
    done = run(command(grid_file(tmp_path, grid), tmp_path / "out.csv", "--workers", "1"))
    assert done.returncode == 0, done.stderr
    assert "(6 ok; 6 reference errors, the first: reference: OptionError: " in done.stderr
    assert "0 errors" not in done.stderr
