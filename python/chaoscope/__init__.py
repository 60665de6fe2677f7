"""chaoscope: chaos in the double pendulum, millions of pendulums at once on the GPU.

The engine of the ``chaoscope`` command line, from Python: maps come back as
``xarray.DataArray`` (or ``xarray.Dataset`` with the verdict) with named dims, coordinates
and units, and carry the command line that reproduces them (``attrs["command"]``).

    >>> import chaoscope
    >>> flips = chaoscope.flip_map(size=256, t_max=10)
    >>> flips.sel(theta1=2.0, theta2=1.0, method="nearest")

Keywords are the spec's field names (``t_max``, ``theta1``, ``joint_damping``), SI units
throughout (rad, rad/s, s, kg, m); defaults equal the command line's. A bad value raises
ValueError naming its keyword, an unknown keyword TypeError; Ctrl-C stops a long map within
about a second (KeyboardInterrupt). Progress shows through tqdm when it is installed.
"""

from __future__ import annotations

import io
import json
import warnings
from pathlib import Path
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np
import pandas as pd
import xarray as xr

from . import _chaoscope as _native
from ._picture import Picture, picture
from ._run import Progress, _call
from ._fit import ModelWarning, fit, forecast
from ._track import track
from ._zoom import zoom

__version__: str = _native.__version__
__all__ = [
    "flip_map",
    "lyapunov_map",
    "trajectory",
    "fit",
    "forecast",
    "traces",
    "track",
    "zoom",
    "params",
    "picture",
    "open_store",
    "Picture",
    "INDICATORS",
    "ModelWarning",
]

#: The divergence-family maps' indicators (``lyapunov_map(indicator=...)``).
INDICATORS: Tuple[str, ...] = tuple(_native.INDICATORS)

Pair = Tuple[float, float]


def _as_xarray(answer: dict) -> Union[xr.DataArray, xr.Dataset]:
    """A map's answer as xarray: dims and coordinates named as its Zarr store names them.

    Built from variables whose data are known to be numpy (the map) and pandas indexes (the
    axes): xarray's generic path asks of any array whether it is a dask array, which imports
    dask where it is installed, 0.4-1.4 s on the first map of a process (the test: the result
    is identical to the generic constructor's).
    """
    x, y = answer["x"], answer["y"]
    dims = (y["name"], x["name"])
    coords = {
        axis["name"]: xr.IndexVariable(
            (axis["name"],),
            pd.Index(axis["values"]),
            {"units": axis["unit"], "long_name": f"{axis['label']} at the pixel centres"},
        )
        for axis in (y, x)
    }
    attrs = {
        "units": answer["unit"],
        "long_name": answer["quantity"],
        "command": answer["command"],
        "place": answer["place"],
        "png_text": [tuple(pair) for pair in answer["png_text"]],
        "rule": answer["rule"],
        "spec": answer["spec"],
        "start": dict(answer["start"]),
    }
    if answer["notices"]:
        # What the command line says on stderr (the CPU fallback, a precision taken over).
        attrs["notices"] = list(answer["notices"])
        for notice in answer["notices"]:
            warnings.warn(notice, RuntimeWarning, stacklevel=3)
    grid = xr.Variable(dims, answer["values"], attrs, fastpath=True)
    values = xr.DataArray(grid, coords=coords, name="map")
    if "resolved" not in answer:
        return values
    resolved = xr.DataArray(
        xr.Variable(dims, answer["resolved"], {"long_name": "1 where the pixel is resolved, 0 where not"}, fastpath=True)
    )
    return xr.Dataset({"map": values, "resolved": resolved}, attrs={"command": answer["command"]})


def _answer(answer: dict, store: Optional[str]) -> Union[xr.DataArray, xr.Dataset]:
    """A map made in memory as xarray, or the store it filled, opened lazily."""
    if store is None:
        return _as_xarray(answer)
    for notice in answer["notices"]:
        warnings.warn(notice, RuntimeWarning, stacklevel=3)
    opened = open_store(store)
    opened.attrs["filled"] = {k: answer[k] for k in ("pixels", "counted", "nan", "missing")}
    return opened


