"""One colour per object in every figure and render of a run (issue: the glass
was red in one figure and green in another; objects not named after a colour
rendered grey in MuJoCo)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.colors import to_hex

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.plotting.colours import (
    CYCLE,
    INK_LUMINANCE,
    NAMED,
    assign_colours,
    ink,
    luminance,
    object_colour,
    rgba,
)
from demoplan.plotting.figures import plot_demonstration
from tests.support.helpers import EXAMPLES


def test_an_object_has_one_colour_in_every_demonstration_figure() -> None:
    """The three set-table demonstrations move the objects in different orders;
    the placed objects' fills in each figure are exactly their colours from
    demoplan.plotting.colours (one source for every figure), distinct within a figure."""
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
    red, green, blue, alpha = (float(v) for v in rgba(object_colour("glass")).split())
    assert to_hex((red, green, blue)) == object_colour("glass") and alpha == 1.0
    assert rgba(object_colour("fork")) != "0.6 0.6 0.7 1"  # no longer every plain name grey


names_strategy = st.lists(
    st.text(alphabet="abcdefghijklmnopqrstuvwxyz_0123456789", min_size=1, max_size=12),
    min_size=1,
    max_size=len(CYCLE),
    unique=True,
)


@settings(max_examples=200, deadline=None)
@given(names_strategy, st.randoms(use_true_random=False))
def test_a_tasks_colours_are_distinct_and_do_not_depend_on_order(
    names: list[str], shuffle: Any
) -> None:
    """However the objects of a task come (learn's figure, plan's, run's
    frames), they get the same colours, distinct where the cycle allows."""
    first = assign_colours(names)
    again = list(names)
    shuffle.shuffle(again)
    for name in again:  # drawn one by one, in another order, before anything else
        object_colour(name)
    assert assign_colours(again) == first
    plain = [n for n in names if n not in NAMED]
    assert len({first[n] for n in plain}) == len(plain)
    assert all(object_colour(n) == first[n] for n in names)


def test_colours_are_the_same_in_another_process() -> None:
    """A command drawing the plan and another drawing the frames agree: the
    colour comes from the names, not from what a process drew first."""
    task = ["motor", "pcb", "screws", "cable", "manual"]
    code = (
        "from demoplan.plotting.colours import object_colour\n"
        "print(object_colour('zebra'))\n"
        "from demoplan.plotting.colours import assign_colours\n"
        f"print(sorted(assign_colours({list(reversed(task))!r}).items()))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    lines = done.stdout.splitlines()
    assert lines[0] == object_colour("zebra")
    assert lines[1] == str(sorted(assign_colours(task).items()))


def test_numbered_instances_of_a_colour_get_that_colour() -> None:
    """Identical blocks as perception (``red2``) and learning (``red#2``) name them."""
    from demoplan.plotting.colours import NAMED, assign_colours, object_colour

    for name in ("red2", "red-2", "red#2", "wood#1"):
        assert object_colour(name) == NAMED[name.rstrip("0123456789").rstrip("-#")]
    assigned = assign_colours(["red", "red2", "plate#1", "plate#2"])
    assert assigned["red"] == assigned["red2"] == NAMED["red"]
    assert assigned["plate#1"] != assigned["plate#2"]


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 0xFFFFFF))
def test_ink_is_the_colour_itself_or_the_same_hue_dark_enough_to_see_on_white(code: int) -> None:
    colour = f"#{code:06x}"
    drawn = ink(colour)
    assert luminance(drawn) <= INK_LUMINANCE + 1e-9
    if luminance(colour) <= INK_LUMINANCE:
        assert drawn == colour
    else:  # each channel scaled alike: the same hue, darker
        before = [int(colour[k : k + 2], 16) for k in (1, 3, 5)]
        after = [int(drawn[k : k + 2], 16) for k in (1, 3, 5)]
        scale = max(after) / max(before)
        assert all(abs(b * scale - a) <= 1.0 for b, a in zip(before, after, strict=True))
        assert luminance(drawn) > INK_LUMINANCE - 0.02  # no darker than it must be


