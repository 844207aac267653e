"""The segmentation plot with the heights panel (``plot_segmentation(..., heights=True)``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.colors import to_rgba

from demoplan.plotting.segmentation import plot_heights, plot_segmentation
from demoplan.segmentation import ObjectTrack, PoseStream, segment


def carried_and_pushed() -> PoseStream:
    """``cup`` lifted 10 cm and set down 30 cm away (a step); ``box`` slid 5 cm along
    the table (a push), both at 60 Hz without noise."""
    t = np.arange(0.0, 10.0, 1 / 60)
    s = np.clip((t - 2.0) / 2.0, 0.0, 1.0)
    smooth = s * s * (3 - 2 * s)
    cup = np.column_stack((0.2 + 0.3 * smooth, np.full_like(t, 0.4), 0.1 * np.sin(np.pi * smooth)))
    u = np.clip((t - 6.0) / 0.5, 0.0, 1.0)
    box = np.column_stack(
        (0.6 + 0.05 * u * u * (3 - 2 * u), np.full_like(t, 0.2), np.zeros_like(t))
    )
    return PoseStream((ObjectTrack("cup", t, cup), ObjectTrack("box", t, box)), "plot.csv")


def test_heights_panel_has_one_line_per_object_and_shades_steps_and_pushes(
    tmp_path: Path,
) -> None:
    found = segment(carried_and_pushed())
    assert [m.object for m in found.moves] == ["cup"]
    assert [m.object for m in found.pushes] == ["box"]
    path = tmp_path / "heights.png"
    axes = plot_segmentation(found, path, heights=True, dpi=60)
    assert path.stat().st_size > 5_000
    assert len(axes) == 3  # cup, box, heights
    heights = axes[-1]
    assert heights.get_ylabel() == "height z (m)"
    assert [line.get_label() for line in heights.lines] == ["cup", "box"]
    assert float(np.max(np.asarray(heights.lines[0].get_ydata()))) > 0.09
    # One span per step, one hatched span per push.
    assert len(heights.patches) == len(found.moves) + len(found.pushes)
    step_span, push_span = heights.patches
    assert step_span.get_facecolor()[:3] == to_rgba(heights.lines[0].get_color())[:3]
    assert push_span.get_hatch()
    # The placement read at the end of the step, dotted.
    (dots,) = heights.collections
    x, z = (float(v) for v in np.asarray(dots.get_offsets())[0])
    move = found.moves[0]
    assert abs(x - move.end) < 1e-9 and abs(z - move.pose.position[2]) < 1e-9
    # Speed rows: the step shaded, the push hatched; thresholds labelled; exact counts.
    assert len(axes[0].patches) == 1 and len(axes[1].patches) == 1
    legend = axes[0].get_legend()
    assert legend is not None
    labels = [text.get_text() for text in legend.get_texts()]
    assert labels == ["start speed 0.10 m/s", "stop speed 0.04 m/s"]
    assert axes[0].get_title() == "Segmentation: 1 step, 0 nudges, 1 push"


def test_without_heights_the_plot_is_unchanged_and_heights_draw_on_given_axes() -> None:
    from matplotlib.figure import Figure

    found = segment(carried_and_pushed())
    axes = plot_segmentation(found)
    assert len(axes) == 2
    assert all(ax.get_ylabel() != "height z (m)" for ax in axes)
    ax = Figure().subplots()
    assert plot_heights(found, ax) is ax
    assert len(ax.lines) == 2