def params(preset: Optional[str] = None, *, params_file: Optional[str] = None, **overrides: Any) -> dict:
    """The pendulum's physics: ``preset`` ("lab": the lab report's apparatus) or a TOML
    ``params_file``, then ``overrides`` (m1, m2 in kg; l1, l2 in m; g in m/s^2; rod_mass,
    joint_damping in N m s as a pair or one value for both; air_drag, rho, cw, drag_area,
    rod_drag_area, bearing_friction, bearing_radius). Returns every value by the keyword the
    map functions take (``flip_map(**chaoscope.params("lab"))``).
    """
    known = {
        "m1", "m2", "l1", "l2", "g", "rod_mass", "joint_damping", "air_drag", "rho", "cw",
        "drag_area", "rod_drag_area", "bearing_friction", "bearing_radius",
    }
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise TypeError(f"params() got an unexpected keyword argument {unknown[0]!r}")
    return _native.params({"preset": preset, "params_file": params_file, **overrides})


def flip_map(
    *,
    size: Union[int, Tuple[int, int]] = 512,
    t_max: float = 30.0,
    dt: float = 0.01,
    x: Optional[str] = None,
    y: Optional[str] = None,
    x_range: Optional[Pair] = None,
    y_range: Optional[Pair] = None,
    theta1: Union[None, float, Pair] = None,
    theta2: Union[None, float, Pair] = None,
    omega1: Optional[float] = None,
    omega2: Optional[float] = None,
    m1: Optional[float] = None,
    m2: Optional[float] = None,
    l1: Optional[float] = None,
    l2: Optional[float] = None,
    g: Optional[float] = None,
    rod_mass: Union[None, float, Pair] = None,
    joint_damping: Union[None, float, Pair] = None,
    air_drag: bool = False,
    rho: Optional[float] = None,
    cw: Optional[float] = None,
    drag_area: Union[None, float, Pair] = None,
    rod_drag_area: Union[None, float, Pair] = None,
    bearing_friction: Optional[float] = None,
    bearing_radius: Optional[float] = None,
    preset: Optional[str] = None,
    params_file: Optional[str] = None,
    measure: str = "time",
    accurate: bool = False,
    resolved: bool = False,
    samples: int = 1,
    backend: str = "auto",
    precision: Optional[str] = None,
    integrator: Optional[str] = None,
    rtol: Optional[float] = None,
    atol: Optional[float] = None,
    use_symmetry: bool = True,
    early_exit: bool = True,
    store: Optional[str] = None,
    tile: Optional[Tuple[int, int]] = None,
    progress: Progress = None,
) -> Union[xr.DataArray, xr.Dataset]:
    """The flip map: for each pixel's start, the time (s) until an arm first flips over
    (``inf``: not within ``t_max``; NaN: the state left the numbers), or with
    ``measure="kind"`` which arm flipped first and which way (0 never, 1/2 upper past +pi/-pi,
    3/4 lower past +pi/-pi). ``chaoscope flip``'s map.

    The plane: ``x`` and ``y`` name what varies along them (theta1, omega1, theta2, omega2,
    m1, m2, m2/m1, l1, l2, l2/l1, g, damping, joint1, joint2, rod1, rod2; theta1 and theta2 by
    default) over ``x_range``/``y_range``; an angle along an axis takes its range from
    ``theta1=(lo, hi)`` (rad, default the whole turn), an angle along neither is the start's
    (``theta2=0.5``). ``size`` is N or (width, height) pixels, one pendulum each; ``t_max`` and
    ``dt`` in s. The physics as :func:`params`. ``accurate``: f64 and DP54 at 1e-9;
    ``resolved``: also the verdict (each pixel checked against finer runs), returning a Dataset
    with ``map`` and ``resolved``; ``samples``: N x N sub-samples a pixel (cost N^2).
    ``backend``: "auto" (the GPU when there is one, else the CPU with a notice), "gpu",
    "cpu"; ``precision``: "f32" (default) or "f64"; ``integrator``: "rk4", "dp54", "dop853"
    with ``rtol``/``atol``.

    Returns a DataArray (height x width, row 0 at the top: y's maximum) named ``map`` with
    coordinates named by the axes, ``attrs["command"]`` the command line that makes the same
    array bit for bit (``--data MAP.npy``). With ``store="MAP.zarr"`` the map goes to a Zarr
    store instead, band by band (memory holds one band; a map larger than memory), resumable,
    and only part ``tile=(index, count)`` of it when given (many workers, one map; see
    examples/dask_map.py); the store is returned opened lazily (:func:`open_store`).
    """
    keywords = dict(locals())
    keywords.pop("progress")
    return _answer(_call(_native.flip_map, keywords, progress), store)


