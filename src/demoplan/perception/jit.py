"""Functions compiled to machine code with numba, typed for mypy.

Perception's inner loops (the square fit's steps, the Hough vote's counts) run over
thousands of pixels thousands of times per photograph: written as loops and
compiled, one pass replaces dozens of NumPy calls whose overhead was their time.
numba compiles a function on its first call for the types it is given (about
1.5 s of CPU for perception's kernels) and caches the machine code on disk, so a
machine compiles them once and later processes load them (about 0.3 s of CPU for
numba's start in each process that fits a square).

The cache is a library cache like fontconfig's, never in the source tree (numba's
default, beside the module, would write into the installed package on every
import): ``$NUMBA_CACHE_DIR`` where the user set it, else
``$XDG_CACHE_HOME/demoplan/numba`` (``~/.cache/demoplan/numba``).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

import numba
import numba.core.config

_config: Any = numba.core.config  # its settings are made at run time (no types)

__all__ = ["cache_folder", "compiled"]

Function = TypeVar("Function", bound=Callable[..., Any])


def cache_folder() -> Path:
    """Where the compiled code is cached when ``NUMBA_CACHE_DIR`` is not set."""
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "demoplan" / "numba"


def compiled(function: Function) -> Function:
    """``function`` compiled (``numba.njit``) on its first call, cached on disk
    (:func:`cache_folder`, unless ``NUMBA_CACHE_DIR`` names another)."""
    chosen = _config.CACHE_DIR
    if not chosen:
        # numba's cache locator reads the setting when the function is wrapped and
        # keeps its folder: set for this function alone, not for other numba users
        _config.CACHE_DIR = os.fspath(cache_folder())
    try:
        return cast(Function, numba.njit(cache=True, nogil=True)(function))
    finally:
        _config.CACHE_DIR = chosen
