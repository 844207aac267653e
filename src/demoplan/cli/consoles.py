"""The console class every command prints with, apart from typer: the lean
``perceive`` path (:mod:`demoplan.cli.perceiving`) renders its table with it
without importing the typer application."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from rich.console import Console
from rich.segment import Segment
from rich.text import Text

__all__ = ["TextConsole", "plain_text"]


class TextConsole(Console):
    """A console whose text is text: every character of what it prints that
    is not printable (an escape sequence, ``\\r``, a bidirectional override in
    an object, a TF frame or an HDF5 key) is written as its escape
    (:func:`~demoplan.wording.printable_lines`); only rich's own styles and
    cursor controls reach the terminal as such."""

    def render_str(self, text: str, **options: Any) -> Text:
        """A string printed or put in a table, its control characters escaped
        before rich would drop some of them silently (``\\r``, ``\\b``)."""
        from demoplan.wording import printable_lines

        return super().render_str(printable_lines(text), **options)

    def _render_buffer(self, buffer: Iterable[Segment]) -> str:
        from demoplan.wording import printable_lines

        return super()._render_buffer(
            segment if segment.control else Segment(printable_lines(segment.text), segment.style)
            for segment in buffer
        )


def plain_text(text: str) -> Text:
    """A name or a line (a table cell) as rich text, shown as written: no
    markup, and its control characters, newlines included, escaped
    (:func:`~demoplan.wording.printable`) before rich would drop ``\\r`` or
    ``\\b`` silently."""
    from demoplan.wording import printable

    return Text(printable(text))
