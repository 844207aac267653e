"""The segmentation plot: each object's speed over time, detected moves shaded.

matplotlib is imported lazily (the ``plot`` extra).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.plotting import object_colour, save_figure
from demoplan.segmentation.detect import Segmentation

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["plot_segmentation"]


def plot_segmentation(
    segmentation: Segmentation,
    path: str | Path | None = None,
    *,
    axes: Any | None = None,
    title: str | None = None,
) -> list[Axes]:
    """Draw each object's speed (m/s) over time (s from the stream's start), one
    row per object: steps shaded in the object's colour and numbered in step
    order, nudges shaded grey, the start and stop thresholds dashed.

    ``axes``: a sequence of one axes per object to draw on; by default a new
    figure is made. With ``path`` the figure is written there atomically (the
    format follows the suffix, e.g. ``.png`` or ``.svg``) and closed.
    Returns the axes, one per object.
    """
    from matplotlib.figure import Figure

    traces = segmentation.traces
    settings = segmentation.settings
    figure = None
    if axes is None:
        figure = Figure(figsize=(9, 0.3 + 1.25 * max(1, len(traces))), layout="constrained")
        created = figure.subplots(max(1, len(traces)), 1, sharex=True, squeeze=False)
        axes_list: list[Axes] = [row[0] for row in created]
    else:
        axes_list = list(axes)
        if len(axes_list) < len(traces):
            raise ValueError(f"{len(traces)} axes expected (one per object), got {len(axes_list)}")
    times = [float(trace.times[0]) for trace in traces if trace.times.size]
    origin = min(times) if times else 0.0
    number = {id(move): k + 1 for k, move in enumerate(segmentation.moves)}
    top = max((float(trace.speed.max()) for trace in traces if trace.speed.size), default=0.0)
    top = max(top * 1.1, settings.start_speed * 1.5)
    for index, (ax, trace) in enumerate(zip(axes_list, traces, strict=False)):
        colour = object_colour(trace.object, index)
        ax.plot(trace.times - origin, trace.speed, color=colour, linewidth=1.0)
        for move in segmentation.moves:
            if move.object == trace.object:
                ax.axvspan(move.start - origin, move.end - origin, color=colour, alpha=0.25)
                ax.annotate(
                    str(number[id(move)]),
                    ((move.start + move.end) / 2 - origin, top * 0.92),
                    ha="center",
                    va="top",
                    fontsize=8,
                )
        for move in segmentation.nudges:
            if move.object == trace.object:
                ax.axvspan(move.start - origin, move.end - origin, color="0.6", alpha=0.3)
        for level in (settings.start_speed, settings.stop_speed):
            ax.axhline(level, color="0.4", linestyle="--", linewidth=0.7)
        ax.set_ylim(0.0, top)
        ax.set_ylabel(f"{trace.object}\nm/s", fontsize=8)
        ax.tick_params(labelsize=7)
    if axes_list:
        axes_list[min(len(traces), len(axes_list)) - 1].set_xlabel("time (s)")
        axes_list[0].set_title(
            title
            or f"Segmentation: {len(segmentation.moves)} steps, {len(segmentation.nudges)} nudges",
            fontsize=9,
        )
    if path is not None and axes_list:
        target: Any = figure if figure is not None else axes_list[0].figure
        save_figure(target, Path(path))
    return axes_list
