"""What the sweep's tests share: tiny grids on tools/scenes/chain.json, the command, and the
processes a process leaves behind (Linux /proc)."""
import json
import os
import pathlib
import shutil
import subprocess
import sys
import time

SCENES = pathlib.Path(os.environ.get("LIMBER_SOURCE_DIR", pathlib.Path(__file__).parents[2])) / "tools" / "scenes"
HARNESS = pathlib.Path(__file__).with_name("sweep_harness.py")
LIMIT = 180  # s: a command that takes longer hangs (each one here takes seconds)


def scene(folder, name):
    """tools/scenes/chain.json copied as `folder`/`name` (a name sweep_harness.py may act on)."""
    shutil.copy(SCENES / "chain.json", folder / name)
    return name


def grid_file(folder, grid, name="grid.json"):
    path = folder / name
    path.write_text(json.dumps(grid))
    return path


def command(grid, out, *flags, harness=False):
    """The sweep's command line: `python3 -m limber.sweep`, or sweep_harness.py's faults planted."""
    head = [sys.executable, str(HARNESS)] if harness else [sys.executable, "-m", "limber.sweep"]
    return [*head, str(grid), "--out", str(out), *flags]


def run(arguments, **options):
    return subprocess.run(arguments, capture_output=True, text=True, timeout=LIMIT, **options)


def rows(out):
    """The data lines of an output file, each a whole line (ending in a newline) or the test fails."""
    text = pathlib.Path(out).read_text()
    assert text == "" or text.endswith("\n"), f"{out} ends in a cut line: {text[-200:]!r}"
    return text.splitlines()[1:]


def wait_until(predicate, what, timeout=LIMIT):
    """Polls `predicate` (a file filling, processes leaving: nothing to wait on but their state)."""
    end = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < end, f"{what}: not within {timeout} s"
        time.sleep(0.05)


def _stat(pid):
    """(parent pid, state, start time) of a process, or None when it is gone."""
    try:
        fields = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return int(fields[1]), fields[0], fields[19]


def descendants(pid):
    """{pid: start time} of every live process below `pid`."""
    table = {int(entry.name): _stat(entry.name) for entry in pathlib.Path("/proc").glob("[0-9]*")}
    found, frontier = {}, [pid]
    while frontier:
        parent = frontier.pop()
        for child, stat in table.items():
            if stat and stat[0] == parent and stat[1] != "Z" and child not in found:
                found[child] = stat[2]
                frontier.append(child)
    return found


def alive(processes):
    """Those of `processes` ({pid: start time}) still running: not zombies, not another process with the pid."""
    out = {}
    for pid, start in processes.items():
        stat = _stat(pid)
        if stat and stat[1] != "Z" and stat[2] == start:
            out[pid] = start
    return out


def end(processes):
    """SIGKILLs what is left of `processes`, so that a failing test leaves nothing running."""
    for pid in alive(processes):
        try:
            os.kill(pid, 9)
        except OSError:
            pass
