"""literal_texts walks a figure without making its axes' ticks: every text a
full walk of the figure (``findobj``) finds is made literal, but the tick
labels and the axes' offset texts, whatever the figure holds."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.plotting.labels import add_label, literal_texts

pytest.importorskip("matplotlib")

PARTS = st.fixed_dictionaries(
    {
        "rows": st.integers(1, 2),
        "columns": st.integers(1, 3),
        "title": st.booleans(),
        "axis_labels": st.booleans(),
        "legend": st.booleans(),
        "labels": st.integers(0, 3),
        "log": st.booleans(),
        "axis_off": st.booleans(),
        "twin": st.booleans(),
        "figure_text": st.booleans(),
        "hidden": st.booleans(),
    }
)


def _figure(parts: dict[str, Any]) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure()
    FigureCanvasAgg(figure)
    axes = figure.subplots(parts["rows"], parts["columns"], squeeze=False).flat
    for k, ax in enumerate(axes):
        ax.plot([1, 10, 100], [1, 2, 3], label="$x^2$ line")
        if parts["title"]:
            ax.set_title(f"$\\sqrt{{x$ {k}")
        if parts["axis_labels"]:
            ax.set_xlabel("$a$")
            ax.set_ylabel("50$-and-60$")
        if parts["legend"]:
            ax.legend(title="$t$")
        for n in range(parts["labels"]):
            add_label(ax, f"$n{n}$", (10.0 * n, 2.0))
        if parts["log"]:
            ax.set_xscale("log")
        if parts["axis_off"] and k == 0:
            ax.set_axis_off()
        if parts["hidden"] and k == 1:
            ax.set_visible(False)
    if parts["twin"]:
        next(iter(figure.axes)).twinx().set_ylabel("$y$")
    if parts["figure_text"]:
        figure.suptitle("$s$")
        figure.text(0.1, 0.1, "$f$")
    return figure


@settings(max_examples=25, deadline=None)
@given(PARTS)
def test_every_text_but_the_ticks_is_made_literal(parts: dict[str, Any]) -> None:
    from matplotlib.text import Text

    figure = _figure(parts)
    literal_texts(figure)
    ticks = set()
    texts = figure.findobj(Text)  # the full walk: it makes the ticks
    for ax in figure.axes:
        for axis in (ax.xaxis, ax.yaxis):
            ticks.add(id(axis.offsetText))
            for tick in [*axis.majorTicks, *axis.minorTicks]:
                ticks.update((id(tick.label1), id(tick.label2)))
    others = [t for t in texts if id(t) not in ticks]
    assert others
    assert all(not t.get_parse_math() and not t.get_usetex() for t in others)
    assert all(t.get_parse_math() for t in texts if id(t) in ticks)


def test_an_axis_off_keeps_no_ticks_made() -> None:
    """An axes never drawn with its axis gets no ticks from being made literal."""
    figure = _figure(
        {
            "rows": 1,
            "columns": 1,
            "title": True,
            "axis_labels": False,
            "legend": False,
            "labels": 1,
            "log": False,
            "axis_off": True,
            "twin": False,
            "figure_text": False,
            "hidden": False,
        }
    )
    (ax,) = figure.axes
    made = len(ax.xaxis.majorTicks) + len(ax.yaxis.majorTicks)
    literal_texts(figure)
    assert len(ax.xaxis.majorTicks) + len(ax.yaxis.majorTicks) == made
    assert not ax.title.get_parse_math()
