"""limber.sweep loses nothing to a process: a worker process that dies has its configuration run
again (RETRIES times, then a 'worker_died' row), and a resumed sweep runs such rows again; a scene
whose loader crashes is a row, not a lost sweep; a configuration past the grid's timeout is a
'timeout' row; SIGINT or SIGTERM stops the sweep at once, keeping the rows it wrote; and no worker
process outlives the sweep, even a SIGKILLed one. Faults are real signals: the sweep runs as a
command, with sweep_harness.py planting them where configurations run."""
import os
import pathlib
import signal
import subprocess

import pandas as pd
import pytest

import limber.sweep
from sweep_helpers import LIMIT, alive, command, descendants, end, grid_file, rows, run, scene, wait_until


def small_grid(scenes, **fields):
    """Featherstone on `scenes` (files beside the grid) at two time steps: 0.2 s, a few ms a run."""
    return {"duration": 0.2, "sample_interval": 0.05, "scenes": [{"scene": s} for s in scenes],
            "methods": [{"method": "featherstone", "dt": [0.01, 0.005]}], **fields}


def test_a_killed_worker_has_its_configuration_run_again_and_the_others_are_untouched(tmp_path):
    grid = grid_file(tmp_path, small_grid([scene(tmp_path, "killed-once.json"), scene(tmp_path, "chain.json")]))
    done = run(command(grid, tmp_path / "out.csv", "--workers", "2", harness=True))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "killed-once.json.killed").exists()  # a worker did die
    assert "its worker process died (killed by SIGKILL); running it again (1 of 2 retries)" in done.stderr
    table = pd.read_csv(tmp_path / "out.csv")
    assert list(table["index"].sort_values()) == [0, 1, 2, 3]
    assert (table["status"] == "ok").all() and (table["steps"] == (0.2 / table["dt"]).round()).all()


def test_a_worker_that_always_dies_is_a_worker_died_row_that_a_resumed_sweep_runs_again(tmp_path):
    fine = scene(tmp_path, "chain.json")
    doomed = scene(tmp_path, "killed-always.json")
    # featherstone takes no iterations: an error row, once its scene has loaded.
    grid = small_grid([doomed, fine], methods=[{"method": "featherstone"}, {"method": "featherstone", "iterations": 3}])
    grid_path, out = grid_file(tmp_path, grid), tmp_path / "out.csv"
    done = run(command(grid_path, out, "--workers", "2", harness=True))
    assert done.returncode == 0, done.stderr
    table = pd.read_csv(out, keep_default_na=False).set_index("index").sort_index()
    assert list(table["status"]) == ["worker_died", "worker_died", "ok", "error"]
    assert table["error"].iloc[:2].str.contains("died 3 times running it \\(the last: killed by SIGKILL\\)").all()
    assert done.stderr.count("running it again (2 of 2 retries)") == 2

    # Resume, the scene now loading (no harness): the worker_died rows run again; the error rows,
    # deterministic, are kept (marked here, so a rerun would show).
    lines = out.read_text().splitlines(keepends=True)
    marked = [line.replace("applies to the Verlet methods", "applies to the Verlet methods [kept]") for line in lines]
    out.write_text("".join(marked))
    done = run(command(grid_path, out, "--workers", "2"))
    assert done.returncode == 0, done.stderr
    table = pd.read_csv(out, keep_default_na=False).set_index("index").sort_index()
    assert list(table["status"]) == ["ok", "error", "ok", "error"]
    assert "applies to the Verlet methods" in table.loc[1, "error"] and "[kept]" not in table.loc[1, "error"]  # run again
    assert "[kept]" in table.loc[3, "error"]


def test_a_scene_that_crashes_its_loader_is_a_row_and_the_sweep_completes(tmp_path):
    # One worker process: before, the sweep's own process loaded the scenes and died with them.
    names = [scene(tmp_path, "segfault.json"), scene(tmp_path, "chain.json")]
    grid = grid_file(tmp_path, small_grid(names, methods=[{"method": "featherstone", "dt": 0.01}]))
    done = run(command(grid, tmp_path / "out.csv", "--workers", "1", harness=True))
    assert done.returncode == 0, done.stderr
    table = pd.read_csv(tmp_path / "out.csv").set_index("scene")
    assert table.loc["segfault", "status"] == "worker_died"
    assert table.loc["segfault", "error"] == "its worker process died 3 times running it (the last: killed by SIGSEGV)"
    assert table.loc["chain", "status"] == "ok"


