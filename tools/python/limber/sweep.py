"""Sweeps: a grid of scenes × methods × settings, one run per configuration, one table of metrics.

    import limber.sweep
    table = limber.sweep.sweep(grid)                    # local processes, one per core
    table = limber.sweep.sweep(grid, client=client)     # a dask.distributed Client's cluster

    python3 -m limber.sweep GRID.json [--scheduler tcp://HOST:PORT | --workers N] --out results.csv

A grid (a dict, or a JSON file of one):

    {"duration": 2, "sample_interval": 0.05, "timeout": 600,
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

    index, scene, method, <one column per option the grid names>, steps (taken; 0 in a row without
    a run's result), steps_per_second (steps over the wall time inside World::step: measured, so it
    varies between runs; every other column is the same bits whoever runs the sweep),
    trajectory_error (m: the largest over samples every sample_interval s of the RMS distance
    between the bodies' origins and the reference run's; inf when the run stopped early; NaN
    without a reference), max_joint_gap, rms_joint_gap, max_link_stretch (relative to link
    length), energy_drift and energy_gain (max |E − E0| and max (E − E0) over the run, relative
    to m·|g|·ΣL), deepest_penetration (m) and max_limit_violation (rad; m for a slide) over the
    run, status (World.run's verdict: 'ok', 'inaccurate', 'diverged_...'; or the sweep's own:
    'error', 'timeout', 'worker_died'), verdict (the verdict in `limber run`'s words), error (why,
    for the sweep's own; "reference: ..." when the scene's reference run failed).

A configuration is a row whatever happens to it, never a lost sweep:
- 'error': it raised (a bad option, a scene that does not load). Deterministic: kept on resume.
- 'timeout': it ran past the grid's "timeout" (s, optional; the reference runs too). World.run
  stops by itself at that wall time (its wall_limit); a local worker process still busy
  timeout + 2 s + timeout/2 after it was handed the configuration (stuck outside World.run) is
  killed. On a Dask cluster only World.run's wall_limit stops a run.
- 'worker_died': the process running it died (a signal, the OOM killer, a crash in the scene
  loader) 1 + RETRIES times; each death is a note and the configuration runs again in a new process.
  On Dask the scheduler decides (distributed.scheduler.allowed-failures, 3 by default).
Configurations run in worker processes, never in the sweep's own (workers=1 is one such process),
so a crash loses at most the configuration it happens in.

With an output file the rows are appended as they finish, each one write of a whole line, and a
sweep over an existing file runs only the configurations it lacks (resume), and those whose row is
'timeout' or 'worker_died'; lines a killed sweep or a full disk cut short are set aside in
OUT.damaged and run again. OUT.sweep beside it names the grid (a hash of it, its "timeout" aside)
and is locked while a sweep writes: another grid's table, or a second sweep on one file, is
refused by name (limber/_sweep_file.py). The reference is one run per scene with the grid's
"reference" options. Ctrl-C or SIGTERM on the command stops the workers at once; the rows written
are kept, and running the command again resumes.

Local processes are spawned, so a script that sweeps without a client needs the
`if __name__ == "__main__":` guard, as multiprocessing and Dask's LocalCluster do. They die with the
sweep's process, even a SIGKILLed one (limber/_sweep_workers.py). A cluster's workers import limber
themselves: install it on their machines (`cmake --install`), or start them with it on PYTHONPATH;
the scene files' paths must be valid where the workers run.
"""
import argparse
import contextlib
import dataclasses
import functools
import hashlib
import io
import itertools
import json
import math
import os
import pathlib
import signal
import sys
import time
import warnings

import numpy as np

import limber  # pandas is imported where tables are made: the workers that run configurations never need it

from . import _sweep_file, _sweep_workers
from ._sweep_file import OutputError
from ._sweep_workers import Failure, WorkerStartError

GRID_KEYS = {"duration", "sample_interval", "timeout", "scenes", "methods", "settings", "reference"}
SCENE_KEYS = {"scene", "name", "body", "links", "copies", "floating_base"}
METRICS = ["steps", "steps_per_second", "trajectory_error", "max_joint_gap", "rms_joint_gap", "max_link_stretch",
           "energy_drift", "energy_gain", "deepest_penetration", "max_limit_violation", "status", "verdict", "error"]
NUMERIC = METRICS[:-3]
# World.run's verdicts of a run that went all the way (the others name the step that stopped it).
COMPLETE = {"ok", "inaccurate"}
MEASURED = ["steps_per_second"]  # wall-time measurements: the only columns that differ between runs
RETRIES = 2  # times a configuration whose worker process died runs again before it is a 'worker_died' row
RERUN = ("timeout", "worker_died")  # statuses a resumed sweep runs again: the next try may end otherwise
GRID_BYTES = 16 << 20  # a grid file larger than this is refused


