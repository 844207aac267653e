"""One colour per object in every figure and render of a run (issue: the glass
was red in one figure and green in another; objects not named after a colour
rendered grey in MuJoCo)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.colors import to_hex

from demoplan.colours import NAMED, object_colour, object_rgba
from demoplan.learning.demonstrations import load_demonstrations
from demoplan.plotting import plot_demonstration
from tests.helpers import EXAMPLES


def test_an_object_has_one_colour_in_every_demonstration_figure() -> None:
    """The three set-table demonstrations move the objects in different orders;
    the placed objects' fills in each figure are exactly their colours from
    demoplan.colours (one source for every figure), distinct within a figure."""
    demos = load_demonstrations([EXAMPLES / "set_table"])
    for demo in demos:
        ax = plot_demonstration(demo)
        colours = {step.object: object_colour(step.object) for step in demo.steps}
        assert len(set(colours.values())) == len(colours)  # distinct within a figure
        fills = {
            to_hex(patch.get_facecolor())
            for patch in ax.patches
            if patch.get_alpha() is not None and patch.get_alpha() > 0.5
        }
        assert fills == set(colours.values())
        plt.close("all")


def test_named_colours_and_mujoco_rgba_agree() -> None:
    assert object_colour("red") == NAMED["red"]
    red, green, blue, alpha = (float(v) for v in object_rgba("glass").split())
    assert to_hex((red, green, blue)) == object_colour("glass") and alpha == 1.0
    assert object_colour("glass") == object_colour("glass")
    assert object_rgba("fork") != "0.6 0.6 0.7 1"  # no longer every plain name grey
