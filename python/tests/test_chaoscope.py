"""The Python package against the command line it wraps: every map bit for bit equal to the
.npy its reproducing command writes, errors that name their keyword, Ctrl-C, the wheel's
command line. Run by scripts/test after `pip install .` into target/pyenv."""

import inspect
import json
import os
import shutil
import signal
import struct
import subprocess
import sys
import threading
import time
import zlib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import chaoscope
from _common import BIN, cli, run_command, same_bits


def test_flip_map_equals_its_command_bit_for_bit(tmp_path):
    flips = chaoscope.flip_map(size=(48, 40), t_max=4, m2=1.5, progress=False)
    assert isinstance(flips, xr.DataArray)
    assert flips.dims == ("theta2", "theta1")
    assert flips.attrs["units"] == "s" and flips.theta1.attrs["units"] == "rad"
    # Row 0 at the top: theta2 falls down the rows.
    assert flips.theta2[0] > flips.theta2[-1] and flips.theta1[0] < flips.theta1[-1]
    if os.environ.get("CI") == "true":
        # CI has lavapipe: the map ran on it, not on the CPU fallback.
        assert flips.attrs["place"] != "the CPU", flips.attrs
    npy = tmp_path / "flips.npy"
    run_command(flips.attrs["command"], "--data", str(npy), "--output", str(tmp_path / "f.png"))
    assert same_bits(np.load(npy), flips.values)



def test_a_parameter_plane_with_its_verdict_equals_its_command(tmp_path):
    made = chaoscope.flip_map(
        size=(40, 24), t_max=3, x="m2/m1", x_range=(0.5, 2.0), y="omega1",
        y_range=(-4.0, 4.0), theta1=2.0, theta2=1.0, resolved=True, progress=False,
    )
    assert isinstance(made, xr.Dataset)
    assert made["map"].dims == ("omega1", "mass_ratio")
    assert made.mass_ratio.attrs["units"] == "1" and made.omega1.attrs["units"] == "rad/s"
    assert made["map"].attrs["start"]["theta2"] == 1.0
    npy, mask = tmp_path / "plane.npy", tmp_path / "plane_mask.npy"
    run_command(made.attrs["command"], "--data", str(npy), "--resolved", str(mask),
                "--output", str(tmp_path / "p.png"))
    assert same_bits(np.load(npy), made["map"].values)
    assert same_bits(np.load(mask), made["resolved"].values)
    assert set(np.unique(made["resolved"].values)) <= {0, 1}



def test_a_map_is_what_xarrays_constructor_makes_without_importing_dask():
    """The fast construction (numpy variable, pandas indexes) gives what xarray's generic
    constructor gives, and a process's first map does not import dask (installed here for
    the Dask example; importing it cost 0.4-1.4 s of the first map)."""
    made = chaoscope.flip_map(size=(16, 12), t_max=1, resolved=True, progress=False)
    for array in (made["map"], made["resolved"]):
        generic = xr.DataArray(
            array.values,
            dims=array.dims,
            coords={d: (d, array[d].values, array[d].attrs) for d in array.dims},
            name=array.name,
            attrs=array.attrs,
        )
        xr.testing.assert_identical(array, generic)
    fresh = subprocess.run(
        [sys.executable, "-c", "import sys, chaoscope; chaoscope.flip_map(size=8, t_max=0.1, "
         "progress=False); print('dask' in sys.modules)"],
        capture_output=True, text=True, check=True,
    )
    assert fresh.stdout.strip() == "False", fresh.stdout + fresh.stderr