class GridError(ValueError):
    """A bad grid: the message names the file (or 'grid'), the field and the problem."""


class SweepWarning(UserWarning):
    """Something a sweep survived: a worker process that died, a damaged line of its output file."""


@dataclasses.dataclass(frozen=True)
class Grid:
    """A checked grid: scene entries (paths resolved), the methods' and settings' expansions, the
    timeout (s, or None); `source`: the grid as it decides the rows (scene files as the grid names
    them, no timeout), whose hash names its tables."""
    duration: float
    sample_interval: float
    scenes: list
    methods: list
    settings: list
    reference: dict = None
    timeout: float = None
    source: dict = dataclasses.field(default=None, compare=False, repr=False)


def grid_identity(grid):
    """(the SHA-256 of the grid's canonical JSON, that JSON as a dict): what its output file is checked against."""
    source = grid.source
    if source is None:
        source = {k: getattr(grid, k) for k in ("duration", "sample_interval", "scenes", "methods", "settings", "reference")}
    canonical = json.dumps(source, separators=(",", ":"), default=str)  # key order kept: it orders the columns and rows
    return hashlib.sha256(canonical.encode()).hexdigest(), json.loads(canonical)


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
    try:  # a FIFO or a device is refused, never read (it could block or never end)
        grid = json.loads(_sweep_file.read_regular(path, GRID_BYTES, GridError).decode())
    except UnicodeDecodeError as error:
        raise GridError(f"{path}: not UTF-8 (byte {error.start})") from None
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
    timeout = grid.get("timeout")
    for key, value in (("duration", duration), ("sample_interval", interval), ("timeout", timeout)):
        if key == "timeout" and value is None:
            continue
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not value > 0 or not math.isfinite(value):
            raise GridError(f"{source}: {key}: must be a number > 0, got {value!r}")
    scenes, written = [], []
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
        written.append(dict(scene))
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
    as_written = {"duration": float(duration), "sample_interval": float(interval), "scenes": written, "methods": grid["methods"],
                  "settings": grid.get("settings", {}), "reference": reference}
    return Grid(float(duration), float(interval), scenes, methods, settings, reference,
                None if timeout is None else float(timeout), as_written)


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


def _run(scene, options, duration, interval, limit=None):
    """One run of `duration` s (whole steps): World.run's dict, sampled every `interval` s, stopped
    after `limit` s of wall time (None: no limit)."""
    world, dt = _world(scene, options)
    every = interval / dt
    if abs(every - round(every)) > 1e-6 * every or round(every) < 1:
        raise limber.OptionError(f"sample_interval {interval:g} s is not a whole number of steps of dt {dt:g} s")
    return world.run(max(1, round(duration / dt)), sample_every=round(every), wall_limit=limit)


def _stopped(run, limit):
    """Why a run stopped at its wall limit, or None."""
    if run.get("stopped") == "wall_limit":
        return f"stopped after {run['steps']} steps at the grid's timeout of {limit:g} s"
    return None


def reference_samples(scene, reference, duration, sample_interval, limit=None):
    """The run of `reference` (World options, or None) on `scene`: its samples (K × N × 3 m), or None."""
    if reference is None:
        return None
    run = _run(scene, reference, duration, sample_interval, limit)
    if _stopped(run, limit):
        raise Failure("timeout", _stopped(run, limit))
    if run["status"] not in COMPLETE:
        raise RuntimeError(f"the reference run stopped after {run['steps']} steps: {run['verdict']}")
    return run["samples"]


def trajectory_error(samples, reference):
    """The largest over common samples of the RMS distance between the bodies' origins, m."""
    if reference is None:
        return math.nan
    if samples.shape[0] < reference.shape[0] or not np.isfinite(samples).all():
        return math.inf
    squared = ((samples[: reference.shape[0]] - reference) ** 2).sum(axis=2).mean(axis=1)
    return float(np.sqrt(squared.max()))


def _error_row(configuration, message, status="error"):
    """A row without a run's result: its metrics NaN, steps 0; the message on one line, as the file holds it."""
    return {**configuration, **{metric: math.nan for metric in METRICS}, "steps": 0, "status": status, "verdict": "",
            "error": _sweep_file.text(message)}


