"""The README's Python example runs as written (from the repository root, as the README says)."""
import os
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(os.environ.get("LIMBER_SOURCE_DIR", pathlib.Path(__file__).parents[2]))


def test_the_readmes_python_example_runs():
    section = ROOT.joinpath("README.md").read_text().split("## In Python", 1)[1]
    command = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    code = re.search(r'-c "\n(.*?)"\n', command, re.S).group(1)
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert len(done.stdout.split()) >= 4  # a position (3 numbers) and the energy
