"""Sweeps: a grid of scenes × methods × settings, one run per configuration, one table of metrics.

    import limber.sweep
    table = limber.sweep.sweep(grid)                    # local processes, one per core
    table = limber.sweep.sweep(grid, client=client)     # a dask.distributed Client's cluster

    python3 -m limber.sweep GRID.json [--scheduler tcp://HOST:PORT | --workers N] --out results.csv

A grid (a dict, or a JSON file of one):

    {"duration": 2, "sample_interval": 0.05,
     "scenes": [{"scene": "chain.json", "name": "chain-5"}, {"scene": "tree.json", "links": 63}],
     "methods": [{"method": "weighted", "iterations": [5, 20]}, {"method": "featherstone"}],
     "settings": {"dt": [0.004166666666666667, 0.001]},
     "reference": {"method": "featherstone", "integrator": "rk4", "dt": 5e-05}}

A scene entry is load_scene's arguments (scene: the file, relative to the grid file; body, links,
copies, floating_base) and an optional name. A method entry and "settings" are World's options,
`limber run`'s flags with '_' for '-'; a list is a dimension (so a flag of three numbers, ball_direction,
is a string "1,0,0"). The configurations are every scene
× every method entry's expansion × every setting's expansion, in that order. Each runs for
`duration` s of simulated time (rounded to whole steps of its dt) and gives one row:

    index, scene, method, <one column per option the grid names>, steps (taken),
    steps_per_second (steps over the wall time inside World::step: measured, so it varies between
    runs; every other column is the same bits whoever runs the sweep), trajectory_error (m: the
    largest over samples every sample_interval s of the RMS distance between the bodies' origins
    and the reference run's; inf when the run stopped early; NaN without a reference),
    max_joint_gap, rms_joint_gap, max_link_stretch (relative to link length), energy_drift and
    energy_gain (max |E − E0| and max (E − E0) over the run, relative to m·|g|·ΣL), status ('ok',
    why a step diverged, or 'error'), error (the message of an 'error' row).

A configuration that raises is an 'error' row, never a lost sweep. With an output file the rows
are appended as they finish, and a sweep over an existing file runs only the configurations it
lacks (resume). The reference is one run per scene with the grid's "reference" options.

Local processes are spawned, so a script that sweeps without a client needs the
`if __name__ == "__main__":` guard, as multiprocessing and Dask's LocalCluster do. A cluster's
workers import limber themselves: install it on their machines (`cmake --install`), or start
them with it on PYTHONPATH; the scene files' paths must be valid where the workers run.
"""
import argparse
import concurrent.futures
import dataclasses
import functools
import itertools
import json
import math
import multiprocessing
import os
import pathlib
import sys
import time

import numpy as np

import limber  # pandas is imported where tables are made: the workers that run configurations never need it

GRID_KEYS = {"duration", "sample_interval", "scenes", "methods", "settings", "reference"}
SCENE_KEYS = {"scene", "name", "body", "links", "copies", "floating_base"}
METRICS = ["steps", "steps_per_second", "trajectory_error", "max_joint_gap", "rms_joint_gap", "max_link_stretch",
           "energy_drift", "energy_gain", "status", "error"]
MEASURED = ["steps_per_second"]  # wall-time measurements: the only columns that differ between runs


class GridError(ValueError):
    """A bad grid: the message names the file (or 'grid'), the field and the problem."""


@dataclasses.dataclass(frozen=True)
class Grid:
    """A checked grid: scene entries (paths resolved), the methods' and settings' expansions."""
    duration: float
    sample_interval: float
    scenes: list
    methods: list
    settings: list
    reference: dict = None


def _expand(options, where):
    """The product of an options dict's list-valued fields, as dicts, in the fields' order."""
    if not isinstance(options, dict):
        raise GridError(f"{where}: expected an object of options, got {options!r}")
    keys = list(options)
    values = [v if isinstance(v, list) else [v] for v in options.values()]
    for key, value in zip(keys, values):
        if not value:
            raise GridError(f"{where}.{key}: an empty list gives no configuration")
    return [dict(zip(keys, combination)) for combination in itertools.product(*values)]