def run_configuration(configuration, scene, duration, sample_interval, limit=None):
    """One run: (`configuration`'s row but its trajectory_error, its samples), or (an 'error' row
    with the message, None). The samples meet the reference's in the sweep's process, so no run
    waits for its scene's reference. limit: the grid's timeout, s, or None."""
    options = {k: v for k, v in configuration.items() if k not in ("index", "scene")}
    try:
        run = _run(scene, options, duration, sample_interval, limit)
    except Exception as error:  # a failed configuration is a row, never a lost sweep
        return _error_row(configuration, f"{type(error).__name__}: {error}"), None
    scale, seconds = run["energy_scale"], run["step_seconds"]
    stopped = _stopped(run, limit)
    row = {**configuration, "steps": run["steps"], "steps_per_second": run["steps"] / seconds if seconds > 0 else math.nan,
           "trajectory_error": math.nan, "max_joint_gap": run["max_joint_gap"], "rms_joint_gap": run["rms_joint_gap"],
           "max_link_stretch": run["max_link_stretch"], "energy_drift": run["energy_drift"] / scale,
           "energy_gain": run["energy_gain"] / scale, "deepest_penetration": run["deepest_penetration"],
           "max_limit_violation": run["max_limit_violation"], "status": "timeout" if stopped else run["status"],
           "verdict": _sweep_file.text(run["verdict"]), "error": stopped or ""}
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
        if isinstance(result, Failure) and kind == "run":  # its worker died, or ran out of time
            result = (_error_row(item, str(result), result.status), None)
        elif isinstance(result, Exception) and kind == "run":  # the cluster could not run it
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
            kind = reference.status if isinstance(reference, Failure) else type(reference).__name__
            row = {**row, "error": _sweep_file.text(f"reference: {kind}: {reference}")}
        elif samples is not None:
            row = {**row, "trajectory_error": trajectory_error(samples, reference)}
        self.finish(row)


def _note(message):
    warnings.warn(message, SweepWarning, stacklevel=2)


def _read_csv(text):
    import pandas as pd

    return pd.read_csv(io.StringIO(text), float_precision="round_trip", keep_default_na=False, na_values=["nan", "NaN"])


def sweep(grid, client=None, *, workers=None, out=None, progress=None):
    """Runs every configuration of `grid` (a Grid, a dict, or a JSON file's path) and returns the table, one
    row per configuration in grid order (a pandas DataFrame; its columns are in the module's
    docstring).

    client: a dask.distributed Client: one task per configuration (and per scene's reference) on
    its cluster. Without one, `workers` local processes (default: one per core).
    out: a CSV file the rows are appended to as they finish; the configurations it holds already
    are not run again. progress: called with (rows done, rows in all) as rows finish. Notes (a
    worker that died, a damaged line set aside) are SweepWarnings. Raises GridError, OutputError
    (the output file: not this grid's, locked by another sweep, not a regular file, a full disk),
    WorkerStartError; KeyboardInterrupt stops the workers, keeping the rows written.
    """
    import pandas as pd

    if isinstance(grid, (str, os.PathLike)):
        grid = load_grid(grid)
    elif not isinstance(grid, Grid):
        grid = check_grid(grid)
    every = configurations(grid)
    option_columns = list(dict.fromkeys(k for c in every for k in c if k not in ("index", "scene")))
    columns = ["index", "scene", *option_columns, *METRICS]
    table = None
    if out is not None:
        table = _sweep_file.open_table(out, columns, every, NUMERIC, *grid_identity(grid), rerun=RERUN, note=_note)
    try:
        finished = _read_csv(table.finished) if table is not None and table.rows else None
        done = set(finished["index"]) if finished is not None else set()
        rows = []

        def finish(row):
            rows.append(row)
            if table is not None:
                table.append(row)
            if progress:
                progress(len(done) + len(rows), len(every))

        remaining = [c for c in every if c["index"] not in done]
        collector = _Rows(finish)
        with _runner(client, workers, grid.timeout) as run:
            for task, result in run(_tasks(grid, remaining)):
                collector.deliver(task, result)
    finally:
        if table is not None:
            table.close()
    parts = [finished.reindex(columns=columns)] if finished is not None else []
    if rows or not parts:  # (an empty frame would make every column's type object)
        parts.append(pd.DataFrame(rows, columns=columns))
    return pd.concat(parts, ignore_index=True).sort_values("index", kind="stable").reset_index(drop=True)


def _tasks(grid, remaining):
    """(key, label, function, arguments) of the references of the scenes `remaining` uses, then of `remaining`."""
    scenes = {scene["name"]: scene for scene in grid.scenes if any(c["scene"] == scene["name"] for c in remaining)}
    # The references first: they are the longest runs, and each scene's rows wait for its own.
    length = (grid.duration, grid.sample_interval, grid.timeout)
    tasks = [(("reference", name), f"the reference run of {name}", _reference_or_error, (scene, grid.reference, *length))
             for name, scene in scenes.items()]
    tasks += [(("run", c), f"configuration {c['index']} ({c['scene']}, {c['method']})", run_configuration,
               (c, scenes[c["scene"]], *length)) for c in remaining]
    return tasks


