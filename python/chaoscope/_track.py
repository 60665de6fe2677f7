"""``chaoscope.track``: a film of the pendulum to the positions of both masses."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Optional, Tuple, Union

import numpy as np
import xarray as xr

from . import _chaoscope as _native
from ._run import Progress, _call


def track(
    video: str,
    *,
    output: str = "out/track.csv",
    l1: Optional[float] = None,
    pixels_per_metre: Union[None, float, str] = None,
    markers: str = "bright",
    region: Optional[Tuple[int, int, int, int]] = None,
    bridge: bool = False,
    preset: Optional[str] = None,
    params_file: Optional[str] = None,
    progress: Progress = None,
) -> xr.Dataset:
    """The positions of both masses in every frame of a film of the pendulum (``chaoscope
    track``): bright markers on a dark background, ``markers="ff2020"`` (or ``"red"``) for
    stickers of one colour, or ``markers="red,green"`` for the upper and the lower mass; the
    scale from the upper arm's length ``l1`` (m) or ``pixels_per_metre`` (or ``"motion"``:
    the scale the swing implies under g at the film's own frame times); ``region`` (x0, y0,
    x1, y1 in pixels) to look in part of the picture. ``bridge=True`` fills gaps where a mass
    is hidden (up to 1 s, with 5 measured rows on each side) with the model fitted to the
    half second measured on each side (``preset`` or ``params_file`` for its masses and
    losses, the lab's by default), marked as bridged. The CSV that ``fit`` and ``forecast``
    read (the measured rows only) is written to ``output``.

    Returns a Dataset over ``time`` (s, the film's timestamps), ``mass`` (upper, lower) and
    ``coordinate`` (x, y; m from the pivot, y up): ``position`` (NaN where a mass was not
    seen), ``error`` (its standard error: the sensor's noise's, or the model's where
    bridged), ``measured`` and ``bridged`` (bool) and ``streak`` (how far the marker moved
    while the shutter was open, m); the summary (pivot, scale, up, the film's frame rate,
    the processing speed...) in ``attrs``.
    """
    keywords = dict(locals())
    keywords.pop("progress")
    keywords["video"] = str(video)
    keywords["output"] = str(output)
    if params_file is not None:
        keywords["params_file"] = str(params_file)
    summary = json.loads(_call(_native.track, keywords, progress))
    return _dataset(Path(summary["output"]), summary)


def _dataset(path: Path, summary: dict) -> xr.Dataset:
    with open(path, newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    rows = list(csv.DictReader(lines))
    n = len(rows)
    position = np.full((n, 2, 2), np.nan)
    error = np.full((n, 2, 2), np.nan)
    streak = np.full((n, 2), np.nan)
    measured = np.zeros((n, 2), dtype=bool)
    bridged = np.zeros((n, 2), dtype=bool)
    for k, r in enumerate(rows):
        for m in range(2):
            seen = r[f"seen{m + 1}"]
            if seen in ("measured", "bridged"):
                measured[k, m] = seen == "measured"
                bridged[k, m] = seen == "bridged"
                position[k, m] = (float(r[f"x{m + 1}"]), float(r[f"y{m + 1}"]))
                error[k, m] = (float(r[f"sx{m + 1}"]), float(r[f"sy{m + 1}"]))
            if seen == "measured":
                streak[k, m] = float(r[f"streak{m + 1}"])
    dims = ("time", "mass", "coordinate")
    coords = {
        "time": ("time", np.array([float(r["t"]) for r in rows]), {"units": "s"}),
        "mass": ["upper", "lower"],
        "coordinate": ["x", "y"],
    }
    attrs = {
        k: (json.dumps(v) if isinstance(v, (list, dict)) else v)
        for k, v in summary.items()
        if v is not None
    }
    return xr.Dataset(
        {
            "position": (dims, position, {"units": "m", "long_name": "mean position over the exposure, from the pivot, y up"}),
            "error": (dims, error, {"units": "m", "long_name": "standard error: the sensor's noise's, or the model's where bridged"}),
            "measured": (("time", "mass"), measured),
            "bridged": (("time", "mass"), bridged),
            "streak": (("time", "mass"), streak, {"units": "m", "long_name": "distance moved during the exposure"}),
        },
        coords=coords,
        attrs=attrs,
    )
