"""What every benchmark script shares: target verdicts, package versions, percentiles.

The scripts run as ``python benchmarks/NAME.py``, so this folder is on
``sys.path`` and they import this module as ``common``.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from importlib import metadata

from rich.console import Console

__all__ = ["Target", "median", "package_version", "percentile", "print_targets"]


@dataclass(frozen=True, slots=True)
class Target:
    """A target of an issue and how this run fared: ``passed`` None = not measured."""

    name: str
    passed: bool | None
    detail: str


def print_targets(console: Console, targets: Iterable[Target]) -> None:
    """One PASS / FAIL / NOT MEASURED line per target."""
    for target in targets:
        verdict = {True: "PASS", False: "FAIL", None: "NOT MEASURED"}[target.passed]
        console.print(
            f"{target.name}: {verdict} — {target.detail}",
            style={True: "bold green", False: "bold red", None: "bold yellow"}[target.passed],
            highlight=False,
            markup=False,
        )


def package_version(distribution: str) -> str:
    """The installed version of ``distribution``, or ``not installed``."""
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return "not installed"


def median(values: Sequence[float]) -> float | None:
    """The median, or None for no values."""
    return statistics.median(values) if values else None


def percentile(values: Sequence[float], q: float) -> float | None:
    """The q-th percentile by linear interpolation between closest ranks (NumPy's
    default), or None for no values."""
    if not values:
        return None
    ordered = sorted(values)
    position = (len(ordered) - 1) * q / 100.0
    low, high = math.floor(position), math.ceil(position)
    return ordered[low] + (ordered[high] - ordered[low]) * (position - low)
