"""How demoplan draws with matplotlib: one place, used by every figure
(plots, frames, storyboards, reports, behaviour trees, recordings).

Figures are drawn off-screen (Agg: no display is needed) and every text but
the tick labels is drawn as written (:func:`~demoplan.plotting.labels.literal_texts`):
object names come from users' files and may hold ``$``; matplotlib would read
``$\\sqrt{$`` as TeX and fail (a plot, a run's frames lost), and ``$x$`` would
show an italic x. Tick labels keep matplotlib's notation (a log axis writes
``$10^{2}$``). A figure's texts are made literal before anything measures them:
:func:`tight_layout` here, and the save (:func:`~demoplan.plotting.output.figure_bytes`).
"""

from __future__ import annotations

from typing import Any

__all__ = ["tight_layout", "use_agg"]


def use_agg() -> None:
    """matplotlib off-screen; raises ImportError without matplotlib (the ``plot`` extra)."""
    import matplotlib

    matplotlib.use("Agg")


def tight_layout(figure: Any) -> None:
    """``figure.tight_layout()``, its texts made literal first: laying a figure
    out measures every text, and a name holding TeX markup fails to measure.
    The figure keeps no layout engine: saving it draws it once."""
    import matplotlib

    from demoplan.plotting.labels import literal_texts

    literal_texts(figure)
    figure.tight_layout()
    # matplotlib keeps a placeholder layout engine after tight_layout, and a
    # figure with an engine is laid out again (a whole draw, unrendered)
    # before every savefig; the layout is done: no engine is kept, whatever
    # the rc settings would put in its place
    with matplotlib.rc_context(
        {"figure.autolayout": False, "figure.constrained_layout.use": False}
    ):
        figure.set_layout_engine(None)
