"""Words in messages: counted nouns (``1 replan``, ``2 replans``), "did you mean",
and names read from files made safe to show on a terminal."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = [
    "did_you_mean",
    "json_document",
    "plural",
    "printable",
    "printable_json",
    "printable_lines",
]


def printable(text: str) -> str:
    """``text`` with every character that is not printable — an escape
    sequence, a newline, a bidirectional override in a name read from a file —
    written as its escape (``\\x1b``, ``\\n``, ``\\u202e``), as the error line
    does (:func:`~demoplan.errors.error_line`): a name never drives the terminal."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def printable_lines(text: str) -> str:
    """:func:`printable` for text of several lines: its line breaks stay,
    every other character that is not printable (``\\r``, escape sequences,
    bidirectional overrides) is written as its escape. What demoplan's
    consoles write (:mod:`demoplan.cli.common`) goes through it, so a name
    printed anywhere — a table cell, a plan's actions — never drives the terminal."""
    return "\n".join(printable(line) for line in text.split("\n"))


def json_document(data: object) -> str:
    """``data`` as a command prints it with ``--json``: indented, non-ASCII kept,
    NaN refused (ValueError), every character that is not printable escaped
    (:func:`printable_json`), a line break at the end."""
    import json

    return printable_json(json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False)) + "\n"


def printable_json(text: str) -> str:
    """JSON text with every character that is not printable (but line breaks)
    written as a ``\\uXXXX`` escape: the same document (such characters
    stand only inside its strings), safe on a terminal. ``json.dumps``
    escapes only the C0 controls; this also catches DEL, the C1 controls
    (``\\x9b`` starts an escape sequence on some terminals) and bidirectional
    overrides."""

    def escaped(c: str) -> str:
        code = ord(c)
        if code <= 0xFFFF:
            return f"\\u{code:04x}"
        code -= 0x10000  # a UTF-16 surrogate pair, as JSON spells it
        return f"\\u{0xD800 + (code >> 10):04x}\\u{0xDC00 + (code & 0x3FF):04x}"

    return "".join(c if c.isprintable() or c == "\n" else escaped(c) for c in text)


def plural(count: int, noun: str, many: str | None = None) -> str:
    """``count`` and ``noun``, in the plural unless ``count`` is 1 (``many`` where
    adding an s is wrong: ``plural(2, "candidate goal")``)."""
    return f"{count} {noun if count == 1 else many or noun + 's'}"


def did_you_mean(name: str, candidates: Iterable[str]) -> str:
    """``"; did you mean 'Tray'?"`` when one of ``candidates`` is ``name`` in
    other letter case, or a near spelling of it (difflib's ratio ≥ 0.75, or
    two neighbouring letters swapped — ``mgu`` for ``mug``, whose ratio is
    only 2/3; case ignored); else ``""``. For an error line about an unknown
    name."""
    pool = [c for c in dict.fromkeys(candidates) if c != name]
    folded: dict[str, str] = {}
    for candidate in pool:
        folded.setdefault(candidate.casefold(), candidate)
    key = name.casefold()
    match = folded.get(key)
    if match is None:
        close = difflib.get_close_matches(key, list(folded), n=1, cutoff=0.75)
        swapped = [c for c in folded if _neighbours_swapped(key, c)]
        match = folded[close[0]] if close else folded[swapped[0]] if swapped else None
    return "" if match is None else f"; did you mean {match!r}?"


def _neighbours_swapped(typed: str, meant: str) -> bool:
    """Whether ``typed`` is ``meant`` with two neighbouring letters swapped."""
    if len(typed) != len(meant):
        return False
    differ = [k for k, (a, b) in enumerate(zip(typed, meant, strict=True)) if a != b]
    return (
        len(differ) == 2
        and differ[1] == differ[0] + 1
        and typed[differ[0]] == meant[differ[1]]
        and typed[differ[1]] == meant[differ[0]]
    )
