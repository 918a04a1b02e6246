"""limber.sweep against itself: the same table from one process, from local processes and from a Dask
LocalCluster of 2 processes on 127.0.0.1 (which the test starts and stops, leaving no process);
a failing configuration is an error row; a resumed sweep keeps its file's rows and runs only the
rest; a bad grid names its file and field. (test_sweep_faults.py: dead workers, crashes, timeouts,
signals; test_sweep_file.py: the output file.) The rows' physics is checked where it is known:
Featherstone RK4 converges on its reference (fourth order) and keeps joints closed to rounding."""
import json
import math
import os
import pathlib
import subprocess
import sys

import pandas as pd
import pytest

import limber.sweep

SCENES = pathlib.Path(os.environ.get("LIMBER_SOURCE_DIR", pathlib.Path(__file__).parents[2])) / "tools" / "scenes"

GRID = {
    "duration": 0.5,
    "sample_interval": 0.05,
    "scenes": [{"scene": str(SCENES / "chain.json"), "name": "chain-5"}],
    "methods": [
        {"method": "weighted", "projection": "pbd", "substeps": 1, "iterations": [4, 40]},
        {"method": "featherstone", "integrator": "rk4"},
        {"method": "featherstone", "iterations": 3},  # not a Featherstone option: error rows
    ],
    "settings": {"dt": [0.01, 0.005, 0.0025]},
    "reference": {"method": "featherstone", "integrator": "rk4", "dt": 0.000625},
}


def deterministic(table):
    """Every column but the wall-time measurements: the same bits whoever runs the sweep."""
    return table[[c for c in table.columns if c not in limber.sweep.MEASURED]]


@pytest.fixture(scope="module")
def one_process():
    return limber.sweep.sweep(GRID, workers=1)


def test_rows_are_the_grids_product_in_order_with_error_rows(one_process):
    table = one_process
    assert list(table["index"]) == list(range(4 * 3))
    errors = table[table["status"] == "error"]
    assert list(errors["index"]) == [9, 10, 11]
    assert errors["error"].str.contains("--iterations: applies to the Verlet methods").all()
    ran = table[table["status"].isin(limber.sweep.COMPLETE)]  # 'ok', or 'inaccurate': a verdict on a whole run
    assert len(ran) == 9 and (ran["steps"] == (0.5 / ran["dt"]).round()).all()
    assert (ran["steps_per_second"] > 0).all()
    assert (ran[ran["status"] == "inaccurate"]["verdict"].str.startswith("inaccurate: ")).all()


def test_featherstone_rk4_converges_to_its_reference_at_fourth_order(one_process):
    rk4 = one_process[(one_process["method"] == "featherstone") & (one_process["status"] == "ok")].sort_values("dt")
    errors = rk4["trajectory_error"].to_numpy()
    assert (rk4["max_joint_gap"] < 1e-12).all()  # reduced coordinates: joints cannot open
    order = [math.log2(errors[k + 1] / errors[k]) for k in range(len(errors) - 1)]
    assert all(3.5 < p < 4.5 for p in order), order


def test_local_processes_give_the_same_table(one_process):
    pd.testing.assert_frame_equal(deterministic(limber.sweep.sweep(GRID, workers=2)), deterministic(one_process), check_exact=True)


def children():
    """Processes whose parent is this one (Linux /proc)."""
    out = []
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == os.getpid() and fields[0] != "Z":
            out.append(stat.parent.name)
    return out


def test_a_dask_cluster_of_two_processes_gives_the_same_table_and_leaves_no_process(one_process):
    distributed = pytest.importorskip("distributed")
    before = set(children())
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            table = limber.sweep.sweep(GRID, client=client)
    pd.testing.assert_frame_equal(deterministic(table), deterministic(one_process), check_exact=True)
    assert set(children()) <= before


def test_a_resumed_sweep_keeps_its_files_rows_and_runs_only_the_rest(tmp_path, one_process):
    out = tmp_path / "results.csv"
    limber.sweep.sweep(GRID, workers=2, out=out)
    first = pd.read_csv(out, keep_default_na=False, dtype=str).sort_values("index", key=lambda i: i.astype(int)).iloc[:5]
    first["steps_per_second"] = "-1.0"  # a mark no run gives
    first.to_csv(out, index=False)  # as a sweep stopped after five rows leaves it (its .sweep kept)
    ran = []
    table = limber.sweep.sweep(GRID, workers=1, out=out, progress=lambda done, total: ran.append(done))
    assert ran == list(range(6, 13))  # the 7 rows the file lacked, one at a time
    assert (table["steps_per_second"].iloc[:5] == -1).all()  # kept, not rerun
    pd.testing.assert_frame_equal(deterministic(table), deterministic(one_process), check_exact=True)
    reread = pd.read_csv(out, float_precision="round_trip", keep_default_na=False, na_values=["nan"])
    pd.testing.assert_frame_equal(deterministic(reread), deterministic(one_process), check_exact=True, check_dtype=False)


def test_the_command_runs_a_grid_file_and_refuses_a_bad_one(tmp_path):
    grid = dict(GRID, scenes=[{"scene": "chain.json"}], methods=[{"method": "featherstone"}], settings={"dt": 0.01})
    (tmp_path / "chain.json").write_text((SCENES / "chain.json").read_text())
    (tmp_path / "grid.json").write_text(json.dumps(grid))
    command = [sys.executable, "-m", "limber.sweep", str(tmp_path / "grid.json"), "--workers", "1", "--out", str(tmp_path / "out.csv")]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert list(pd.read_csv(tmp_path / "out.csv")["status"]) == ["ok"]  # the scene found beside the grid

    (tmp_path / "bad.json").write_text(json.dumps(dict(grid, duraton=1)))
    done = subprocess.run(command[:3] + [str(tmp_path / "bad.json"), "--out", str(tmp_path / "bad.csv")], capture_output=True, text=True)
    assert done.returncode == 2 and "bad.json: duraton: unknown field" in done.stderr
    assert not (tmp_path / "bad.csv").exists()
    done = subprocess.run(command[:3] + [str(tmp_path / "grid.json"), "--out", str(tmp_path / "no" / "out.csv")], capture_output=True, text=True)
    assert done.returncode == 2 and "its folder does not exist" in done.stderr


def test_a_bad_grid_names_its_field():
    with pytest.raises(limber.sweep.GridError, match=r"scenes\[1\]\.name: 'chain-5' names an earlier scene"):
        limber.sweep.sweep(dict(GRID, scenes=GRID["scenes"] * 2), workers=1)
    with pytest.raises(limber.sweep.GridError, match="methods: required, a non-empty list"):
        limber.sweep.sweep(dict(GRID, methods=[]), workers=1)
    with pytest.raises(limber.sweep.GridError, match=r"settings\.dt: an empty list"):
        limber.sweep.sweep(dict(GRID, settings={"dt": []}), workers=1)