HANGING = {"method": "featherstone", "integrator": ["rk4", "semi-implicit"], "dt": 1e-8}  # 2·10⁷ steps each: minutes
TIMED = [HANGING, {"method": "featherstone", "dt": [0.01, 0.005]}]  # two that hang, then two that do not


def test_configurations_past_the_timeout_are_timeout_rows_and_the_others_finish(tmp_path):
    grid = small_grid([scene(tmp_path, "chain.json")], timeout=1.5, methods=TIMED)
    done = run(command(grid_file(tmp_path, grid), tmp_path / "out.csv", "--workers", "2"))
    assert done.returncode == 0, done.stderr
    table = pd.read_csv(tmp_path / "out.csv", keep_default_na=False).set_index("index").sort_index()
    assert list(table["status"]) == ["timeout", "timeout", "ok", "ok"]
    assert table["error"].iloc[:2].str.contains("timeout of 1.5 s|1.5 s after it started").all()


def test_a_dask_cluster_stops_configurations_at_the_timeout(tmp_path):
    distributed = pytest.importorskip("distributed")
    grid = small_grid([str(tmp_path / scene(tmp_path, "chain.json"))], timeout=1.5, methods=TIMED)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            table = limber.sweep.sweep(grid, client=client)
    assert list(table["status"]) == ["timeout", "timeout", "ok", "ok"]


def slow_grid(folder):
    """12 configurations of about a second each (featherstone RK4 at dt 10⁻⁵ s)."""
    grid = small_grid([scene(folder, "chain.json")], duration=0.3, sample_interval=0.1,
                      methods=[{"method": "featherstone", "integrator": ["rk4", "semi-implicit"],
                                "dt": [1e-5, 1.25e-5, 2e-5, 2.5e-5, 4e-5, 5e-5]}])
    return grid_file(folder, grid)


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_sweep_at_once_keeping_its_rows_and_no_process(tmp_path, stop):
    out = tmp_path / "out.csv"
    sweep = subprocess.Popen(command(slow_grid(tmp_path), out, "--workers", "2"), stderr=subprocess.PIPE, text=True)
    workers = {}
    try:
        wait_until(lambda: out.exists() and len(rows(out)) >= 2, "two rows")
        workers = descendants(sweep.pid)
        sweep.send_signal(stop)
        _, stderr = sweep.communicate(timeout=LIMIT)
        assert sweep.returncode == 128 + stop, stderr
        assert f"stopped by {stop.name}" in stderr and "the same command resumes" in stderr
        kept = rows(out)  # whole lines only
        assert 2 <= len(kept) < 12  # stopped, not run to the end
        wait_until(lambda: not alive(workers), "the workers' end", timeout=30)
        done = run(command(tmp_path / "grid.json", out, "--workers", "2"))
        assert done.returncode == 0, done.stderr
        assert rows(out)[:len(kept)] == kept and len(rows(out)) == 12
    finally:
        sweep.kill()
        sweep.wait()
        end(workers)


def test_a_sigkilled_sweep_leaves_no_worker_process(tmp_path):
    grid = small_grid([scene(tmp_path, "chain.json")], methods=[HANGING])
    out = tmp_path / "out.csv"
    sweep = subprocess.Popen(command(grid_file(tmp_path, grid), out, "--workers", "2"), stderr=subprocess.DEVNULL)
    workers = {}
    try:
        wait_until(lambda: _busy(descendants(sweep.pid)), "a worker running a configuration")
        workers = descendants(sweep.pid)
        sweep.kill()
        sweep.wait()
        wait_until(lambda: not alive(workers), "the workers' end", timeout=30)
    finally:
        sweep.kill()
        sweep.wait()
        end(workers)


def _busy(processes):
    """Whether one of `processes` has used a second of CPU (it is stepping a configuration)."""
    ticks = os.sysconf("SC_CLK_TCK")
    for pid in processes:
        try:
            fields = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if (int(fields[11]) + int(fields[12])) / ticks > 1:
            return True
    return False
