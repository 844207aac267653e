"""A storyboard's captions fit their cells: a failure's reason (``FAILED:
dropped: cup stands at (0.392, 0.577, -0.000), 9.3 cm from its target``) is
broken into lines, none wider than its column of the figure — on the arm's
rendered frames and the kinematic top views alike — and no word is lost."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.execution.frames import FrameWriter
from demoplan.execution.world import Observation
from demoplan.model import ObjectGeometry, Pose
from demoplan.plotting.captions import wrap_to_width

pytest.importorskip("matplotlib")

CUP = ObjectGeometry("cylinder", (0.07, 0.07, 0.09))
REASON = "dropped: cup stands at (0.392, 0.577, -0.000), 9.3 cm from its target"


def observation(x: float) -> Observation:
    return Observation({"cup": Pose((x, 0.1, 0.0))}, None, {"cup": CUP})


def storyboard(folder: Path, captions: list[str], failures: dict[int, str], rendered: bool) -> Any:
    """The storyboard figure of frames with ``captions``, ``failures`` (frame →
    reason) marked; ``rendered``: each frame a simulator's picture (as the
    arm's), else drawn from above (as the kinematic world's)."""
    writer = FrameWriter(folder, targets={"cup": Pose((0.4, 0.3, 0.0))})
    for index, caption in enumerate(captions):
        image = np.full((360, 480, 3), 200, dtype=np.uint8) if rendered else None
        writer.capture(observation(0.1 + 0.01 * index), caption, image)
        if index in failures:
            writer.mark_failure(failures[index])
    return writer, writer.storyboard_figure()


def check_captions_fit(writer: FrameWriter, figure: Any) -> None:
    """Every caption lies inside its column of the figure and keeps its words."""
    import matplotlib.pyplot as plt

    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    width, height = figure.bbox.width, figure.bbox.height
    shown = [ax for ax in figure.axes if ax.get_visible()]
    columns = shown[0].get_subplotspec().get_gridspec().ncols
    for ax, index in zip(shown, writer.storyboard_frames(), strict=True):
        column = ax.get_subplotspec().colspan.start
        box = ax.title.get_window_extent(renderer)
        low, high = column * width / columns, (column + 1) * width / columns
        assert low - 0.5 <= box.x0 and box.x1 <= high + 0.5, (ax.title.get_text(), box, low, high)
        assert box.y0 >= 0 and box.y1 <= height + 0.5
        caption = writer.frames[index][1]
        assert ax.title.get_text().split() == caption.split() or "".join(
            ax.title.get_text().split()
        ) == "".join(caption.split())
    plt.close(figure)


@pytest.mark.parametrize("rendered", [True, False], ids=["arm-pictures", "top-views"])
def test_the_arm_runs_failure_captions_fit_the_last_column(tmp_path: Path, rendered: bool) -> None:
    """The user's run: two drops of the cup, the second in the fourth column."""
    captions = ["start", "1: GRASP screwdriver", "2: PUT_DOWN screwdriver", "3: GRASP cup"]
    captions += ["4: PUT_DOWN cup", "5: GRASP cup", "6: PUT_DOWN cup", "end"]
    writer, figure = storyboard(
        tmp_path, captions, {3: REASON, 6: REASON.replace("9.3", "9.7")}, rendered
    )
    assert writer.storyboard_frames() == list(range(8))  # 4 a row: frame 3 ends the first
    check_captions_fit(writer, figure)


words = st.text("abcdefghijklmnopqrstuvwxyz0123456789.,()-$\\{", min_size=1, max_size=40)


@settings(max_examples=4, deadline=None)
@given(
    frames=st.integers(1, 9),
    reason=st.lists(words, min_size=1, max_size=30).map(" ".join),
    rendered=st.booleans(),
)
def test_any_failure_caption_fits_its_cell(
    tmp_path_factory: pytest.TempPathFactory, frames: int, reason: str, rendered: bool
) -> None:
    captions = [f"{k}: PUT_DOWN cup" for k in range(frames)]
    writer, figure = storyboard(
        tmp_path_factory.mktemp("frames"), captions, {frames - 1: reason}, rendered
    )
    check_captions_fit(writer, figure)


@given(
    text=st.lists(words, min_size=1, max_size=40).map(" ".join),
    width=st.integers(1, 60),
)
def test_wrapping_keeps_every_word_and_each_line_within_the_width(text: str, width: int) -> None:
    wrapped = wrap_to_width(text, width, len)
    lines = wrapped.split("\n")
    assert all(len(line) <= width for line in lines)
    assert "".join(wrapped.split()) == "".join(text.split())
    for line, after in itertools.pairwise(lines):  # greedy: no room for the next word
        assert len(f"{line} {after.split(' ')[0]}") > width