def load_grid(path):
    """A grid from a JSON file, its scenes' paths made relative to the file's folder."""
    try:
        grid = json.loads(pathlib.Path(path).read_text())
    except OSError as error:
        raise GridError(f"{path}: cannot read: {error.strerror}") from None
    except json.JSONDecodeError as error:
        raise GridError(f"{path}:{error.lineno}: not JSON: {error.msg}") from None
    return check_grid(grid, str(path), base=pathlib.Path(path).parent)


def check_grid(grid, source="grid", base=None):
    """The Grid a dict describes, defaults set and scene paths resolved against `base`; GridError
    names `source` and the field."""
    if not isinstance(grid, dict):
        raise GridError(f"{source}: expected a JSON object")
    for key in grid:
        if key not in GRID_KEYS:
            raise GridError(f"{source}: {key}: unknown field (the fields are {', '.join(sorted(GRID_KEYS))})")
    for key in ("scenes", "methods"):
        if not isinstance(grid.get(key), list) or not grid[key]:
            raise GridError(f"{source}: {key}: required, a non-empty list")
    duration = grid.get("duration", 1.0)
    interval = grid.get("sample_interval", 0.05)
    for key, value in (("duration", duration), ("sample_interval", interval)):
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not value > 0 or not math.isfinite(value):
            raise GridError(f"{source}: {key}: must be a number > 0, got {value!r}")
    scenes = []
    for k, scene in enumerate(grid["scenes"]):
        where = f"{source}: scenes[{k}]"
        if not isinstance(scene, dict) or "scene" not in scene:
            raise GridError(f"{where}: expected an object with a 'scene' file")
        for key in scene:
            if key not in SCENE_KEYS:
                raise GridError(f"{where}.{key}: unknown field (the fields are {', '.join(sorted(SCENE_KEYS))})")
        scene = dict(scene)
        scene.setdefault("name", pathlib.Path(scene["scene"]).stem)
        if any(other["name"] == scene["name"] for other in scenes):
            raise GridError(f"{where}.name: '{scene['name']}' names an earlier scene too; give each scene its own name")
        if base is not None:
            scene["scene"] = str(pathlib.Path(base) / scene["scene"])
        scenes.append(scene)
    methods = []
    for k, method in enumerate(grid["methods"]):
        if not isinstance(method, dict) or not isinstance(method.get("method"), (str, list)):
            raise GridError(f"{source}: methods[{k}]: expected an object with a 'method'")
        methods += _expand(method, f"{source}: methods[{k}]")
    settings = _expand(grid.get("settings", {}), f"{source}: settings")
    reference = grid.get("reference")
    if reference is not None and (not isinstance(reference, dict) or "method" not in reference):
        raise GridError(f"{source}: reference: expected an object with a 'method'")
    return Grid(float(duration), float(interval), scenes, methods, settings, reference)


def configurations(grid):
    """Every configuration of a checked grid, in order: dicts of scene, method and options."""
    out = []
    for scene, method, setting in itertools.product(grid.scenes, grid.methods, grid.settings):
        options = {**method, **setting}
        out.append({"index": len(out), "scene": scene["name"], **options})
    return out


@functools.lru_cache(maxsize=8)
def _loaded(path, loading):
    """A scene file loaded once per process: every configuration of a scene starts from it (a World
    steps its own copy)."""
    return limber.load_scene(path, **dict(loading))


def _world(scene, options):
    """The World `options` ask for on `scene`, and its time step, s."""
    loaded = _loaded(scene["scene"], tuple(sorted((k, v) for k, v in scene.items() if k not in ("scene", "name"))))
    options = dict(options)
    world = limber.World(loaded, options.pop("method"), **options)
    return world, options.get("dt", loaded.time_step)


def _run(scene, options, duration, interval):
    """One run of `duration` s (whole steps): World.run's dict, sampled every `interval` s."""
    world, dt = _world(scene, options)
    every = interval / dt
    if abs(every - round(every)) > 1e-6 * every or round(every) < 1:
        raise limber.OptionError(f"sample_interval {interval:g} s is not a whole number of steps of dt {dt:g} s")
    return world.run(max(1, round(duration / dt)), sample_every=round(every))


