"""The `chaoscope` command of the wheel: the command line, run by the Rust module."""

import sys

from . import _chaoscope


def main() -> None:
    sys.exit(_chaoscope.main(["chaoscope", *sys.argv[1:]]))
