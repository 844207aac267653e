"""Plots: they draw what the model says."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

from demoplan import TaskModelLearner, load_demonstrations
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.plotting.figures import plot_constraints, plot_demonstration
from tests.support.helpers import EXAMPLES


def test_fig_2_transitive_reduction() -> None:
    """Fig. 2's nine constraints reduce to the five arrows the figure draws."""
    from demoplan.learning.constraints import goal_order, learn_constraints

    constraints = learn_constraints(["ABEFG", "AEBFG"]).constraints
    order = goal_order("ABEFG", constraints)
    assert order.drawn == {("A", "B"), ("A", "E"), ("B", "F"), ("E", "F"), ("F", "G")}
    assert order.implied == frozenset()


def test_plots_draw_every_state_and_step() -> None:
    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    model = TaskModelLearner(PAPER_SETTINGS).fit(demos).model_  # Table IV (the data's reading)
    ax = plot_constraints(model, 0)
    texts = {t.get_text() for t in ax.texts}
    assert {"A", "B", "C"} <= texts and "D" not in texts  # demonstration 1: A-B-C
    assert ax.get_title() == "3 constraints here: 2 drawn, the rest are paths"
    ax = plot_demonstration(demos[0])
    assert len(ax.patches) == len(demos[0].initial) + len(demos[0].steps)
    assert {"1 wood", "2 green", "3 red"} <= {t.get_text() for t in ax.texts}
    plt.close("all")


def test_side_by_side_demonstrations_share_their_axis_ranges() -> None:
    """The experiments' demonstration panels: one range for all, covering each."""
    from demoplan.plotting.figures import share_limits

    demos = load_demonstrations([EXAMPLES / "set_table"])
    figure, axes = plt.subplots(1, len(demos))
    own = []
    for ax, demo in zip(axes, demos, strict=True):
        plot_demonstration(demo, ax)
        own.append((ax.get_xlim(), ax.get_ylim()))
    assert len({limits for limits in own}) > 1  # they differed before
    share_limits(list(axes))
    shared = {(ax.get_xlim(), ax.get_ylim()) for ax in axes}
    assert len(shared) == 1
    ((x_low, x_high), (y_low, y_high)) = shared.pop()
    for (xl, xh), (yl, yh) in own:
        assert x_low <= xl and xh <= x_high and y_low <= yl and yh <= y_high
    plt.close(figure)


def test_top_views_carry_a_legend_of_their_marks() -> None:
    """Faint and solid shapes, arrows and dashed circles are explained in the figure."""
    from demoplan import load_scene, plan
    from demoplan.plotting.figures import plot_scene_plan
    from demoplan.scenes.scene import complete_geometry

    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    ax = plot_demonstration(demos[0])
    legend = ax.get_legend()
    assert legend is not None
    assert [t.get_text() for t in legend.get_texts()] == [
        "where the objects stood",
        "where step n put them",
        "the move of step n",
    ]
    model = TaskModelLearner(PAPER_SETTINGS).fit(demos).model_
    scene = load_scene(EXAMPLES / "scenes" / "pyramid-fig4.json")
    result = plan(model, scene)
    ax = plot_scene_plan(complete_geometry(scene, model), result.chosen.problem, result.chosen.plan)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts == [
        "where the objects stand now",
        "where the plan leaves them",
        "move n of the plan",
        "free-space spot",
    ]
    plt.close("all")