def test_a_map_reaches_python_without_a_copy():
    """The issue's memory target, on the CPU backend (whose engine holds nothing beyond the
    map; lavapipe's GPU buffers are host memory and would count): in a process where a map
    has been made once (the thread pool, the lazy imports), a map's call peaks at most 10 %
    above the map's bytes over the baseline (1.003x measured at 1536^2). A copy on the way to
    numpy or xarray would double it."""
    child = r"""
import json
import chaoscope
def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024
chaoscope.flip_map(size=8, t_max=0.02, backend="cpu", progress=False)
base = status("VmRSS:")
# Resets this process's peak RSS (VmHWM) to the present.
open("/proc/self/clear_refs", "w").write("5")
m = chaoscope.flip_map(size=1536, t_max=0.02, backend="cpu", progress=False)
print(json.dumps({"over": status("VmHWM:") - base, "map": m.values.nbytes}))
"""
    out = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True, check=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["map"] == 1536 * 1536 * 4
    assert got["over"] <= 1.1 * got["map"], got



@pytest.mark.parametrize("indicator", ["ftle", "megno"])
def test_lyapunov_maps_equal_their_commands(tmp_path, indicator):
    made = chaoscope.lyapunov_map(size=32, t_max=2, indicator=indicator, progress=False)
    npy = tmp_path / "l.npy"
    run_command(made.attrs["command"], "--data", str(npy), "--output", str(tmp_path / "l.png"))
    assert same_bits(np.load(npy), made.values)
    assert f"--indicator {indicator}" in made.attrs["command"] or indicator == "ftle"



def test_trajectory_equals_its_command():
    run = chaoscope.trajectory(theta1=2.1, theta2=-0.7, t_max=2, every=0.05, joint_damping=0.01)
    assert run.t.attrs["units"] == "s" and run.theta1.attrs["units"] == "rad"
    csv = run_command(run.attrs["command"]).stdout.splitlines()
    table = np.loadtxt(csv[2:], delimiter=",")
    names = csv[1].split(",")
    # One name for each column in the CSV and the Dataset, time included.
    assert [run.t.name, *run.data_vars] == names
    assert np.array_equal(table[:, 0], run.t.values)
    for k, name in enumerate(names[1:], start=1):
        assert np.array_equal(table[:, k], run[name].values), name


def test_trajectory_at_a_parameter_planes_pixel():
    # m2/m1 = 2.5 on m1 = 2 is m2 = 5, whichever way it is given (2.5 x 2 is exact).
    at = chaoscope.trajectory(theta1=2, theta2=2, t_max=1, m1=2, at={"m2/m1": 2.5})
    given = chaoscope.trajectory(theta1=2, theta2=2, t_max=1, m1=2, m2=5)
    assert np.array_equal(at.theta2.values, given.theta2.values)
    with pytest.raises(ValueError, match="^at: "):
        chaoscope.trajectory(theta1=2, theta2=2, t_max=1, at={"theta1": 1.0})
    with pytest.raises(ValueError, match="^at: "):
        chaoscope.trajectory(theta1=2, theta2=2, t_max=1, at={"mass": 1.0})



