"""A time budget for learning: state generation reads it between cluster counts.

Learning is bounded by the data (demonstrations × objects × candidate
references × cluster counts), and on thousands of scattered placements the
paper's full scan of the cluster count takes minutes. :func:`time_budget`
sets a deadline for the code run inside it; :func:`check_time` raises
:class:`~demoplan.errors.LimitReachedError` (exit 4) once it has passed,
saying how to give more. Without a budget nothing is checked.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

from demoplan.errors import LimitReachedError

__all__ = ["check_time", "time_budget"]

_deadline: ContextVar[tuple[float, str] | None] = ContextVar("learning_deadline", default=None)


@contextmanager
def time_budget(seconds: float | None, how_to_raise: str = "--timeout") -> Iterator[None]:
    """Learning inside the block stops after ``seconds`` (None: no limit);
    ``how_to_raise`` is what the message tells the user to change."""
    if seconds is None or seconds == float("inf"):
        yield
        return
    token = _deadline.set((time.monotonic() + seconds, f"{how_to_raise} {seconds:g} s"))
    try:
        yield
    finally:
        _deadline.reset(token)


def check_time() -> None:
    """Raise LimitReachedError if the current budget is spent."""
    budget = _deadline.get()
    if budget is not None and time.monotonic() > budget[0]:
        raise LimitReachedError(
            f"learning stopped at its time budget ({budget[1]}); give it more time, or for "
            "many scattered placements cap the clusters per object (--max-clusters 5)"
        )
