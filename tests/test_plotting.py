"""Plots: they draw what the model says."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

from demoplan import TaskModelLearner, load_demonstrations
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.plotting import (
    _transitive_reduction,
    plot_constraints,
    plot_demonstration,
)
from tests.helpers import EXAMPLES


def test_fig_2_transitive_reduction() -> None:
    """Fig. 2's nine constraints reduce to the five arrows the figure draws."""
    from demoplan.learning.constraints import learn_constraints

    edges = set(learn_constraints(["ABEFG", "AEBFG"]).constraints)
    assert _transitive_reduction(list("ABEFG"), edges) == {
        ("A", "B"),
        ("A", "E"),
        ("B", "F"),
        ("E", "F"),
        ("F", "G"),
    }


def test_plots_draw_every_state_and_step() -> None:
    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    model = TaskModelLearner(PAPER_SETTINGS).fit(demos).model_  # Table IV (the data's reading)
    ax = plot_constraints(model)
    texts = {t.get_text() for t in ax.texts}
    assert {"A", "B", "C", "D"} <= texts
    assert "5 constraints" in ax.get_title()
    ax = plot_demonstration(demos[0])
    assert len(ax.patches) == len(demos[0].initial) + len(demos[0].steps)
    assert {"1 wood", "2 green", "3 red"} <= {t.get_text() for t in ax.texts}
    plt.close("all")
