#!/usr/bin/python3
"""One grid swept four ways, raced in one run: wall time of each and whether their tables agree.

    PYTHONPATH=build/python bench/sweep_scaling.py [--grid bench/pareto_sweep/grid.json] [--rounds 3] [--out T.csv]

1. one worker process (limber.sweep's workers=1: one process runs every configuration);
2. 2 local processes (workers=2);
3. a Dask LocalCluster of 2 worker processes on 127.0.0.1;
4. a scheduler and 2 workers started as separate processes (dask-scheduler, dask-worker) on
   127.0.0.1, reached through their address as `python3 -m limber.sweep --scheduler` does.
Each round runs the four in turn (a cluster is started before its sweep is timed and stopped after);
the table gives each one's median wall time over the rounds, the CPU time this process spent
(it gathers the rows; with a LocalCluster it also runs the scheduler), and, for the LocalCluster,
the seconds its workers spent computing tasks (Dask's task stream). Every table must equal the first in
every column but the measured steps/s, bit for bit. Prints a markdown table; --out keeps the last
one-process table (tools/plot_pareto.py draws it). Needs Debian's
python3-distributed. Run it on a quiet machine: the workers share its cores.
"""
import argparse
import contextlib
import os
import resource
import statistics
import subprocess
import sys
import time

import distributed
import pandas as pd

import limber.sweep


@contextlib.contextmanager
def separate_cluster(port=8786):
    """dask-scheduler and 2 dask-worker processes on 127.0.0.1, stopped on exit."""
    address = f"tcp://127.0.0.1:{port}"
    environment = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    processes = [subprocess.Popen(["dask-scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                                  env=environment, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(2):
            processes.append(subprocess.Popen(["dask-worker", address, "--nworkers", "1", "--nthreads", "1", "--no-dashboard",
                                               "--host", "127.0.0.1"], env=environment, stdout=subprocess.DEVNULL,
                                              stderr=subprocess.DEVNULL))
        with distributed.Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
            yield client
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            process.wait(timeout=30)


def timed(run):
    start = time.perf_counter()
    table = run()
    return time.perf_counter() - start, table


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--grid", default="bench/pareto_sweep/grid.json")
    parser.add_argument("--out", help="the one-process table, CSV")
    parser.add_argument("--rounds", type=int, default=3)
    arguments = parser.parse_args()
    grid = limber.sweep.load_grid(arguments.grid)
    names = ["1 process", "2 local processes", "Dask LocalCluster, 2 workers", "dask-scheduler + 2 dask-workers, 127.0.0.1"]
    seconds, tables, cpu = ({name: [] for name in names} for _ in range(3))
    computing = []  # the LocalCluster workers' compute seconds, summed, per round

    def record(name, run):
        before = resource.getrusage(resource.RUSAGE_SELF)
        elapsed, table = timed(run)
        after = resource.getrusage(resource.RUSAGE_SELF)
        cpu[name].append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        seconds[name].append(elapsed), tables[name].append(table)

    for _ in range(arguments.rounds):
        record(names[0], lambda: limber.sweep.sweep(grid, workers=1))
        record(names[1], lambda: limber.sweep.sweep(grid, workers=2))
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as client:
            with distributed.get_task_stream(client) as stream:
                record(names[2], lambda: limber.sweep.sweep(grid, client=client))
            computing.append(sum(stop["stop"] - stop["start"] for task in stream.data for stop in task["startstops"]
                                 if stop["action"] == "compute"))
        with separate_cluster() as client:
            record(names[3], lambda: limber.sweep.sweep(grid, client=client))
    one = tables[names[0]][0]
    if arguments.out:
        tables[names[0]][-1].to_csv(arguments.out, index=False, na_rep="nan")
    deterministic = [c for c in one.columns if c not in limber.sweep.MEASURED]
    print(f"{arguments.grid}: {len(one)} configurations, {int((one['status'] == 'error').sum())} error rows, "
          f"{int((one['status'].str.startswith('diverged')).sum())} diverged; medians of {arguments.rounds} rounds\n")
    print("| runs on | wall s (median) | every round, s | speed-up | this process's CPU s (median) | tables |")
    print("|---|---:|---|---:|---:|---|")
    base = statistics.median(seconds[names[0]])
    for name in names:
        try:
            for table in tables[name]:
                pd.testing.assert_frame_equal(table[deterministic], one[deterministic], check_exact=True)
            same = "identical"
        except AssertionError as difference:
            same = f"DIFFER: {str(difference).splitlines()[0]}"
        median = statistics.median(seconds[name])
        rounds = ", ".join(f"{t:.1f}" for t in seconds[name])
        print(f"| {name} | {median:.1f} | {rounds} | {base / median:.2f}× | {statistics.median(cpu[name]):.2f} | {same} |")
    print(f"\nThe LocalCluster's workers computed tasks for {statistics.median(computing):.1f} s (median), against "
          f"{base:.1f} s of wall time for the same runs on one process.")


if __name__ == "__main__":
    main()
