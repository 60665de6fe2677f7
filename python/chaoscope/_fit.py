"""The real pendulum: ``chaoscope.fit`` (the model from tracked positions, and a calibration
for forecasts) and ``chaoscope.forecast`` (an ensemble forecast scored only on rows it never
learned from)."""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Optional, Tuple, Union

import numpy as np
import xarray as xr

from . import _chaoscope as _native
from ._run import Progress, _call

Pair = Tuple[float, float]


def fit(
    file: str,
    *,
    output: str = "out/fit",
    pixels_per_metre: Union[None, float, str] = None,
    frame_rate: Optional[float] = None,
    before_release: bool = False,
    y_up: bool = False,
    start: Optional[float] = None,
    until: Optional[float] = None,
    window: Optional[float] = None,
    tolerance: Optional[float] = None,
    candidates: int = 65536,
    held_out: int = 40,
    lead: float = 1.0,
    velocity_error: float = 0.1,
    mass: Optional[float] = None,
    m1: Optional[float] = None,
    m2: Optional[float] = None,
    l1: Optional[float] = None,
    l2: Optional[float] = None,
    g: Optional[float] = None,
    rod_mass: Union[None, float, Pair] = None,
    air_drag: bool = False,
    rho: Optional[float] = None,
    cw: Optional[float] = None,
    drag_area: Union[None, float, Pair] = None,
    rod_drag_area: Union[None, float, Pair] = None,
    bearing_friction: Optional[float] = None,
    bearing_radius: Optional[float] = None,
    preset: Optional[str] = None,
    params_file: Optional[str] = None,
    backend: str = "auto",
    precision: Optional[str] = None,
    progress: Progress = None,
) -> dict:
    """The model fitted to a camera-tracked run (``chaoscope fit``): ``file`` is a CSV of
    t, x1, y1, x2, y2 (s, m; y up), or ``frame`` numbers at ``frame_rate`` and pixels (y down;
    ``y_up=True``: up, as Tracker exports them in its own frame) at ``pixels_per_metre`` (or
    ``"motion"``: the scale the swing implies), a moving pivot in
    ``x0``, ``y0``; a file ``track`` wrote is read from the release it found (the rest and
    the lift by hand are no free motion) unless ``before_release=True``. Returns the summary: the pivot and arm lengths (m, with errors), the
    energy's exponential and inverse-square decay fits, and how long the model released at
    ``start`` (s; default the second row) agrees with the data within ``tolerance`` (m;
    default 6 % of the reach), its ``candidates`` fitted over ``window`` s (default four of
    the motion's own times); plots, derived.csv, summary.json and model.toml (the model as a
    parameter file, ``params_file=`` reads it back) go to ``output``. model.toml also holds the
    calibration a :func:`forecast` of another launch carries (``held_out`` stretches of the
    recording, each fitted and followed ``lead`` s past its end: the model's own error by
    lead and the tracking error; ``held_out=0``: none); ``until`` (s) reads the rows up to
    that time only, a calibration stretch of a longer recording. The model: a
    ``preset`` or ``params_file`` where given, else the pendulum's own moments found from its
    motion, over the upper arm's gravity moment P unless ``mass`` (kg, the weighed
    pendulum: all that swings) sets their scale in kg m^2 and joules; the joint damping is what
    the fit finds. ``summary["verdict"]`` says whether the
    model follows the data in the window; where it does not, :class:`ModelWarning` is raised
    as a warning and the figures are no findings.
    """
    keywords = dict(locals())
    keywords.pop("progress")
    summary = json.loads(_call(_native.fit, keywords, progress))
    _warn_unfollowed(summary.get("verdict"))
    return summary


class ModelWarning(UserWarning):
    """The fitted model does not follow the tracked data in its window: its horizons and
    agreement are no findings (the command line exits 3)."""


def _warn_unfollowed(verdict: Optional[dict]) -> None:
    if verdict is not None and not verdict["follows"]:
        warnings.warn(
            f"the fitted model does not follow the data: it strays by {1e3 * verdict['rms']:.3f} mm "
            f"RMS, {verdict['ratio']:.1f} times the tracking error (at most {verdict['limit']:g}); "
            "state the pendulum's model (preset= or params_file=) or try another window",
            ModelWarning,
            stacklevel=3,
        )


