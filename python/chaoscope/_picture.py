"""A map's picture as the command line draws it: the same PNG, byte for byte."""

from __future__ import annotations

import os
from typing import Optional, Tuple, Union

import numpy as np
import xarray as xr

from . import _chaoscope as _native

Pair = Tuple[float, float]


class Picture:
    """A PNG as the command line writes it (``.png``: its bytes; a notebook shows it)."""

    def __init__(self, png: bytes):
        self.png = png

    def _repr_png_(self) -> bytes:
        return self.png

    def save(self, path: str) -> None:
        """Writes the PNG to ``path``, making its missing folders as the command line does."""
        folder = os.path.dirname(path)
        if folder:
            os.makedirs(folder, exist_ok=True)
        with open(path, "wb") as f:
            f.write(self.png)


def picture(
    map: Union[xr.DataArray, xr.Dataset],
    *,
    colormap: Optional[str] = None,
    annotate: bool = False,
    colour_range: Optional[Pair] = None,
    show_unresolved: bool = False,
) -> Picture:
    """The picture ``chaoscope flip``/``lyapunov`` would draw of a map made by
    :func:`flip_map` or :func:`lyapunov_map`: its colour map (``colormap``, the quantity's
    default otherwise), axes, colour bar and physics line (``annotate``, as ``--annotate``), ``colour_range`` (low, high) for
    the divergence family, unresolved pixels grey (``show_unresolved``, a Dataset with the
    verdict).
    """
    values = map["map"] if isinstance(map, xr.Dataset) else map
    resolved = map["resolved"].values if isinstance(map, xr.Dataset) else None
    if show_unresolved and resolved is None:
        raise ValueError("show_unresolved: the map has no verdict (make it with resolved=True)")
    return Picture(
        _native.picture(
            values.attrs["spec"],
            np.ascontiguousarray(values.values, dtype=np.float32),
            None if resolved is None else np.ascontiguousarray(resolved, dtype=np.uint8),
            values.attrs["command"],
            values.attrs["png_text"],
            values.attrs["rule"],
            colormap,
            annotate,
            None if colour_range is None else (float(colour_range[0]), float(colour_range[1])),
            show_unresolved,
        )
    )