def _runner(client, workers, limit):
    """A context manager giving run(tasks) -> (key, result) pairs as tasks finish, on `client`'s
    cluster or on local worker processes; leaving it stops what still runs."""
    if client is not None:
        return _on_dask(client)
    if workers is not None and workers < 1:
        raise ValueError(f"workers: must be ≥ 1, got {workers}")
    deadline = None if limit is None else limit + 2 + limit / 2  # World.run stops first
    return _sweep_workers.Workers(workers or os.cpu_count() or 1, deadline=deadline, retries=RETRIES, note=_note)


@contextlib.contextmanager
def _on_dask(client):
    """(task, result) pairs as the cluster finishes them; a worker that died gives its exception."""
    import distributed

    futures = {}

    def run(tasks):
        futures.update({client.submit(function, *arguments, pure=False): key for key, _, function, arguments in tasks})
        # with_results: results come in batches, not one round trip each; an error comes as (type, value, traceback).
        for future, result in distributed.as_completed(futures, with_results=True, raise_errors=False):
            if future.status != "error":
                yield futures[future], result
            elif isinstance(result[1], distributed.KilledWorker):  # the scheduler's allowed-failures used up
                yield futures[future], Failure("worker_died", f"its Dask workers died running it ({result[1]})")
            else:
                yield futures[future], result[1]

    try:
        yield run
    finally:
        client.cancel(list(futures))


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m limber.sweep", description="Runs a grid of limber configurations into a CSV table.")
    parser.add_argument("grid", help="the grid, a JSON file (limber/sweep.py's docstring)")
    parser.add_argument("--out", required=True, help="the CSV table; rows are appended as they finish, and a sweep resumes from it")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--scheduler", help="a dask.distributed scheduler's address, tcp://HOST:PORT")
    where.add_argument("--workers", type=int, help="local processes (default: one per core)")
    arguments = parser.parse_args(argv)
    if arguments.workers is not None and arguments.workers < 1:
        parser.exit(2, f"limber.sweep: --workers: must be ≥ 1, got {arguments.workers}\n")
    if pathlib.Path(arguments.out).resolve() == pathlib.Path(arguments.grid).resolve():
        parser.exit(2, f"limber.sweep: --out {arguments.out}: is the grid itself; it would be written over\n")
    try:
        grid = load_grid(arguments.grid)
    except GridError as error:
        parser.exit(2, f"limber.sweep: {error}\n")
    status = _Status()
    with warnings.catch_warnings(), _signals_interrupt(status):
        warnings.simplefilter("always", SweepWarning)
        warnings.showwarning = lambda message, *_: status.say(f"limber.sweep: {message}")
        client = None
        try:
            if arguments.scheduler:
                import distributed

                client = distributed.Client(arguments.scheduler)
            table = sweep(grid, client, workers=arguments.workers, out=arguments.out, progress=status.progress)
        except (GridError, OutputError, WorkerStartError) as error:
            status.say(f"limber.sweep: {error}")
            return 2
        except KeyboardInterrupt:
            written = f"{status.done} of {status.total} configurations are" if status.total else "no row is"
            status.say(f"limber.sweep: stopped by {status.signal.name}: {written} in {arguments.out}; the same command resumes")
            return 128 + status.signal
        finally:
            if client is not None:
                client.close()
    status.say(f"{len(table)} configurations in {status.seconds():.1f} s ({summary(table)}): {arguments.out}")
    return 0


def summary(table):
    """The count of each status in a table, and of its rows without their reference, with the first one's error."""
    counts = table["status"].value_counts(sort=False)
    text = ", ".join(f"{n} {status}" for status, n in counts.items())
    without = table[table["error"].astype(str).str.startswith("reference: ")]
    if len(without):
        text += f"; {len(without)} reference errors, the first: {without['error'].iloc[0]}"
    else:
        text += "; 0 reference errors"
    return text


class _Status:
    """The command's lines on stderr: a progress line rewritten in place, and whole lines below it."""

    def __init__(self):
        self.start, self.done, self.total, self.open = time.perf_counter(), 0, 0, False
        self.signal = signal.SIGINT

    def progress(self, done, total):
        self.done, self.total, self.open = done, total, True
        print(f"\r{done}/{total} configurations", end="", file=sys.stderr, flush=True)

    def say(self, line):
        print(("\n" if self.open else "") + line, file=sys.stderr, flush=True)
        self.open = False

    def seconds(self):
        return time.perf_counter() - self.start


@contextlib.contextmanager
def _signals_interrupt(status):
    """SIGTERM interrupts as Ctrl-C does (KeyboardInterrupt), so both stop the workers and keep the rows;
    `status.signal` says which came."""
    def interrupt(number, frame):
        status.signal = signal.Signals(number)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    sys.exit(main())