def png_pixels(png):
    """A PNG's size and its decompressed scanlines (the encoder's filtered rows)."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    at, idat, size = 8, b"", None
    while at < len(png):
        (length,), kind = struct.unpack(">I", png[at:at + 4]), png[at + 4:at + 8]
        data = png[at + 8:at + 8 + length]
        if kind == b"IHDR":
            size = struct.unpack(">II", data[:8])
        elif kind == b"IDAT":
            idat += data
        at += 12 + length
    return size, zlib.decompress(idat)



def test_picture_is_the_commands_png(tmp_path):
    flips = chaoscope.flip_map(size=64, t_max=3, progress=False)
    pic = chaoscope.picture(flips, colormap="turbo", annotate=True)
    assert pic._repr_png_() == pic.png
    png = tmp_path / "cli.png"
    run_command(flips.attrs["command"], "--colormap", "turbo", "--annotate", "--output", str(png))
    assert png_pixels(pic.png) == png_pixels(png.read_bytes())
    # The same PNG, byte for byte: pixels and every text chunk the command writes.
    assert pic.png == png.read_bytes()
    bare = chaoscope.picture(flips)
    run_command(flips.attrs["command"], "--output", str(png))
    assert bare.png == png.read_bytes()
    assert png_pixels(bare.png)[0] == (64, 64)
    # Saved where the folders do not exist yet, as the command line would.
    bare.save(str(tmp_path / "new" / "folder" / "flip.png"))
    assert (tmp_path / "new" / "folder" / "flip.png").read_bytes() == png.read_bytes()
    checked = chaoscope.flip_map(size=32, t_max=2, resolved=True, progress=False)
    shown = chaoscope.picture(checked, show_unresolved=True)
    run_command(checked["map"].attrs["command"], "--show-unresolved", "--output", str(png),
                "--resolved", str(tmp_path / "r.npy"))
    assert shown.png == png.read_bytes()



@pytest.mark.parametrize(
    "keywords, name",
    [
        ({"t_max": -1}, "t_max"),
        ({"dt": 0}, "dt"),
        ({"size": 0}, "size"),
        ({"m1": -2}, "m1"),
        ({"x": "speed"}, "x"),
        ({"backend": "tpu"}, "backend"),
        ({"measure": "colour"}, "measure"),
        ({"samples": 0}, "samples"),
        ({"samples": -3}, "samples"),
        ({"size": -1}, "size"),
        ({"size": (16, 2**40)}, "size"),
        ({"store": "x.zarr", "tile": (5, 2)}, "tile"),
        ({"x": "omega1"}, "x"),
        ({"theta1": (-9.0, 9.0)}, "theta1"),
        ({"integrator": "euler"}, "integrator"),
    ],
)
def test_bad_values_raise_value_error_naming_the_keyword(keywords, name):
    with pytest.raises(ValueError, match=f"^{name}: "):
        chaoscope.flip_map(**{"size": 16, "t_max": 1, "progress": False, **keywords})



def test_bad_keywords_and_types_raise_type_error():
    with pytest.raises(TypeError, match="tmax"):
        chaoscope.flip_map(tmax=3)
    with pytest.raises(TypeError, match="^t_max: "):
        chaoscope.flip_map(size=16, t_max="long")
    with pytest.raises(TypeError, match="^theta1: "):
        chaoscope.flip_map(size=16, theta1="all")
    with pytest.raises(ValueError, match="^indicator: "):
        chaoscope.lyapunov_map(size=16, t_max=1, indicator="entropy")
    # accurate steps the tangent method with DP54, as `lyapunov --accurate` refuses a twin.
    with pytest.raises(ValueError, match="^accurate: .*method='twin'"):
        chaoscope.lyapunov_map(size=16, t_max=1, accurate=True, method="twin")
    with pytest.raises(TypeError, match="colour"):
        chaoscope.params(colour=3)



def test_ctrl_c_stops_a_long_map_and_the_next_call_works():
    # 1024^2 pendulums for 100 s, every one every step: some 30 s on lavapipe, so the signal
    # comes mid-map.
    # Python raises KeyboardInterrupt on SIGINT only where it started with SIGINT's default
    # action: a run started in the background by a shell without job control inherits it
    # ignored. The handler a terminal's Python has, then.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    started = time.monotonic()
    try:
        chaoscope.flip_map(size=1024, t_max=100, use_symmetry=False, early_exit=False,
                           progress=False)
    except KeyboardInterrupt:
        pass
    else:
        pytest.fail(f"no KeyboardInterrupt: the map ran {time.monotonic() - started:.1f} s "
                    "(the signal came at 1 s)")
    stopped = time.monotonic() - started - 1.0
    timer.join()
    signal.signal(signal.SIGINT, previous)
    # The engine stops at its next dispatch: well within 2 s of the signal.
    assert stopped < 2.0, stopped
    again = chaoscope.flip_map(size=16, t_max=1, progress=False)
    assert again.shape == (16, 16)



def test_progress_is_reported_to_a_callable():
    seen = []
    # Every pixel for every step (~1 s on lavapipe): long enough for the 0.1 s looks.
    chaoscope.flip_map(size=256, t_max=30, use_symmetry=False, early_exit=False,
                       progress=lambda *p: seen.append(p))
    assert seen, "the callable was never called"
    assert all(isinstance(phase, str) and done >= 0 for phase, done, _ in seen)



def test_the_wheels_command_line_runs_from_the_venv():
    assert shutil.which("chaoscope", path=str(BIN.parent)) == str(BIN)
    assert cli("--version").stdout.startswith("chaoscope ")
    bad = cli("flip", "--size", "0", check=False)
    assert bad.returncode == 2 and "--size" in bad.stderr



def test_a_store_opens_lazily_with_its_command(tmp_path):
    store = tmp_path / "map.zarr"
    flips = chaoscope.flip_map(size=32, t_max=2, progress=False)
    run_command(flips.attrs["command"], "--data", str(store))
    opened = chaoscope.open_store(str(store))
    assert opened.attrs["command"].startswith("chaoscope flip")
    assert same_bits(opened["map"].values, flips.values)
    assert list(opened["map"].dims) == ["theta2", "theta1"]
    # Another map into the same store is refused naming the keyword, with what differs.
    with pytest.raises(ValueError, match="^store: .*t_max"):
        chaoscope.flip_map(size=32, t_max=3, store=str(store), progress=False)



def test_python_manners():
    sig = inspect.signature(chaoscope.flip_map)
    assert all(p.kind is p.KEYWORD_ONLY for p in sig.parameters.values())
    assert sig.parameters["t_max"].default == 30.0
    assert "flip" in chaoscope.flip_map.__doc__
    lab = chaoscope.params("lab")
    assert lab["m1"] == pytest.approx(0.301) and lab["air_drag"]
    # The physics round-trips into the map functions.
    assert chaoscope.flip_map(size=8, t_max=1, progress=False, **lab).shape == (8, 8)
    package = Path(chaoscope.__file__).parent
    assert (package / "py.typed").exists() and (package / "_chaoscope.pyi").exists()



def test_the_readmes_python_runs(tmp_path, monkeypatch, capsys):
    readme = (Path(__file__).parents[2] / "README.md").read_text()
    code = readme.split("```python\n", 1)[1].split("```", 1)[0]
    # Anywhere: the folder `out/` it saves into does not exist yet.
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    assert (tmp_path / "out" / "flip_python.png").exists()
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].endswith(" s") and printed[1].startswith("chaoscope flip ")
    assert (tmp_path / "out" / "flip_python.png").read_bytes()[:4] == b"\x89PNG"


EXAMPLES = Path(__file__).parents[2] / "examples"



def test_the_notebook_executes_and_draws_its_figures(tmp_path):
    import base64

    import nbformat
    from nbclient import NotebookClient

    notebook = nbformat.read(EXAMPLES / "explore.ipynb", as_version=4)
    # Committed with its outputs (examples/make_notebook.py executes it): a reader on the
    # web sees its six figures.
    committed = [
        output for cell in notebook.cells if cell.cell_type == "code"
        for output in cell.get("outputs", []) if "image/png" in output.get("data", {})
    ]
    assert len(committed) == 6, "examples/explore.ipynb lacks its outputs: run make_notebook.py"
    client = NotebookClient(notebook, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    images = [
        base64.b64decode(output["data"]["image/png"])
        for cell in notebook.cells if cell.cell_type == "code"
        for output in cell.get("outputs", [])
        if "image/png" in output.get("data", {})
    ]
    # The flip map, the zoom, the trajectory, the two maps side by side, the command line's
    # picture, the store's part: each a PNG of some substance (an empty axes is ~5 kB).
    assert len(images) == 6, len(images)
    assert all(len(png) > 10_000 for png in images), [len(png) for png in images]



def test_the_dask_example_fills_one_store_equal_to_the_single_process_map(tmp_path):
    ran = subprocess.run(
        [sys.executable, str(EXAMPLES / "dask_map.py"), str(tmp_path / "dask.zarr"),
         "--size", "256", "--t-max", "3", "--tiles", "4", "--workers", "2"],
        capture_output=True, text=True, timeout=600,
    )
    assert ran.returncode == 0, ran.stdout + ran.stderr
    assert "4 tasks on 2 workers filled 65536 pixels" in ran.stdout, ran.stdout
    assert "equal to the single-process map, bit for bit" in ran.stdout, ran.stdout



def test_progress_goes_to_tqdm_when_it_is_installed(monkeypatch):
    import types

    bars = []

    class FakeBar:
        def __init__(self, total=None, desc="", leave=True):
            self.total, self.desc, self.n, self.closed = total, desc, 0, False
            bars.append(self)

        def update(self, k):
            self.n += k

        def close(self):
            self.closed = True

    fake = types.ModuleType("tqdm.auto")
    fake.tqdm = FakeBar
    monkeypatch.setitem(sys.modules, "tqdm", types.ModuleType("tqdm"))
    monkeypatch.setitem(sys.modules, "tqdm.auto", fake)
    # Long enough (~1 s on lavapipe) for the 0.1 s looks to see it run.
    chaoscope.flip_map(size=256, t_max=30, use_symmetry=False, early_exit=False)
    assert bars, "no bar was made"
    assert all(b.closed for b in bars)
    assert any(b.n > 0 for b in bars), [(b.desc, b.n, b.total) for b in bars]



def test_traces_equal_their_command(tmp_path):
    runs = chaoscope.traces(theta1=2.0, theta2=2.5, runs=8, spread="5mm", exposure=0.5,
                            size=64, output=str(tmp_path / "py.png"), backend="cpu",
                            progress=False)
    assert runs.dims == ("run", "time", "coordinate") and runs.shape == (8, 501, 4)
    assert runs.attrs["units"] == "m" and runs.time.attrs["units"] == "s"
    words = runs.attrs["command"].split()[1:]
    cli(*words, "--output", str(tmp_path / "cli.png"), "--data", str(tmp_path / "cli.npy"))
    # The same job: the command line's positions bit for bit, and its picture.
    assert np.array_equal(np.load(tmp_path / "cli.npy"), runs.values)
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    with pytest.raises(ValueError, match="^runs: "):
        chaoscope.traces(theta1=2.0, theta2=2.5, runs=0, output=str(tmp_path / "bad.png"),
                         progress=False)
    with pytest.raises(ValueError, match="^spread: "):
        chaoscope.traces(theta1=2.0, theta2=2.5, spread="5 furlongs",
                         output=str(tmp_path / "bad.png"), progress=False)



def test_every_indicator_option_is_a_keyword_and_reaches_the_command():
    """The measures declare their options (the registry); each is a keyword of
    lyapunov_map, and one given travels into the map's reproducing command."""
    keywords = inspect.signature(chaoscope.lyapunov_map).parameters
    options = chaoscope._native.INDICATOR_OPTIONS
    assert "rli_delta" in options and "ld_p" in options
    for field in options:
        assert field in keywords and keywords[field].default is None, field
    m = chaoscope.lyapunov_map(size=8, t_max=1, indicator="rli", rli_delta=1e-6,
                               backend="cpu", progress=False)
    assert "--indicator rli --rli-delta 1e-6" in m.attrs["command"]
    with pytest.raises(ValueError, match="^rli_delta: "):
        chaoscope.lyapunov_map(size=8, t_max=1, indicator="rli", rli_delta=1.0,
                               backend="cpu", progress=False)
    with pytest.raises(ValueError, match="^gali: "):
        chaoscope.lyapunov_map(size=8, t_max=1, indicator="gali", gali=7,
                               backend="cpu", progress=False)


