"""The thresholds of move detection (:mod:`demoplan.segmentation.detect`).

Apart from the detection itself, so that the command line can list them (and
read ``segment --set``) without importing NumPy.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, fields

from demoplan.errors import InputError
from demoplan.model import REST_TOLERANCE

__all__ = ["SegmentationSettings", "settings_from_text", "settings_help"]


@dataclass(frozen=True, slots=True)
class SegmentationSettings:
    """Thresholds of the move detection (module docstring); the defaults suit
    hand-carried table-top objects tracked at 30–120 Hz with up to ~3 mm noise.

    Attributes
    ----------
    speed_window_s : float
        Width of the speed estimate's window (s), default 0.4. Wider is less
        noisy but blurs the start and end of a move by about half of it.
    start_speed : float
        A move starts when the speed exceeds this (m/s), default 0.10. Hand
        carries peak at 0.3–1 m/s; sensor noise stays far below it.
    stop_speed : float
        A move ends when the speed falls below this (m/s), default 0.04; must be
        below ``start_speed`` (the hysteresis).
    min_rest_s : float
        Rest needed to end a move (s), default 0.5; shorter pauses are part of
        the move.
    min_distance : float
        Smallest displacement that makes a move a step (m), default 0.02 (2 cm).
        Smaller moves are nudges and not steps.
    min_angle_deg : float
        Smallest rotation that makes a move a step (degrees), default 20, for
        streams with orientations.
    pose_window_s : float
        Length of the start of a rest averaged into its pose (s), default 1.0.
    max_gap_s : float
        Gaps between samples longer than this (s), default 0.25, are checked for
        a move the tracker did not see.
    min_lift : float
        Height (m), default 0.01, an object must rise above where it rested for
        its move to be a step (or change its height by this much): a move
        along the support without it is a push, reported, not a step; a rest
        followed by a move that only lowers the object by at least this much
        was a pause in the air, not a placement.
    settle_radius : float
        At the end of the stream, the samples within this distance (m) of the
        last ones, default 0.01, are the final rest even when they are fewer
        than ``min_rest_s`` (a recording stopped right after a release).
    support_tolerance : float
        With geometry (``segment(..., geometry=...)``): a rest is on a support
        when the object's resting point is within this height (m), default
        0.01, of the table (z = 0) or of the top of an object or landmark
        beneath it; a rest above a known support and on none is a pause in
        the air.
    """

    speed_window_s: float = 0.4
    start_speed: float = 0.10
    stop_speed: float = 0.04
    min_rest_s: float = 0.5
    min_distance: float = 0.02
    min_angle_deg: float = 20.0
    pose_window_s: float = 1.0
    max_gap_s: float = 0.25
    min_lift: float = 0.01
    settle_radius: float = 0.01
    support_tolerance: float = REST_TOLERANCE

    def __post_init__(self) -> None:
        for item in fields(self):
            value = getattr(self, item.name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise InputError(
                    f"must be a positive number, got {value!r}", field=f"settings.{item.name}"
                )
        if self.stop_speed >= self.start_speed:
            raise InputError(
                f"must be below start_speed ({self.start_speed} m/s) for hysteresis, "
                f"got {self.stop_speed}",
                field="settings.stop_speed",
            )


def settings_from_text(assignments: Iterable[str]) -> SegmentationSettings:
    """Settings from ``NAME=VALUE`` texts (``segment --set min_lift=0.02``), the
    rest at their defaults; an unknown name or a bad value is an :class:`InputError`."""
    known = {f.name for f in fields(SegmentationSettings)}
    values: dict[str, float] = {}
    for text in assignments:
        name, sep, value = text.partition("=")
        name = name.strip().replace("-", "_")
        if not sep or name not in known:
            raise InputError(
                f"expected NAME=VALUE with NAME one of {', '.join(sorted(known))}, got {text!r}",
                field="--set",
            )
        try:
            values[name] = float(value)
        except ValueError:
            raise InputError(f"{name}: expected a number, got {value!r}", field="--set") from None
    return SegmentationSettings(**values)


def settings_help() -> str:
    """The thresholds and their defaults, for ``segment --help``."""
    defaults = SegmentationSettings()
    return ", ".join(f"{f.name}={getattr(defaults, f.name):g}" for f in fields(defaults))
