"""The Python package's real-pendulum and film doors against the command line they wrap: fit,
forecast, track and zoom, each the command's own job, with errors that name their keyword.
Run by scripts/test after `pip install .` into target/pyenv."""

import inspect
import json
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import chaoscope
from _common import cli


def test_fit_equals_its_command(tmp_path):
    data = Path(__file__).parents[2] / "data" / "lab_table1.csv"
    # The guide's window (a table of one row every 1/3 s is fitted there with a small search;
    # the default window from the second row wants the default 65 536 candidates).
    made = chaoscope.fit(str(data), output=str(tmp_path / "py"), candidates=4096,
                         preset="lab", start=0.8, window=1.5, progress=False)
    cli("fit", str(data), "--output", str(tmp_path / "cli"), "--candidates", "4096",
        "--preset", "lab", "--start", "0.8", "--window", "1.5")
    written = json.loads((tmp_path / "cli" / "summary.json").read_text())
    ours = json.loads((tmp_path / "py" / "summary.json").read_text())
    # The same fit: the model, its search and agreement, and the command that makes it.
    assert ours["model"] == written["model"]
    assert made["agrees_until"] == written["model"]["agrees_until"]
    assert ours.get("command", "").replace(str(tmp_path / "py"), "") == written.get(
        "command", "").replace(str(tmp_path / "cli"), "")
    with pytest.raises(ValueError, match="^window: "):
        chaoscope.fit(str(data), output=str(tmp_path / "bad"), window=100.0, progress=False)
    # The fit finds the joint damping: no keyword for it.
    with pytest.raises(TypeError, match="joint_damping"):
        chaoscope.fit(str(data), joint_damping=0.01, progress=False)
    # y_up is for pixels: metres are read y up already.
    with pytest.raises(ValueError, match="^y_up: "):
        chaoscope.fit(str(data), output=str(tmp_path / "up"), y_up=True, progress=False)
    # A weighed mass sets the scale of moments found from the motion, not a stated model's.
    with pytest.raises(ValueError, match="^mass: "):
        chaoscope.fit(str(data), output=str(tmp_path / "kg"), preset="lab", mass=0.5,
                      progress=False)



def test_forecast_equals_its_command(tmp_path):
    data = Path(__file__).parents[2] / "data" / "lab_table1.csv"
    bands = chaoscope.forecast(str(data), output=str(tmp_path / "py"), window=(0.6, 1.7),
                               members=300, candidates=512, backend="cpu", preset="lab",
                               progress=False)
    cli("forecast", str(data), "--output", str(tmp_path / "cli"), "--window", "0.6:1.7",
        "--members", "300", "--candidates", "512", "--backend", "cpu", "--preset", "lab")
    # The same job: its bands byte for byte, and the command that makes them.
    assert (tmp_path / "py" / "bands.csv").read_bytes() == (
        tmp_path / "cli" / "bands.csv").read_bytes()
    written = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert bands.attrs["command"] == written["command"]
    assert bands.model.dims == ("time", "coordinate", "quantile")
    assert bands.model.attrs["units"] == "m" and bands.time.attrs["units"] == "s"
    # The Dataset holds the CSV's numbers: the lower bob's median x at the first time.
    lines = (tmp_path / "cli" / "bands.csv").read_text().splitlines()
    header, first = lines[2].split(","), lines[3].split(",")
    assert float(bands.model.sel(coordinate="x2", quantile=0.5)[0]) == float(
        first[header.index("x2_median")])
    # Quantiles ordered; the measurement's 90 % band (the model's with the tracking error) is
    # wider on average (at any one time 300 members' quantiles scatter).
    m, o = bands.model.values, bands.measurement.values
    assert (np.diff(m, axis=2) >= 0).all()
    assert (o[..., 4] - o[..., 0]).mean() > (m[..., 4] - m[..., 0]).mean()
    with pytest.raises(ValueError, match="^window: "):
        chaoscope.forecast(str(data), output=str(tmp_path / "bad"), window=(25.0, 30.0),
                           preset="lab", progress=False)
    with pytest.raises(ValueError, match="^members: "):
        chaoscope.forecast(str(data), output=str(tmp_path / "bad"), members=0, preset="lab",
                           progress=False)