def forecast(
    file: str,
    *,
    output: str = "out/forecast",
    pixels_per_metre: Union[None, float, str] = None,
    frame_rate: Optional[float] = None,
    before_release: bool = False,
    y_up: bool = False,
    window: Optional[Pair] = None,
    ahead: Optional[float] = None,
    in_sample: bool = False,
    members: int = 10000,
    seed: int = 1,
    tolerance: Optional[float] = None,
    tracking_error: Optional[float] = None,
    candidates: int = 65536,
    held_out: int = 8,
    video: Optional[str] = None,
    m1: Optional[float] = None,
    m2: Optional[float] = None,
    l1: Optional[float] = None,
    l2: Optional[float] = None,
    g: Optional[float] = None,
    rod_mass: Union[None, float, Pair] = None,
    air_drag: bool = False,
    rho: Optional[float] = None,
    cw: Optional[float] = None,
    drag_area: Union[None, float, Pair] = None,
    rod_drag_area: Union[None, float, Pair] = None,
    bearing_friction: Optional[float] = None,
    bearing_radius: Optional[float] = None,
    preset: Optional[str] = None,
    params_file: Optional[str] = None,
    backend: str = "auto",
    precision: Optional[str] = None,
    progress: Progress = None,
) -> xr.Dataset:
    """An ensemble forecast of a camera-tracked run (``chaoscope forecast``; ``file`` and its
    units as :func:`fit`): the model's state, joint damping, pivot, scale and lower arm
    fitted on ``window`` = (start, end) in s (default: from the second row, a calibration's
    length, else four of the motion's own times over the window's own rows), then
    ``members`` drawn from the fit's covariance (``seed``) and integrated to the data's end
    (or ``ahead`` s past the window, whether or not rows exist there), the bands at least as
    wide as the model's own error: a calibration's (``params_file`` written by :func:`fit`),
    else measured on ``held_out`` windows of the recording before this one. Nothing is
    learned from the rows after the window: they are only scored (``in_sample=True`` learns
    from every row, and every output says so).
    Returns an ``xarray.Dataset`` over ``time`` (s): ``model`` and ``measurement`` (the
    model's band with the tracking error, ``tracking_error`` m or the fit's residuals)
    quantiles of the positions (m) by ``coordinate`` (x1, y1, x2, y2) and ``quantile``
    (0.05 .. 0.95),
    ``spread_lower`` (m, the lower bob's RMS spread) and ``ftle`` (1/s, along the fitted
    orbit); ``attrs`` hold the horizon (s after the window: when the median is expected to
    leave the pendulum by ``tolerance`` m, default 5 % of the reach; summary.json has its
    quartiles), the spread's and the data's, ``sample`` ("out of sample" unless
    ``in_sample``), the summary.json and the reproducing command. forecast.png, bands.csv and
    summary.json go to ``output``, and with ``video`` (the film :func:`track` read) the
    forecast drawn on its frames, overlay.mp4. The model as :func:`fit` finds it; where it
    does not follow the data in the window, :class:`ModelWarning` is raised as a warning,
    ``attrs["model_follows"]`` is 0 and the horizons are NaN (no findings).
    """
    keywords = dict(locals())
    keywords.pop("progress")
    if video is None:
        keywords.pop("video")
    short = json.loads(_call(_native.forecast, keywords, progress))
    _warn_unfollowed(short.get("verdict"))
    return _bands(Path(short["output"]))


def _bands(out: Path) -> xr.Dataset:
    """bands.csv and summary.json of a forecast as a Dataset."""
    summary = json.loads((out / "summary.json").read_text())
    table = np.loadtxt(out / "bands.csv", delimiter=",", comments="#", skiprows=3)
    header = (out / "bands.csv").read_text().splitlines()[2].split(",")
    coords = ["x1", "y1", "x2", "y2"]
    quantiles = [0.05, 0.25, 0.5, 0.75, 0.95]
    names = ["p05", "p25", "median", "p75", "p95"]

    def block(kind: str) -> np.ndarray:
        cols = [[header.index(f"{c}_{kind}{q}") for q in names] for c in coords]
        return table[:, cols]

    dims = ("time", "coordinate", "quantile")
    horizon = summary["horizon"]
    follows = bool(summary["verdict"]["follows"])
    return xr.Dataset(
        {
            "model": (dims, block(""), {"units": "m", "long_name": "members' positions"}),
            "measurement": (
                dims,
                block("obs_"),
                {"units": "m", "long_name": "a measurement's positions (model and tracking error)"},
            ),
            "spread_lower": (
                "time",
                table[:, header.index("spread_lower")],
                {"units": "m", "long_name": "lower bob's RMS distance from the members' mean"},
            ),
            "ftle": (
                "time",
                table[:, header.index("ftle")],
                {"units": "1/s", "long_name": "FTLE along the fitted orbit from the window's end"},
            ),
        },
        coords={
            "time": ("time", table[:, 0], {"units": "s"}),
            "coordinate": coords,
            "quantile": quantiles,
        },
        attrs={
            "command": summary["command"],
            "model_follows": int(follows),
            "horizon": _nan(horizon["headline"]["lead"] if follows else None),
            "sample": summary["sample"],
            "spread_horizon": _nan(horizon["spread"] if follows else None),
            "data_horizon": _nan(horizon["data"] if follows else None),
            "lyapunov_exponent": summary["lyapunov"]["exponent"],
            "tracking_error": summary["ensemble"]["tracking_error"],
            "summary": json.dumps(summary),
        },
    )


def _nan(v: Optional[float]) -> float:
    """A horizon beyond the data (null in JSON) as NaN: netCDF attributes hold no None."""
    return float("nan") if v is None else float(v)
