"""How demoplan draws with matplotlib: one place, called before every figure
(plots, frames, storyboards, reports, behaviour trees, recordings).

Figures are drawn off-screen (Agg: no display is needed) and every text is
drawn as written. Object names come from users' files and may hold ``$``:
matplotlib would read ``$\\sqrt{$`` as TeX and fail (a plot, a run's frames
lost), and ``$x$`` would show an italic x. Text objects take this setting
when they are made, so it holds for titles, labels, legends and annotations
alike — and for measuring them (``tight_layout``) before a figure is saved.
"""

from __future__ import annotations

__all__ = ["use_agg"]


def use_agg() -> None:
    """matplotlib off-screen, every text literal (module docstring); raises
    ImportError without matplotlib (the ``plot`` extra)."""
    import matplotlib

    matplotlib.use("Agg")
    matplotlib.rcParams["text.parse_math"] = False
    matplotlib.rcParams["text.usetex"] = False
