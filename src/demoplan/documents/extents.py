"""The extents every file's numbers are held to (docs/limits.md), apart from the
pose documents' models: ``demoplan perceive`` checks ``--side`` against them
without importing pydantic (a tenth of a second of its start-up)."""

from __future__ import annotations

__all__ = ["MAX_DISTANCE_M", "MAX_SIZE_M", "MIN_SIZE_M"]

MAX_DISTANCE_M = 1000.0
"""The farthest a position may lie from the origin on any axis: 1 km."""
MIN_SIZE_M = 1e-4
"""The smallest extent of an object: 0.1 mm."""
MAX_SIZE_M = 10.0
"""The largest extent of an object: 10 m."""