def reference_samples(scene, reference, duration, sample_interval):
    """The run of `reference` (World options, or None) on `scene`: its samples (K × N × 3 m), or None."""
    if reference is None:
        return None
    run = _run(scene, reference, duration, sample_interval)
    if run["status"] != "ok":
        raise RuntimeError(f"the reference run stopped after {run['steps']} steps: {run['status']}")
    return run["samples"]


def trajectory_error(samples, reference):
    """The largest over common samples of the RMS distance between the bodies' origins, m."""
    if reference is None:
        return math.nan
    if samples.shape[0] < reference.shape[0] or not np.isfinite(samples).all():
        return math.inf
    squared = ((samples[: reference.shape[0]] - reference) ** 2).sum(axis=2).mean(axis=1)
    return float(np.sqrt(squared.max()))


def _error_row(configuration, message):
    return {**configuration, **{metric: math.nan for metric in METRICS}, "steps": 0, "status": "error", "error": message}


def run_configuration(configuration, scene, duration, sample_interval):
    """One run: (`configuration`'s row but its trajectory_error, its samples), or (an 'error' row
    with the message, None). The samples meet the reference's in the sweep's process, so no run
    waits for its scene's reference."""
    options = {k: v for k, v in configuration.items() if k not in ("index", "scene")}
    try:
        run = _run(scene, options, duration, sample_interval)
    except Exception as error:  # a failed configuration is a row, never a lost sweep
        return _error_row(configuration, f"{type(error).__name__}: {error}"), None
    scale, seconds = run["energy_scale"], run["step_seconds"]
    row = {**configuration, "steps": run["steps"], "steps_per_second": run["steps"] / seconds if seconds > 0 else math.nan,
           "trajectory_error": math.nan, "max_joint_gap": run["max_joint_gap"], "rms_joint_gap": run["rms_joint_gap"],
           "max_link_stretch": run["max_link_stretch"], "energy_drift": run["energy_drift"] / scale,
           "energy_gain": run["energy_gain"] / scale, "status": run["status"], "error": ""}
    return row, run["samples"]


def _reference_or_error(*arguments):
    try:
        return reference_samples(*arguments)
    except Exception as error:
        return error


class _Rows:
    """Completes each row when both its run and its scene's reference have arrived, in whatever
    order they come, and hands it to `finish`."""

    def __init__(self, finish):
        self.finish, self.references, self.waiting = finish, {}, {}

    def deliver(self, task, result):
        kind, item = task
        if isinstance(result, Exception) and kind == "run":  # the process running it died
            result = (_error_row(item, f"worker: {type(result).__name__}: {result}"), None)
        if kind == "reference":
            self.references[item] = result
            for row, samples in self.waiting.pop(item, []):
                self._complete(row, samples)
        elif item["scene"] in self.references:
            self._complete(*result)
        else:
            self.waiting.setdefault(item["scene"], []).append(result)

    def _complete(self, row, samples):
        reference = self.references[row["scene"]]
        if samples is not None and isinstance(reference, Exception):
            row = {**row, "error": f"reference: {reference}"}
        elif samples is not None:
            row = {**row, "trajectory_error": trajectory_error(samples, reference)}
        self.finish(row)


def _read_finished(out):
    """The rows an output file already holds (a resumed sweep keeps them), or None."""
    if out is None or not pathlib.Path(out).exists() or pathlib.Path(out).stat().st_size == 0:
        return None
    import pandas as pd

    return pd.read_csv(out, float_precision="round_trip", keep_default_na=False, na_values=["nan", "NaN"])


