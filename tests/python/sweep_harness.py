"""`python3 -m limber.sweep`'s main with faults planted where configurations run, for the sweep's
tests: run it as a script (python3 sweep_harness.py GRID --out OUT ...). The sweep's spawned
worker processes import it as their main module, so the faults are planted in them too; and in the
sweep's own process, which must never load a scene.

A scene file whose name holds
- 'segfault': loading it raises SIGSEGV, as a crash in the scene loader does;
- 'killed-once': the first process that loads it SIGKILLs itself (a marker file beside the scene,
  made with O_EXCL, says it happened); any later one loads it;
- 'killed-always': every process that loads it SIGKILLs itself.
"""
import os
import pathlib
import resource
import signal
import sys

import limber
import limber.sweep

resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # the crashes leave no core file
_load_scene = limber.load_scene


def load_scene(path, **options):
    name = pathlib.Path(path).name
    if "segfault" in name:
        os.kill(os.getpid(), signal.SIGSEGV)
    if "killed-always" in name:
        os.kill(os.getpid(), signal.SIGKILL)
    if "killed-once" in name:
        try:
            os.close(os.open(f"{path}.killed", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:
            pass
        else:
            os.kill(os.getpid(), signal.SIGKILL)
    return _load_scene(path, **options)


limber.load_scene = load_scene

if __name__ == "__main__":
    sys.exit(limber.sweep.main())