def test_a_white_mugs_moves_are_drawn_dark_enough_to_see_from_above_and_from_the_side() -> None:
    """A new user's desk (tests/data/desk) with a mug the user made white
    (#ecf0f1): its move's arrow and number in the plan figure and the side
    view were white on white. Every arrow and number of a move is now at most
    INK_LUMINANCE; the mug's own patches keep its colour."""
    import demoplan
    from demoplan.plotting.figures import plot_scene_plan
    from demoplan.plotting.side_view import plot_scene_side

    desk = Path(__file__).resolve().parents[1] / "data" / "desk"
    model = demoplan.learn([desk / f"desk-{k}.json" for k in (1, 2, 3)])
    result = demoplan.plan(model, desk / "new-desk.json")
    chosen = result.chosen
    _, (top, side) = plt.subplots(1, 2)
    plot_scene_plan(result.scene, chosen.problem, chosen.plan, top)
    plot_scene_side(result.scene, chosen.problem, chosen.plan, side)
    for ax in (top, side):
        arrows = [text.arrow_patch for text in ax.texts if getattr(text, "arrow_patch", None)]
        numbers = [text for text in ax.texts if text.get_text().isdigit()]
        assert len(arrows) == 5 and len(numbers) == 5
        drawn = [to_hex(a.get_edgecolor()) for a in arrows] + [
            to_hex(t.get_color()) for t in numbers
        ]
        assert max(luminance(colour) for colour in drawn) <= INK_LUMINANCE, drawn
        assert ink("#ecf0f1") in drawn  # the mug's, darkened
    assert "#ecf0f1" in {to_hex(patch.get_facecolor()) for patch in top.patches}
    # where there is no plan: the targets as dashed outlines, the mug's too
    from demoplan.plotting.figures import plot_scene_targets

    ax = plot_scene_targets(result.scene, chosen.problem, "no plan")
    dashed = [p for p in ax.patches if p.get_linestyle() == "--" and p.get_fill() is False]
    outlines = [to_hex(p.get_edgecolor()) for p in dashed if to_hex(p.get_edgecolor()) != "#999999"]
    assert ink("#ecf0f1") in outlines, outlines
    assert max(luminance(colour) for colour in outlines) <= INK_LUMINANCE, outlines
    plt.close("all")


def test_a_white_mugs_target_outline_is_drawn_dark_enough_to_see_in_run_frames(
    tmp_path: Path,
) -> None:
    """``run --frames`` (kinematic) draws each target as a dashed outline in its
    object's colour: the white mug's was white on white. Its outline now at
    most INK_LUMINANCE; the mug itself still in its own colour."""
    from demoplan.execution.frames import FrameWriter
    from demoplan.execution.world import Observation
    from demoplan.model import ObjectGeometry, Pose
    from demoplan.scenes.scene import scene_from_document

    mug = ObjectGeometry("cylinder", (0.08, 0.08, 0.1))
    scene = scene_from_document(
        {
            "format": "demoplan/scene-1",
            "objects": {
                "mug": {"position": [0.6, 0.1, 0.0], "size": [0.08, 0.08, 0.1]}
                | {"shape": "cylinder", "colour": "#ecf0f1"}
            },
        },
        "desk.json",
    )
    writer = FrameWriter(tmp_path, {"mug": Pose((0.3, 0.4, 0.0))}, scene)
    standing = Observation({"mug": Pose((0.6, 0.1, 0.0))}, None, {"mug": mug})
    writer.capture(standing, "start")
    assert writer._frame is not None
    patches = writer._frame.ax.patches
    dashed = [p for p in patches if p.get_linestyle() == "--"]
    assert len(dashed) == 1
    assert luminance(to_hex(dashed[0].get_edgecolor())) <= INK_LUMINANCE
    assert "#ecf0f1" in {to_hex(p.get_facecolor()) for p in patches}
    plt.close("all")


def test_a_constraint_arrow_passes_through_no_other_state_in_the_figure() -> None:
    """The desk's constraints A<B, B<E, C<E, D<E: C, B and E stand on one row
    of the layered graph (show --plot, the report), and C → E was drawn
    straight through B, read as 'the book before the phone'. Each arrow now
    keeps off every state but its own two."""
    import demoplan
    from demoplan.plotting.figures import plot_constraints

    desk = Path(__file__).resolve().parents[1] / "data" / "desk"
    model = demoplan.learn([desk / f"desk-{k}.json" for k in (1, 2, 3)])
    figure, ax = plt.subplots(figsize=(6, 3))
    plot_constraints(model, 0, ax)
    figure.canvas.draw()
    centres = {
        text.get_text(): ax.transData.transform(text.xy)
        for text in ax.texts
        if text.get_bbox_patch() is not None
    }
    assert sorted(centres) == ["A", "B", "C", "D", "E"]
    crossed = []
    for text in ax.texts:
        arrow = getattr(text, "arrow_patch", None)
        if arrow is None:
            continue
        tail, head = ax.transData.transform(text.xyann), ax.transData.transform(text.xy)
        start = min(centres, key=lambda n: float(np.hypot(*(centres[n] - tail))))
        end = min(centres, key=lambda n: float(np.hypot(*(centres[n] - head))))
        path = arrow.get_path().interpolated(40).vertices  # display coordinates
        for name, centre in centres.items():
            near = min(float(np.hypot(*(p - centre))) for p in path) < 11  # within its circle
            if near and name not in (start, end):
                crossed.append(f"{start} -> {end} through {name}")
    assert crossed == []
    plt.close(figure)
