"""Type stubs of the Rust module (python/src/lib.rs); the public API is chaoscope/__init__.py."""

from typing import Any, Callable, Optional

import numpy as np

__version__: str
INDICATORS: list[str]

Progress = Optional[Callable[[str, int, Optional[int]], Any]]

def flip_map(keywords: dict[str, Any], progress: Progress = None) -> dict[str, Any]: ...
def lyapunov_map(keywords: dict[str, Any], progress: Progress = None) -> dict[str, Any]: ...
def trajectory(keywords: dict[str, Any], progress: Progress = None) -> str: ...
def fit(keywords: dict[str, Any], progress: Progress = None) -> str: ...
def forecast(keywords: dict[str, Any], progress: Progress = None) -> str: ...
def traces(keywords: dict[str, Any], progress: Progress = None) -> str: ...
def params(keywords: dict[str, Any]) -> dict[str, Any]: ...
def picture(
    spec: str,
    values: np.ndarray,
    resolved: Optional[np.ndarray],
    command: str,
    png_text: list[tuple[str, str]],
    rule: str,
    colormap: Optional[str] = None,
    annotate: bool = False,
    colour_range: Optional[tuple[float, float]] = None,
    show_unresolved: bool = False,
) -> bytes: ...
def main(args: list[str]) -> int: ...
