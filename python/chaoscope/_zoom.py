"""``chaoscope.zoom``: a film diving into a map's plane, its frames read back lazily."""

from __future__ import annotations

import inspect
import json
from pathlib import Path
from typing import Any, Iterable, Optional, Sequence, Tuple

import numpy as np
import pandas as pd
import xarray as xr
from xarray.backends import BackendArray
from xarray.core import indexing

from . import _chaoscope as _native
from ._run import Progress, _call

View = Tuple[float, float, float]

# A map's own files and shares: a zoom's frames are its files.
_NOT_IN_A_ZOOM = {
    "store": "a zoom writes its frames as PNGs into output",
    "tile": "a zoom's tile=(index, count) shares out frames: give it to zoom(), not the map",
    "resolved": "a zoom judges its frames with verdict=True (each frame's share in frames.csv)",
}


def zoom(
    to: Sequence[View] | View,
    *,
    map: str = "flip",
    frames: Optional[int] = None,
    fps: Optional[float] = None,
    crf: Optional[int] = None,
    output: Optional[str] = None,
    film: Optional[str] = None,
    tile: Optional[Tuple[int, int]] = None,
    verdict: bool = False,
    show_unresolved: bool = False,
    colour_range: Optional[Tuple[float, float]] = None,
    progress: Progress = None,
    **map_keywords: Any,
) -> xr.Dataset:
    """A film from a map's plane into the view ``to`` = (x, y, width) (``chaoscope zoom``):
    its centre on the map's axes and its width along x; a list of views is passed through in
    order. ``map`` is "flip" or "lyapunov", and ``map_keywords`` are that map's, as
    :func:`flip_map` or :func:`lyapunov_map` take them (``size``, ``t_max``, ``x``, ``theta1``,
    ``indicator``, ...): that map is the first frame. Widths shrink geometrically over
    ``frames`` frames (default 120); each frame runs in f32 while f32 resolves its step, then
    in f64; a zoom deeper than f64 resolves raises ValueError naming the end width.

    Frames go to ``output`` (default ``out/zoom``) as numbered PNGs (a call with the same
    settings keeps those already there: an interrupted zoom resumes), then the film
    (``film``, default ``output/zoom.mp4``, at ``fps`` (30) and ``crf`` (18)) and
    ``frames.csv``; a setting given as None takes the library's default, as the command's
    flag does. ``tile=(index, count)`` makes every count-th frame from index and no film
    (workers sharing one folder; a call without it then encodes). ``verdict`` judges every
    frame (``unresolved``); ``show_unresolved`` paints those pixels grey; ``colour_range``
    fixes a divergence map's colours (default: frame 0's range, for every frame).

    Returns a Dataset over ``frame``: ``image`` (frame x y x x x channel, uint8 RGB, read
    from the PNGs only when its values are asked for), and per frame the view's centre
    ``x_centre``/``y_centre``, ``width``, ``height``, the ``step`` between starts, the
    ``precision`` it ran in and, with ``verdict``, the ``unresolved`` share; the summary (the
    frame where f64 took over, seconds, files) in ``attrs``.
    """
    natives = {"flip": (_native.flip_map, _flip_map()), "lyapunov": (_native.lyapunov_map, _lyapunov_map())}
    if map not in natives:
        raise ValueError(f"map: {map!r} must be one of {sorted(natives)}")
    native, signature = natives[map]
    for key, why in _NOT_IN_A_ZOOM.items():
        if key in map_keywords:
            raise ValueError(f"{key}: {why}")
    try:
        bound = signature.bind(**map_keywords)
    except TypeError as e:
        raise TypeError(f"zoom() with map={map!r}: {e}") from None
    bound.apply_defaults()
    keywords = dict(bound.arguments)
    keywords.pop("progress", None)
    views = _views(to)
    keywords["colour_range"] = colour_range
    keywords["show_unresolved"] = show_unresolved
    keywords["zoom"] = {
        "to": views,
        "frames": frames,
        "fps": fps,
        "crf": crf,
        "output": None if output is None else str(output),
        "film": None if film is None else str(film),
        "tile": tile,
        "verdict": verdict,
    }
    summary = json.loads(_call(native, keywords, progress)["zoom"])
    return _frames(Path(summary["output"]), summary)


