"""Captions that fit their panel: a title broken into lines, word by word, so
that no line is wider than the cell of the figure it stands over (a
storyboard's failure reason runs longer than a frame is wide)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from demoplan.plotting.labels import figure_renderer

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.text import Text

__all__ = ["CELL_FRACTION", "LINES_WITH_ROOM", "fit_title", "grow_for_titles", "wrap_to_width"]

CELL_FRACTION = 0.9
"""The share of its cell's width a caption's widest line may take (the title
stands centred over its axes, which tick labels may move off the cell's middle)."""


LINES_WITH_ROOM = 2
"""Title lines a row of panels has room for at its figure's size; each line
more makes the figure taller by the line's height."""


def wrap_to_width(text: str, width: float, measure: Callable[[str], float]) -> str:
    """``text`` broken into lines that each ``measure`` at most ``width``: at
    spaces, and inside a word only where the word alone is wider (a line then
    holds at least one character). The line breaks of ``text`` are kept."""
    lines: list[str] = []
    for paragraph in text.split("\n"):
        line = ""
        for word in paragraph.split(" "):
            candidate = f"{line} {word}" if line else word
            if measure(candidate) <= width:
                line = candidate
                continue
            if line:
                lines.append(line)
            while len(word) > 1 and measure(word) > width:
                cut = max((k for k in range(1, len(word)) if measure(word[:k]) <= width), default=1)
                lines.append(word[:cut])
                word = word[cut:]
            line = word
        lines.append(line)
    return "\n".join(lines)


def fit_title(ax: Axes, text: str, **style: Any) -> Text:
    """``ax``'s title ``text`` (in ``style``: fontsize, colour…), its lines
    broken to fit :data:`CELL_FRACTION` of the width of ``ax``'s cell: its
    column's share of the figure (the whole figure for a lone axes)."""
    figure = ax.get_figure()
    assert figure is not None
    spec = ax.get_subplotspec()
    columns = spec.get_gridspec().ncols if spec is not None else 1
    width = figure.bbox.width / columns * CELL_FRACTION  # the column's slot, margins and all
    renderer = figure_renderer(figure)  # type: ignore[arg-type]
    title = ax.set_title("", **style)
    title.set_parse_math(False)  # as written (a name may hold "$"), as every figure's texts

    def measure(line: str) -> float:
        title.set_text(line)
        return float(title.get_window_extent(renderer).width)

    title.set_text(wrap_to_width(text, width, measure))
    return title


def grow_for_titles(figure: Any, rows: list[list[Axes]]) -> None:
    """Make ``figure`` taller by the title lines beyond :data:`LINES_WITH_ROOM`
    of each row's tallest title, so that its layout keeps the panels' size
    and the titles stay inside the figure."""
    extra = 0.0
    for row in rows:
        titles = [ax.title for ax in row if ax.get_visible()]
        beyond = [
            (t.get_text().count("\n") + 1 - LINES_WITH_ROOM) * float(t.get_fontsize()) * 1.2 / 72
            for t in titles
        ]
        extra += max([0.0, *beyond])  # inches
    if extra > 0:
        width, height = figure.get_size_inches()
        figure.set_size_inches(width, height + extra)