def test_python_is_as_strict_as_the_command_line(tmp_path):
    """Issue 35's audit of the Python door: a bool where a number is wanted, a tile without
    a store, a progress of another type, a colour range upside down, an eps no twin could
    take, a file where a store should be, a missing CSV and an axis beside the value it sets
    are refused naming the keyword."""
    for keywords in ({"size": True}, {"samples": True}, {"t_max": True}):
        with pytest.raises(TypeError, match=f"^{next(iter(keywords))}: "):
            chaoscope.flip_map(**{"size": 8, "t_max": 1, "progress": False, **keywords})
    with pytest.raises(TypeError, match="^exponent: "):
        chaoscope.lyapunov_map(size=8, t_max=1, indicator="exponent", exponent=True, progress=False)
    with pytest.raises(ValueError, match="^tile: "):
        chaoscope.flip_map(size=8, t_max=1, tile=(0, 2), progress=False)
    with pytest.raises(TypeError, match="^progress: "):
        chaoscope.flip_map(size=8, t_max=1, progress="yes")
    with pytest.raises(ValueError, match="^eps: "):
        chaoscope.lyapunov_map(size=8, t_max=1, eps=0, progress=False)
    made = chaoscope.lyapunov_map(size=8, t_max=1, progress=False)
    with pytest.raises(ValueError, match="^colour_range: "):
        chaoscope.picture(made, colour_range=(1, 0))
    a_file = tmp_path / "map.zarr"
    a_file.write_text("not a store")
    with pytest.raises(ValueError, match="^store: "):
        chaoscope.flip_map(size=8, t_max=1, store=str(a_file), progress=False)
    with pytest.raises(FileNotFoundError, match="^file: "):
        chaoscope.forecast(str(tmp_path / "nope.csv"))
    with pytest.raises(FileNotFoundError, match="^params_file: "):
        chaoscope.flip_map(size=8, params_file="/nonexistent/pendulum.toml", progress=False)
    with pytest.raises(ValueError, match="^m1: .*m1 along x"):
        chaoscope.flip_map(size=8, t_max=1, x="m1", x_range=(1, 2), m1=3, progress=False)
    with pytest.raises(ValueError, match="^exposure: "):
        chaoscope.traces(theta1=1, theta2=1, exposure=-1, progress=False)



