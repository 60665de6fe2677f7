"""What the Python tests share: the wheel's command line and a bit-for-bit comparison."""

import subprocess
import sys
from pathlib import Path

BIN = Path(sys.executable).parent / "chaoscope"


def cli(*args, check=True):
    """The wheel's `chaoscope` command (the venv's console script)."""
    return subprocess.run([str(BIN), *args], capture_output=True, text=True, check=check)



def run_command(command, *extra):
    """A map's reproducing command (attrs["command"]), with `extra` flags."""
    words = command.split()
    assert words[0] == "chaoscope"
    return cli(*words[1:], *extra)



def same_bits(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