def lyapunov_map(
    *,
    size: Union[int, Tuple[int, int]] = 512,
    t_max: float = 20.0,
    dt: float = 0.01,
    x: Optional[str] = None,
    y: Optional[str] = None,
    x_range: Optional[Pair] = None,
    y_range: Optional[Pair] = None,
    theta1: Union[None, float, Pair] = None,
    theta2: Union[None, float, Pair] = None,
    omega1: Optional[float] = None,
    omega2: Optional[float] = None,
    m1: Optional[float] = None,
    m2: Optional[float] = None,
    l1: Optional[float] = None,
    l2: Optional[float] = None,
    g: Optional[float] = None,
    rod_mass: Union[None, float, Pair] = None,
    joint_damping: Union[None, float, Pair] = None,
    air_drag: bool = False,
    rho: Optional[float] = None,
    cw: Optional[float] = None,
    drag_area: Union[None, float, Pair] = None,
    rod_drag_area: Union[None, float, Pair] = None,
    bearing_friction: Optional[float] = None,
    bearing_radius: Optional[float] = None,
    preset: Optional[str] = None,
    params_file: Optional[str] = None,
    indicator: str = "ftle",
    exponent: Optional[int] = None,
    gali: Optional[int] = None,
    threshold: Optional[float] = None,
    ld_p: Optional[float] = None,
    rli_delta: Optional[float] = None,
    method: str = "tangent",
    eps: float = 1e-8,
    renorm: float = 0.1,
    accurate: bool = False,
    resolved: bool = False,
    samples: int = 1,
    backend: str = "auto",
    precision: Optional[str] = None,
    integrator: Optional[str] = None,
    rtol: Optional[float] = None,
    atol: Optional[float] = None,
    use_symmetry: bool = True,
    store: Optional[str] = None,
    tile: Optional[Tuple[int, int]] = None,
    progress: Progress = None,
) -> Union[xr.DataArray, xr.Dataset]:
    """A divergence-family map (``chaoscope lyapunov``'s): by default the finite-time
    Lyapunov exponent (1/s) of each pixel's start; ``indicator`` one of :data:`INDICATORS`
    (an exponent of the spectrum with ``exponent=k``, 1 to 4 in Gram-Schmidt order: the first
    is the largest, the others are not sorted per pixel at a finite time; their sum, SALI/GALI and the time they
    take to fall below ``threshold``, MEGNO, the FLI, the Lagrangian descriptor with ``ld_p``,
    the orthogonal FLI, the relative Lyapunov indicator with its neighbour ``rli_delta`` away).
    ``method``: "tangent" (the variational equations) or "twin" (a neighbour ``eps`` away);
    tangent vectors renormalised every ``renorm`` s. The plane, physics, stepping and the rest
    as :func:`flip_map`.
    """
    keywords = dict(locals())
    keywords.pop("progress")
    return _answer(_call(_native.lyapunov_map, keywords, progress), store)


