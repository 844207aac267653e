"""Words in messages: counted nouns (``1 replan``, ``2 replans``) and "did you mean"."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = ["did_you_mean", "plural"]


def plural(count: int, noun: str, many: str | None = None) -> str:
    """``count`` and ``noun``, in the plural unless ``count`` is 1 (``many`` where
    adding an s is wrong: ``plural(2, "candidate goal")``)."""
    return f"{count} {noun if count == 1 else many or noun + 's'}"


def did_you_mean(name: str, candidates: Iterable[str]) -> str:
    """``"; did you mean 'Tray'?"`` when one of ``candidates`` is ``name`` in
    other letter case, or a near spelling of it (difflib's ratio ≥ 0.75, case
    ignored); else ``""``. For an error line about an unknown name."""
    pool = [c for c in dict.fromkeys(candidates) if c != name]
    folded: dict[str, str] = {}
    for candidate in pool:
        folded.setdefault(candidate.casefold(), candidate)
    key = name.casefold()
    match = folded.get(key)
    if match is None:
        close = difflib.get_close_matches(key, list(folded), n=1, cutoff=0.75)
        match = folded[close[0]] if close else None
    return "" if match is None else f"; did you mean {match!r}?"
