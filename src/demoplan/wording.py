"""Counted nouns in messages: ``1 replan``, ``2 replans``."""

from __future__ import annotations

__all__ = ["plural"]


def plural(count: int, noun: str, many: str | None = None) -> str:
    """``count`` and ``noun``, in the plural unless ``count`` is 1 (``many`` where
    adding an s is wrong: ``plural(2, "candidate goal")``)."""
    return f"{count} {noun if count == 1 else many or noun + 's'}"