def _flip_map() -> inspect.Signature:
    from . import flip_map

    return inspect.signature(flip_map)


def _lyapunov_map() -> inspect.Signature:
    from . import lyapunov_map

    return inspect.signature(lyapunov_map)


def _views(to: Sequence[View] | View) -> list:
    bad = ValueError(f"to: {to!r} must be (x, y, width), or a list of them")
    try:
        if isinstance(to, (str, bytes)) or len(to) == 0:
            raise bad
    except TypeError:
        raise bad from None
    items: Iterable = [to] if len(to) == 3 and not isinstance(to[0], (tuple, list)) else to
    views = []
    for v in items:
        try:
            x, y, width = (float(c) for c in v)
        except (TypeError, ValueError):
            raise ValueError(f"to: {v!r} must be (x, y, width), or a list of them") from None
        views.append((x, y, width))
    return views


class _Frames(BackendArray):
    """The frames' RGB, read from their PNGs when indexed (one frame at a time)."""

    def __init__(self, paths: list, height: int, width: int):
        self.paths = paths
        self.shape = (len(paths), height, width, 3)
        self.dtype = np.dtype(np.uint8)

    def __getitem__(self, key: indexing.ExplicitIndexer) -> np.ndarray:
        return indexing.explicit_indexing_adapter(
            key, self.shape, indexing.IndexingSupport.BASIC, self._read
        )

    def _read(self, key: tuple) -> np.ndarray:
        frames = np.arange(self.shape[0])[key[0]]
        rest = key[1:]
        one = np.ndim(frames) == 0
        out = [self._frame(int(k))[rest] for k in np.atleast_1d(frames)]
        if one:
            return out[0]
        return np.stack(out) if out else np.zeros((0,) + self.shape[1:], np.uint8)[(slice(None),) + rest]

    def _frame(self, k: int) -> np.ndarray:
        width, height, rgb = _native.png_rgb(str(self.paths[k]))
        return np.frombuffer(rgb, dtype=np.uint8).reshape(height, width, 3)


def _frames(out: Path, summary: dict) -> xr.Dataset:
    plans = pd.DataFrame(summary["plans"])
    made = [k for k in plans["frame"] if (out / f"frame_{k:04d}.png").exists()]
    plans = plans.set_index("frame").loc[made]
    paths = [out / f"frame_{k:04d}.png" for k in made]
    height = width = 0
    if paths:
        width, height, _ = _native.png_rgb(str(paths[0]))
    image = xr.Variable(
        ("frame", "y", "x", "channel"),
        indexing.LazilyIndexedArray(_Frames(paths, height, width)),
        {"long_name": "the frame as drawn (RGB)"},
    )
    table = out / "frames.csv"
    unresolved = None
    if summary.get("film") and table.exists():
        csv = pd.read_csv(table, comment="#").set_index("frame")
        unresolved = csv["unresolved"].reindex(made).to_numpy(dtype=float)
    axes = summary.get("axes", ["x", "y"])
    coords = {
        "frame": ("frame", np.array(made, dtype=int)),
        "x_centre": ("frame", plans["x"].to_numpy(), {"long_name": f"the view's centre along {axes[0]}"}),
        "y_centre": ("frame", plans["y"].to_numpy(), {"long_name": f"the view's centre along {axes[1]}"}),
        "width": ("frame", plans["width"].to_numpy(), {"long_name": f"the view's width along {axes[0]}"}),
        "height": ("frame", plans["height"].to_numpy(), {"long_name": f"the view's height along {axes[1]}"}),
        "step": ("frame", plans["step"].to_numpy(), {"long_name": "the step between neighbouring starts along x"}),
        "precision": ("frame", plans["precision"].to_numpy(dtype=str)),
        "channel": ["r", "g", "b"],
    }
    data = {"image": image}
    if unresolved is not None and summary.get("unresolved_mean") is not None:
        data["unresolved"] = ("frame", unresolved, {"units": "1", "long_name": "share of the frame's pixels not resolved"})
    attrs = {
        k: (json.dumps(v) if isinstance(v, (list, dict)) else v)
        for k, v in summary.items()
        if v is not None and k != "plans"
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)
