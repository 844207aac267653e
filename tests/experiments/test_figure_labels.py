"""Figures: labels placed without overlap, inside their axes (issue 15), and the
side view that shows Experiment 2's unstacking.

The figures `demoplan experiments` writes are checked as they are written
(demoplan.plotting.observing_saved_figures: the figure at the dpi of the file,
its labels placed); the placement itself (place_boxes) on generated crowded
scenes.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

matplotlib.use("Agg")

from matplotlib.transforms import Bbox

from demoplan.plotting.colours import object_colour
from demoplan.plotting.figures import Leader, place_boxes
from demoplan.plotting.output import observing_saved_figures
from demoplan.scenes.prepared import prepare
from tests.support.helpers import UNTIMED
from tests.support.shared_experiments import AxesRecord, ExperimentsRun, text_box

REPORT_FIGURES = (
    "experiment1-set-table-demonstrations.png",
    "experiment1-set-table-plan.png",
    "experiment2-blocks-demonstrations.png",
    "experiment2-blocks-plan.png",
    "experiment1-segmentation.png",
)


@pytest.fixture(scope="module")
def figures(experiments_run: ExperimentsRun) -> dict[str, list[AxesRecord]]:
    """Every figure ``demoplan experiments`` writes, by its path under the
    output folder (the session's run, tests/support/shared_experiments.py)."""
    assert experiments_run.exit_code == 0, experiments_run.output
    return experiments_run.figures


def _rounded(box: Bbox) -> tuple[float, ...]:
    return tuple(round(float(v), 1) for v in box.extents)


def _overlap(a: Bbox, b: Bbox) -> bool:
    return min(a.x1, b.x1) > max(a.x0, b.x0) and min(a.y1, b.y1) > max(a.y0, b.y0)


def test_every_report_figure_is_checked(figures: dict[str, list[AxesRecord]]) -> None:
    assert set(REPORT_FIGURES) <= set(figures)
    labelled = [name for name in REPORT_FIGURES if any(a.texts for a in figures[name])]
    assert labelled == list(REPORT_FIGURES)  # each has labels to check


def test_no_two_labels_of_an_axes_overlap(figures: dict[str, list[AxesRecord]]) -> None:
    overlaps = [
        f"{name}: {a!r} over {b!r}"
        for name, axes in figures.items()
        for record in axes
        for i, (a, box_a) in enumerate(record.texts)
        for b, box_b in record.texts[i + 1 :]
        if _overlap(box_a, box_b)
    ]
    assert overlaps == []


def test_every_label_lies_inside_its_axes(figures: dict[str, list[AxesRecord]]) -> None:
    outside = [
        f"{name}: {text!r} at {_rounded(box)} outside {_rounded(record.frame)}"
        for name, axes in figures.items()
        for record in axes
        for text, box in record.texts
        if not (
            record.frame.x0 <= box.x0
            and box.x1 <= record.frame.x1
            and record.frame.y0 <= box.y0
            and box.y1 <= record.frame.y1
        )
    ]
    assert outside == []


def test_experiment_2_plan_shows_the_heights(figures: dict[str, list[AxesRecord]]) -> None:
    """Beside the top view, a side view: red stands on the others at the start and
    at the end, and is put down on the table on its way (the unstacking)."""
    axes = figures["experiment2-blocks-plan.png"]
    assert len(axes) == 2
    side = [a for a in axes if re.search(r"\b(height|z)\b", a.ylabel, re.IGNORECASE)]
    assert len(side) == 1
    red = object_colour("red")
    reds = [r for r in side[0].rectangles if r[0] == red]
    faint = [r for r in reds if r[2] and r[1] < 0.5]
    solid = [r for r in reds if r[2] and r[1] > 0.5]
    between = [r for r in reds if not r[2]]
    assert [round(r[4], 3) for r in faint] == [0.04]  # on wood and green now
    assert [round(r[4], 3) for r in solid] == [0.04]  # and again at the end
    assert [(round(r[4], 3), r[3]) for r in between] == [(0.0, "--")]  # on the table between
    filled = {r[0] for r in side[0].rectangles if r[2]}
    assert filled == {object_colour(name) for name in ("wood", "green", "red")}
    top = next(a for a in axes if a is not side[0])
    assert top.ylabel == "y [m]"


# The placement alone, on generated scenes: many labels crowded in a small area.

GAP = 2.0
STEP = 1.5


@st.composite
def crowded_scenes(
    draw: st.DrawFn,
) -> tuple[tuple[float, float, float, float], list[tuple[float, float, float, float]], list[Any]]:
    width = draw(st.floats(200, 600))
    height = draw(st.floats(150, 450))
    centre_x, centre_y = draw(st.floats(0, width)), draw(st.floats(0, height))
    spread = draw(st.floats(0, 30))
    boxes = []
    for _ in range(draw(st.integers(1, 30))):
        w, h = draw(st.floats(8, 70)), draw(st.floats(6, 16))
        x = centre_x + draw(st.floats(-spread, spread)) - w / 2
        y = centre_y + draw(st.floats(-spread, spread)) - h / 2
        boxes.append((x, y, x + w, y + h))
    obstacles = []
    for _ in range(draw(st.integers(0, 3))):
        w, h = draw(st.floats(5, width / 4)), draw(st.floats(5, height / 4))
        x, y = draw(st.floats(0, width - w)), draw(st.floats(0, height - h))
        obstacles.append((x, y, x + w, y + h))
    padded = sum((b[2] - b[0] + 2 * GAP) * (b[3] - b[1] + 2 * GAP) for b in boxes + obstacles)
    assume(padded <= 0.35 * width * height)  # room enough, if not where it is wanted
    return (0.0, 0.0, width, height), boxes, obstacles


def _shifted(box: tuple[float, float, float, float], shift: tuple[float, float]) -> Bbox:
    return Bbox.from_extents(
        box[0] + shift[0], box[1] + shift[1], box[2] + shift[0], box[3] + shift[1]
    )


def _apart(a: Bbox, b: Bbox, gap: float) -> bool:
    tolerance = 1e-6
    return (
        a.x1 + gap <= b.x0 + tolerance
        or b.x1 + gap <= a.x0 + tolerance
        or a.y1 + gap <= b.y0 + tolerance
        or b.y1 + gap <= a.y0 + tolerance
    )


@settings(max_examples=150, deadline=None)
@given(crowded_scenes())
def test_placed_boxes_never_overlap_and_stay_inside(scene: Any) -> None:
    bounds, boxes, obstacles = scene
    leaders = [Leader((b[0] + b[2]) / 2, (b[1] + b[3]) / 2, 6.0) for b in boxes]
    placements = place_boxes(boxes, bounds, obstacles, step=STEP, gap=GAP, leaders=leaders)
    assert len(placements) == len(boxes)
    assert all(p.free for p in placements)
    placed = [_shifted(box, p.shift) for box, p in zip(boxes, placements, strict=True)]
    walls = [Bbox.from_extents(*o) for o in obstacles]
    for k, box in enumerate(placed):
        assert bounds[0] + GAP - 1e-6 <= box.x0 and box.x1 <= bounds[2] - GAP + 1e-6
        assert bounds[1] + GAP - 1e-6 <= box.y0 and box.y1 <= bounds[3] - GAP + 1e-6
        assert all(_apart(box, wall, GAP) for wall in walls)
        assert all(_apart(box, other, GAP) for other in placed[:k])


@settings(max_examples=100, deadline=None)
@given(crowded_scenes())
def test_a_box_moves_only_as_far_as_it_must(scene: Any) -> None:
    """A box free where it is stays there; any other goes to the nearest free
    position of its grid (checked here by trying them all)."""
    bounds, boxes, obstacles = scene
    placements = place_boxes(boxes, bounds, obstacles, step=STEP, gap=GAP)
    taken = [Bbox.from_extents(*o) for o in obstacles]
    for box, placement in zip(boxes, placements, strict=True):
        width, height = box[2] - box[0], box[3] - box[1]
        low_x, high_x = bounds[0] + GAP, bounds[2] - GAP - width
        low_y, high_y = bounds[1] + GAP, bounds[3] - GAP - height
        kx = np.arange(math.ceil((low_x - box[0]) / STEP), math.floor((high_x - box[0]) / STEP) + 1)
        ky = np.arange(math.ceil((low_y - box[1]) / STEP), math.floor((high_y - box[1]) / STEP) + 1)
        dx, dy = (a.ravel() * STEP for a in np.meshgrid(kx, ky))
        free = np.ones(dx.shape, dtype=bool)
        for other in taken:
            free &= ~(
                (box[0] + dx < other.x1 + GAP)
                & (box[2] + dx > other.x0 - GAP)
                & (box[1] + dy < other.y1 + GAP)
                & (box[3] + dy > other.y0 - GAP)
            )
        nearest = float(np.hypot(dx[free], dy[free]).min()) if free.any() else math.inf
        moved = math.hypot(*placement.shift)
        assert moved <= nearest + 1e-9
        home_free = (
            low_x <= box[0] <= high_x
            and low_y <= box[1] <= high_y
            and all(_apart(Bbox.from_extents(*box), other, GAP) for other in taken)
        )
        if home_free:
            assert placement.shift == (0.0, 0.0)
        taken.append(_shifted(box, placement.shift))


def test_a_leader_line_goes_round_the_other_labels() -> None:
    """The label of the point (100, 100) cannot stay just above it (a label is
    there), and just above or below the labels there its line would cross them:
    it goes beside them, though that is further."""
    above = (70.0, 103.0, 130.0, 113.0)
    below = (70.0, 85.0, 130.0, 99.0)
    home = (80.0, 104.0, 120.0, 112.0)
    point = (100.0, 100.0)
    leader = Leader(*point, 6.0)
    bounds = (0.0, 0.0, 300.0, 200.0)
    (with_line,) = place_boxes([home], bounds, [above, below], step=1.0, leaders=[leader])
    (without,) = place_boxes([home], bounds, [above, below], step=1.0)
    assert with_line.free and without.free
    assert abs(without.shift[0]) < 1e-9 and without.shift[1] > 0  # straight up, over `above`
    placed = _shifted(home, with_line.shift)
    assert placed.x1 <= 70.0 or placed.x0 >= 130.0  # beside both
    end = (min(max(point[0], placed.x0), placed.x1), min(max(point[1], placed.y0), placed.y1))
    for t in np.linspace(0.0, 1.0, 401):
        x, y = point[0] + t * (end[0] - point[0]), point[1] + t * (end[1] - point[1])
        for box in (above, below):
            assert not (box[0] < x < box[2] and box[1] < y < box[3])


def test_kinematic_storyboard_frames_keep_their_names_apart(tmp_path: Path) -> None:
    """Without MuJoCo's pictures the frames are drawn from above with each
    object's name: the crowded set table must not print one name over another."""
    from demoplan.documents.demonstrations import load_demonstrations
    from demoplan.execution.runner import run_task
    from demoplan.learning import learn
    from demoplan.learning.settings import PAPER_SETTINGS
    from demoplan.scenes.scene import load_scene
    from tests.support.helpers import EXAMPLES

    model = learn(load_demonstrations([EXAMPLES / "set_table"]), settings=PAPER_SETTINGS)
    scene = load_scene(EXAMPLES / "scenes" / "set-table-cluttered.json")
    boxes: dict[str, list[tuple[str, Bbox]]] = {}

    def record(figure: Any, renderer: Any, path: Path) -> None:
        for k, ax in enumerate(figure.axes):
            texts = [(t.get_text(), text_box(t, renderer)) for t in ax.texts if t.get_visible()]
            boxes[f"{path.name}#{k}"] = [(n, b) for n, b in texts if n]

    with observing_saved_figures(record):
        report = run_task(model, prepare(model, scene), frames=tmp_path, settings=UNTIMED)
    assert report.success and boxes
    named = [key for key, texts in boxes.items() if len(texts) >= 5]
    assert named  # the frames do name the objects
    overlaps = [
        f"{key}: {a!r} over {b!r}"
        for key, texts in boxes.items()
        for i, (a, box_a) in enumerate(texts)
        for b, box_b in texts[i + 1 :]
        if _overlap(box_a, box_b)
    ]
    assert overlaps == []