def sweep(grid, client=None, *, workers=None, out=None, progress=None):
    """Runs every configuration of `grid` (a Grid, a dict, or a JSON file's path) and returns the table, one
    row per configuration in grid order (a pandas DataFrame; its columns are in the module's
    docstring).

    client: a dask.distributed Client: one task per configuration (and per scene's reference) on
    its cluster. Without one, `workers` local processes (default: one per core; 1: this process).
    out: a CSV file the rows are appended to as they finish; the configurations it holds already
    are not run again. progress: called with (rows done, rows in all) as rows finish.
    """
    import pandas as pd

    if isinstance(grid, (str, os.PathLike)):
        grid = load_grid(grid)
    elif not isinstance(grid, Grid):
        grid = check_grid(grid)
    every = configurations(grid)
    option_columns = list(dict.fromkeys(k for c in every for k in c if k not in ("index", "scene")))
    columns = ["index", "scene", *option_columns, *METRICS]
    finished = _read_finished(out)
    if finished is not None and list(finished.columns) != columns:
        raise GridError(f"{out}: holds another grid's table (its columns: {', '.join(finished.columns)}); it is not resumed or written over")
    done = set(finished["index"]) if finished is not None else set()
    remaining = [c for c in every if c["index"] not in done]
    rows = []

    def finish(row):
        rows.append(row)
        if out is not None:
            new = not pathlib.Path(out).exists() or pathlib.Path(out).stat().st_size == 0
            pd.DataFrame([row], columns=columns).to_csv(out, mode="a", header=new, index=False, na_rep="nan")
        if progress:
            progress(len(done) + len(rows), len(every))

    scenes = {scene["name"]: scene for scene in grid.scenes if any(c["scene"] == scene["name"] for c in remaining)}
    # The references first: they are the longest runs, and each scene's rows wait for its own.
    length = (grid.duration, grid.sample_interval)
    tasks = [(("reference", name), _reference_or_error, (scene, grid.reference, *length)) for name, scene in scenes.items()]
    tasks += [(("run", c), run_configuration, (c, scenes[c["scene"]], *length)) for c in remaining]
    collector = _Rows(finish)
    if client is not None:
        results = _on_dask(client, tasks)
    elif (workers or os.cpu_count() or 1) == 1:
        results = ((task, function(*arguments)) for task, function, arguments in tasks)
    else:
        results = _on_processes(workers or os.cpu_count(), tasks)
    for task, result in results:
        collector.deliver(task, result)
    table = pd.DataFrame(rows, columns=columns)
    if finished is not None:
        table = pd.concat([finished.reindex(columns=columns), table], ignore_index=True)
    return table.sort_values("index", kind="stable").reset_index(drop=True)


def _on_processes(workers, tasks):
    """(task, result) pairs as local processes finish them; a process that died gives its exception."""
    # spawn, not fork: the parent's kernel may hold worker threads a forked child would lack.
    with concurrent.futures.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = {pool.submit(function, *arguments): task for task, function, arguments in tasks}
        for future in concurrent.futures.as_completed(futures):
            yield futures[future], future.exception() or future.result()


def _on_dask(client, tasks):
    """(task, result) pairs as the cluster finishes them; a worker that died gives its exception."""
    import distributed

    futures = {client.submit(function, *arguments, pure=False): task for task, function, arguments in tasks}
    # with_results: results come in batches, not one round trip each; an error comes as (type, value, traceback).
    for future, result in distributed.as_completed(futures, with_results=True, raise_errors=False):
        yield futures[future], result[1] if future.status == "error" else result


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m limber.sweep", description="Runs a grid of limber configurations into a CSV table.")
    parser.add_argument("grid", help="the grid, a JSON file (limber/sweep.py's docstring)")
    parser.add_argument("--out", required=True, help="the CSV table; rows are appended as they finish, and a sweep resumes from it")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--scheduler", help="a dask.distributed scheduler's address, tcp://HOST:PORT")
    where.add_argument("--workers", type=int, help="local processes (default: one per core)")
    arguments = parser.parse_args(argv)
    if pathlib.Path(arguments.out).resolve() == pathlib.Path(arguments.grid).resolve():
        parser.exit(2, f"limber.sweep: --out {arguments.out}: is the grid itself; it would be written over\n")
    if not pathlib.Path(arguments.out).resolve().parent.is_dir():
        parser.exit(2, f"limber.sweep: --out {arguments.out}: its folder does not exist\n")
    try:
        grid = load_grid(arguments.grid)
    except GridError as error:
        parser.exit(2, f"limber.sweep: {error}\n")
    client = None
    if arguments.scheduler:
        import distributed

        client = distributed.Client(arguments.scheduler)
    start = time.perf_counter()
    try:
        table = sweep(arguments.grid, client, workers=arguments.workers, out=arguments.out,
                      progress=lambda k, n: print(f"\r{k}/{n} configurations", end="", file=sys.stderr))
    finally:
        if client is not None:
            client.close()
    errors = int((table["status"] == "error").sum())
    print(f"\n{len(table)} configurations in {time.perf_counter() - start:.1f} s ({errors} errors): {arguments.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