def test_track_equals_its_command_as_a_dataset(tmp_path):
    film = Path(__file__).parents[2] / "data" / "test_film.mp4"
    tracked = chaoscope.track(str(film), output=str(tmp_path / "py.csv"), l1=0.30, progress=False)
    cli("track", str(film), "--output", str(tmp_path / "cli.csv"), "--l1", "0.30")
    # The same CSV as the command's, byte for byte.
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    assert tracked.position.dims == ("time", "mass", "coordinate")
    assert tracked.position.attrs["units"] == "m" and tracked.time.attrs["units"] == "s"
    assert list(tracked.mass.values) == ["upper", "lower"]
    # 300 frames at 30 a second, both markers in view throughout (the film's truth), where
    # the truth has them to 0.3 px RMS (0.4 mm at 727 px/m: the film is compressed hard, at
    # crf 23, which moves a centroid by a tenth of a pixel or two).
    assert tracked.sizes["time"] == 300 and bool(tracked.measured.all())
    truth = np.genfromtxt(film.with_suffix(".truth.csv"), delimiter=",", names=True,
                          skip_header=1, dtype=None, encoding="utf-8")
    assert np.allclose(tracked.time, truth["t"], atol=1e-4)
    true_xy = np.stack([np.stack([truth["x1"], truth["y1"]], -1),
                        np.stack([truth["x2"], truth["y2"]], -1)], 1)
    rms = float(np.sqrt(((tracked.position.values - true_xy) ** 2).sum(-1).mean()))
    assert rms < 0.3 / tracked.attrs["pixels_per_metre"], rms
    with pytest.raises(ValueError, match="^l1: "):
        chaoscope.track(str(film), output=str(tmp_path / "x.csv"), progress=False)
    # Not a colour, and two too alike in hue to tell apart.
    for markers in ("chartreuse", "red,orange"):
        with pytest.raises(ValueError, match="^markers: "):
            chaoscope.track(str(film), l1=0.3, markers=markers, progress=False)
    with pytest.raises(ValueError, match="^region: "):
        chaoscope.track(str(film), l1=0.3, region=(0, 0, 5000, 10), progress=False)
    # A model is for bridging only: without bridge=True it would do nothing.
    with pytest.raises(ValueError, match="^preset: "):
        chaoscope.track(str(film), l1=0.3, preset="lab", progress=False)
    # What is no film is a bad value of ``video``, as the command line's exit 2.
    (tmp_path / "text.mp4").write_text("no film here\n")
    with pytest.raises(ValueError, match="^video: "):
        chaoscope.track(str(tmp_path / "text.mp4"), l1=0.3, progress=False)
    # Nothing hidden, nothing bridged: the same positions, each marked measured.
    bridged = chaoscope.track(str(film), output=str(tmp_path / "b.csv"), l1=0.30, bridge=True,
                              progress=False)
    assert json.loads(bridged.attrs["bridged"])["gaps"] == 0 and not bool(bridged.bridged.any())
    assert np.array_equal(bridged.position.values, tracked.position.values)
    with pytest.raises(ValueError, match="^preset: "):
        chaoscope.track(str(film), l1=0.3, bridge=True, preset="moon", progress=False)