def trajectory(
    *,
    theta1: float,
    theta2: float,
    t_max: float,
    omega1: float = 0.0,
    omega2: float = 0.0,
    dt: float = 0.01,
    every: Optional[float] = None,
    m1: Optional[float] = None,
    m2: Optional[float] = None,
    l1: Optional[float] = None,
    l2: Optional[float] = None,
    g: Optional[float] = None,
    rod_mass: Union[None, float, Pair] = None,
    joint_damping: Union[None, float, Pair] = None,
    air_drag: bool = False,
    rho: Optional[float] = None,
    cw: Optional[float] = None,
    drag_area: Union[None, float, Pair] = None,
    rod_drag_area: Union[None, float, Pair] = None,
    bearing_friction: Optional[float] = None,
    bearing_radius: Optional[float] = None,
    preset: Optional[str] = None,
    params_file: Optional[str] = None,
    at: Optional[Dict[str, float]] = None,
    backend: str = "cpu",
    precision: Optional[str] = None,
    progress: Progress = False,
) -> xr.Dataset:
    """One start's trajectory (``chaoscope trajectory``'s CSV, CPU f64 by default): a Dataset
    over ``t`` (s; the CSV's column, each variable named as the CSV names it) with the angles (rad), angular velocities (rad/s), the bobs' positions
    (m, pivot at the origin, y up), the energy and the energy dissipated (J); a row every
    ``every`` s (every step by default). ``attrs["command"]`` reproduces the CSV. ``at``: a
    parameter plane's pixel, its axes' values by name (``{"m2/m1": 2.5}``), set as the map
    sets them (``trajectory --at``).

    A Dataset rather than a DataFrame: the maps are xarray, and time is a coordinate with a
    unit like their axes.
    """
    keywords = dict(locals())
    keywords.pop("progress")
    csv = _call(_native.trajectory, keywords, progress)
    lines = csv.splitlines()
    command = lines[0].removeprefix("# ")
    names = lines[1].split(",")
    table = np.loadtxt(io.StringIO("\n".join(lines[2:])), delimiter=",", ndmin=2)
    units = {
        "theta1": "rad", "theta2": "rad", "omega1": "rad/s", "omega2": "rad/s",
        "x1": "m", "y1": "m", "x2": "m", "y2": "m", "energy": "J", "dissipated": "J",
    }
    data = {
        name: ("t", table[:, k], {"units": units.get(name, "")})
        for k, name in enumerate(names)
        if name != "t"
    }
    return xr.Dataset(
        data,
        coords={"t": ("t", table[:, 0], {"units": "s", "long_name": "time"})},
        attrs={"command": command},
    )


def traces(
    *,
    theta1: float,
    theta2: float,
    omega1: float = 0.0,
    omega2: float = 0.0,
    runs: int = 3,
    spread: Union[float, str] = "5mm",
    exposure: float = 3.2,
    dt: float = 0.001,
    size: int = 1024,
    output: str = "out/traces.png",
    data: Optional[str] = None,
    m1: Optional[float] = None,
    m2: Optional[float] = None,
    l1: Optional[float] = None,
    l2: Optional[float] = None,
    g: Optional[float] = None,
    rod_mass: Union[None, float, Pair] = None,
    joint_damping: Union[None, float, Pair] = None,
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
) -> xr.DataArray:
    """An ensemble of releases from "the same" start (``chaoscope traces``): ``runs``
    pendulums released within ``spread`` (rad, or a length of the lower bob such as
    ``"5mm"``) of (``theta1``, ``theta2``), integrated for ``exposure`` s in steps of ``dt``
    on the engine. Returns their positions as an ``xarray.DataArray`` over (``run``, ``time``,
    ``coordinate``: x1, y1, x2, y2; m, pivot at the origin, y up), the light-trail picture
    written to ``output`` (``attrs["picture"]``; :class:`Picture` shows it) and the positions
    to ``data`` (a temporary .npy unless given). ``attrs["command"]`` reproduces both.
    """
    import tempfile

    keywords = dict(locals())
    keywords.pop("progress")
    keywords.pop("tempfile")
    with tempfile.TemporaryDirectory() as scratch:
        npy = data if data is not None else str(Path(scratch) / "traces.npy")
        keywords["data"] = npy
        summary = json.loads(_call(_native.traces, keywords, progress))
        positions = np.load(npy)
    steps = positions.shape[1]
    return xr.DataArray(
        positions,
        dims=("run", "time", "coordinate"),
        coords={
            "run": np.arange(positions.shape[0]),
            "time": ("time", np.arange(steps) * dt, {"units": "s"}),
            "coordinate": ["x1", "y1", "x2", "y2"],
        },
        name="position",
        attrs={
            "units": "m",
            "long_name": "bob positions (pivot at the origin, y up)",
            "command": summary["command"],
            "picture": str(summary["output"]),
        },
    )


def open_store(path: str) -> xr.Dataset:
    """A Zarr store written by ``chaoscope flip/lyapunov --data MAP.zarr`` (or many tasks
    over Slurm or Kubernetes), opened lazily with xarray: ``map`` (and ``resolved``) over the
    axes' coordinates; ``attrs["command"]`` the command that makes it. Needs zarr.
    """
    store = xr.open_zarr(path, consolidated=False)
    store.attrs["command"] = store.attrs.get("chaoscope:command", "")
    return store

