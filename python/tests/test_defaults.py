"""Each default written once: a keyword of a Python function and the flag of the same name
of its command take the same default, read from the commands' own --help."""

import inspect
import re

import pytest

import chaoscope
from _common import cli

DOORS = [
    (chaoscope.flip_map, "flip"),
    (chaoscope.lyapunov_map, "lyapunov"),
    (chaoscope.trajectory, "trajectory"),
    (chaoscope.traces, "traces"),
    (chaoscope.fit, "fit"),
    (chaoscope.forecast, "forecast"),
    (chaoscope.track, "track"),
    (chaoscope.zoom, "zoom"),
]


def flag_defaults(command):
    """{flag's field: its default as --help shows it} of `chaoscope COMMAND`."""
    text = cli(command, "--help").stdout
    blocks = re.split(r"\n\s+(?:-\w, )?--", "\n" + text)
    out = {}
    for block in blocks[1:]:
        name = re.match(r"[\w-]+", block).group(0)
        found = re.search(r"\[default: ([^\]]+)\]", block)
        if found:
            out[name.replace("-", "_")] = found.group(1)
    return out


def same(python, shown):
    if isinstance(python, bool):
        # A switch's default in words ("[default: from the release]") is its being off.
        return str(python).lower() == shown or (not python and shown not in ("true", "false"))
    if isinstance(python, (int, float)):
        try:
            return float(python) == float(shown)
        except ValueError:
            return False
    return str(python) == shown


@pytest.mark.parametrize("function,command", DOORS, ids=[c for _, c in DOORS])
def test_python_defaults_are_the_command_lines(function, command):
    shown = flag_defaults(command)
    compared = 0
    for name, p in inspect.signature(function).parameters.items():
        if p.default is inspect.Parameter.empty or p.default is None or name not in shown:
            continue
        compared += 1
        assert same(p.default, shown[name]), (
            f"{function.__name__}({name}={p.default!r}) but {command} --{name.replace('_', '-')}"
            f" defaults to {shown[name]}"
        )
    # zoom's keywords are None, the library's defaults (spec::ZoomDefaults), as its flags'.
    assert compared > 0 or command == "zoom", f"{command}: no default compared"
