"""Calling the Rust module with progress shown (shared by the public functions)."""

from __future__ import annotations

from typing import Any, Callable, Optional, Union

Progress = Union[None, bool, Callable[[str, int, Optional[int]], Any]]


def _reporter(progress: Progress):
    """A callback (phase, done, total) for the engine, and a function that closes it.

    None: a tqdm bar when tqdm is installed, silent otherwise; False: silent; a callable is
    called as it is.
    """
    if progress is False:
        return None, lambda: None
    if callable(progress):
        return progress, lambda: None
    if progress is not None and progress is not True:
        raise TypeError(
            f"progress: None, True, False or a callable (phase, done, total), not {type(progress).__name__}"
        )
    try:
        from tqdm.auto import tqdm
    except ImportError:
        if progress is True:
            raise
        return None, lambda: None
    bar: dict = {}

    def report(phase: str, done: int, total: Optional[int]) -> None:
        if bar.get("phase") != phase:
            if "bar" in bar:
                bar["bar"].close()
            bar["bar"] = tqdm(total=total, desc=phase or "chaoscope", leave=False)
            bar["phase"] = phase
        b = bar["bar"]
        if total is not None and b.total != total:
            b.total = total
        b.update(done - b.n)

    def close() -> None:
        if "bar" in bar:
            bar["bar"].close()

    return report, close


def _call(native, keywords: dict, progress: Progress):
    report, close = _reporter(progress)
    try:
        return native(keywords, report)
    finally:
        close()