def test_zoom_is_its_command_with_frames_read_lazily(tmp_path):
    edge = (-1.68923151770833, 0.74163544020833)
    window = dict(size=(96, 54), theta2=(-1.7671458676442586, 1.7671458676442586), t_max=6)
    ds = chaoscope.zoom((*edge, 1e-7), frames=6, output=str(tmp_path / "py"), progress=False, **window)
    # The frames are read when asked for, not before.
    assert isinstance(ds.image.variable._data, xr.core.indexing.LazilyIndexedArray)
    assert ds.image.dims == ("frame", "y", "x", "channel") and ds.image.shape == (6, 54, 96, 3)
    # Each frame the PNG the command makes, byte for byte in its pixels.
    out = tmp_path / "cli"
    cli("zoom", f"--to={edge[0]},{edge[1]},1e-7", "--frames", "6", "--output", str(out),
        "flip", "--size", "96x54", "--theta2=-1.7671458676442586:1.7671458676442586", "--t-max", "6")
    for k in (0, 3, 5):
        w, h, rgb = chaoscope._chaoscope.png_rgb(str(out / f"frame_{k:04d}.png"))
        assert ds.image.isel(frame=k).values.tobytes() == rgb
    assert (out / "frames.csv").read_text() == (tmp_path / "py" / "frames.csv").read_text()
    # f32 while the step between starts is >= 16 f32 ulps of pi, f64 after.
    f32 = ds.step.values >= 16 * 2 * float(np.finfo(np.float32).eps)
    assert list(ds.precision.values) == ["f32" if s else "f64" for s in f32]
    assert json.loads(ds.attrs["switch"])["frame"] == int(np.argmin(f32))
    with pytest.raises(ValueError, match="^to: a width of 1e-15"):
        chaoscope.zoom((0.5, 0.5, 1e-15), output=str(tmp_path / "x"), size=64, progress=False)
    with pytest.raises(ValueError, match="^store: "):
        chaoscope.zoom((0.5, 0.5, 1e-3), output=str(tmp_path / "x"), store="m.zarr", progress=False)
    with pytest.raises(ValueError, match="^map: "):
        chaoscope.zoom((0.5, 0.5, 1e-3), output=str(tmp_path / "x"), map="phase", progress=False)
    with pytest.raises(TypeError, match="sizes"):
        chaoscope.zoom((0.5, 0.5, 1e-3), output=str(tmp_path / "x"), sizes=64, progress=False)
    for to in (None, 3, "abc", ()):
        with pytest.raises(ValueError, match="^to: "):
            chaoscope.zoom(to, output=str(tmp_path / "x"), progress=False)
    assert not (tmp_path / "x").exists()



def test_none_means_the_default_and_ranges_name_their_keyword(tmp_path, monkeypatch):
    # output=None is the library's default folder, out/zoom (here under tmp_path), never one
    # named "None".
    monkeypatch.chdir(tmp_path)
    chaoscope.zoom((0.5, 0.5, 0.5), frames=2, size=8, t_max=1, output=None, progress=False)
    assert (tmp_path / "out" / "zoom" / "frame_0001.png").exists()
    assert not (tmp_path / "None").exists()
    for bad in ((1, 1), (2, 1), (0, float("nan"))):
        with pytest.raises(ValueError, match="^x_range: "):
            chaoscope.flip_map(size=8, t_max=1, x="theta1", x_range=bad, progress=False)
        with pytest.raises(ValueError, match="^y_range: "):
            chaoscope.flip_map(size=8, t_max=1, y_range=bad, progress=False)



def test_zooms_defaults_are_the_commands():
    # Python's settings say None (the library's default, which the command's flags show),
    # and the docstring names the same defaults as `chaoscope zoom --help`.
    help_text = cli("zoom", "--help").stdout
    shown = dict(re.findall(r"--(frames|fps|crf|output) <[A-Z]+>\s+.*?\[default: ([^\]]+)\]", help_text, re.S))
    assert shown == {"frames": "120", "fps": "30", "crf": "18", "output": "out/zoom"}, shown
    parameters = inspect.signature(chaoscope.zoom).parameters
    for name in shown:
        assert parameters[name].default is None, name
    doc = chaoscope.zoom.__doc__
    for said in ("frames (default 120)", "default ``out/zoom``", "``fps`` (30)", "``crf`` (18)"):
        assert said in " ".join(doc.split()), said