def test_reads_are_bounded_from_python(tmp_path):
    """`chaoscope.fit('/dev/zero')` read until the kernel killed it: a device, a FIFO and a
    10 GB sparse file are refused naming the keyword, at once."""
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    sparse = tmp_path / "sparse.toml"
    with open(sparse, "wb") as f:
        f.truncate(10 << 30)
    for path in ("/dev/zero", str(fifo)):
        with pytest.raises(ValueError, match="^file: .*not a regular file"):
            chaoscope.fit(path, progress=False)
        with pytest.raises(ValueError, match="^params_file: .*not a regular file"):
            chaoscope.params(params_file=path)
    with pytest.raises(ValueError, match="^params_file: .*larger than"):
        chaoscope.params(params_file=str(sparse))



def test_repeated_maps_do_not_grow_the_process():
    """200 calls of a MEGNO map each made a GPU device, growing the process by 53 MB; the
    engine is now made once and lent. After a warm-up, 200 calls may grow RSS by 2 MB (the
    allocator's slack)."""
    child = r"""
import json
import chaoscope
def rss():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024
for _ in range(20):
    chaoscope.lyapunov_map(size=64, t_max=1, indicator="megno", progress=False)
before = rss()
for _ in range(200):
    chaoscope.lyapunov_map(size=64, t_max=1, indicator="megno", progress=False)
print(json.dumps({"grown": rss() - before}))
"""
    out = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True, check=True)
    grown = json.loads(out.stdout.strip().splitlines()[-1])["grown"]
    print(f"RSS grew {grown / 2**20:.2f} MB over 200 calls")
    assert grown <= 2 << 20, grown



def test_a_message_names_settings_as_keywords_not_flags():
    # The library names the setting to change; Python words it as its keyword.
    with pytest.raises(ValueError, match="^dt: ") as caught:
        chaoscope.flip_map(size=8, t_max=1, dt=0.05, resolved=True, progress=False)
    assert "dt=0.01" in str(caught.value) and "--" not in str(caught.value)
    with pytest.raises(ValueError, match="^threshold: ") as caught:
        chaoscope.lyapunov_map(size=8, t_max=1, indicator="sali", threshold=1e-8,
                               backend="gpu", progress=False)
    assert "precision='f64'" in str(caught.value) and "--" not in str(caught.value)
