"""The segmentation plot: each object's speed over time, detected moves shaded,
and optionally every object's height over time.

matplotlib is imported lazily (the ``plot`` extra).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.plotting.backend import use_agg
from demoplan.plotting.colours import assign_colours, object_colour
from demoplan.plotting.output import save_figure
from demoplan.segmentation.detect import Move, Segmentation

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from demoplan.segmentation.settings import SegmentationSettings

__all__ = ["plot_heights", "plot_segmentation"]

PUSH_HATCH = "////"


def _counted(count: int, noun: str, plural: str | None = None) -> str:
    """``1 step``, ``2 steps``, ``1 push``, ``0 pushes``."""
    return f"{count} {noun if count == 1 else plural or noun + 's'}"


def _origin(segmentation: Segmentation) -> float:
    """The stream's first sample time: the plots' time zero."""
    times = [float(trace.times[0]) for trace in segmentation.traces if trace.times.size]
    return min(times) if times else 0.0


def plot_segmentation(
    segmentation: Segmentation,
    path: str | Path | None = None,
    *,
    axes: Any | None = None,
    title: str | None = None,
    heights: bool = False,
    dpi: int = 110,
) -> list[Axes]:
    """Draw each object's speed (m/s) over time (s from the stream's start), one
    row per object: steps shaded in the object's colour and numbered in step
    order, nudges shaded grey, pushes hatched, the start and stop thresholds
    as labelled lines. The title counts the steps, nudges and pushes.

    With ``heights`` a last, taller row shows every object's height z (m)
    over time (:func:`plot_heights`): the steps' spans shaded, the pushes
    hatched and the rests read as placements dotted.

    ``axes``: a sequence of axes to draw on, one per object (and one more for
    the heights); by default a new figure is made. With ``path`` the figure
    is written there atomically at ``dpi`` (the format follows the suffix,
    e.g. ``.png`` or ``.svg``). Returns the axes: one per object, then the
    heights' axes.
    """
    use_agg()
    traces = segmentation.traces
    settings = segmentation.settings
    wanted = len(traces) + (1 if heights else 0)
    figure, axes_list = _segmentation_axes(len(traces), heights, axes)
    speed_axes = axes_list[: len(traces)] if traces else axes_list[:1]
    origin = _origin(segmentation)
    assign_colours(trace.object for trace in segmentation.traces)
    number = {id(move): k + 1 for k, move in enumerate(segmentation.moves)}
    top = max((float(trace.speed.max()) for trace in traces if trace.speed.size), default=0.0)
    top = max(top * 1.1, settings.start_speed * 1.5)
    for ax, trace in zip(speed_axes, traces, strict=False):
        colour = object_colour(trace.object)
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
        for move in segmentation.pushes:
            if move.object == trace.object:
                _hatch_push(ax, move, origin, colour)
        _speed_thresholds(ax, settings)
        ax.set_ylim(0.0, top)
        ax.set_ylabel(f"{trace.object}\nm/s", fontsize=8)
        ax.tick_params(labelsize=7)
    if traces and speed_axes:
        speed_axes[0].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7, frameon=False)
    if heights and len(axes_list) > len(traces):
        plot_heights(segmentation, axes_list[len(traces)])
    if axes_list:
        last = min(wanted, len(axes_list)) - 1
        axes_list[max(last, 0)].set_xlabel("time (s)")
        counts = ", ".join(
            (
                _counted(len(segmentation.moves), "step"),
                _counted(len(segmentation.nudges), "nudge"),
                _counted(len(segmentation.pushes), "push", "pushes"),
            )
        )
        axes_list[0].set_title(title or f"Segmentation: {counts}", fontsize=9)
    if path is not None and axes_list:
        target: Any = figure if figure is not None else axes_list[0].figure
        save_figure(target, Path(path), dpi=dpi)
    return axes_list


def _segmentation_axes(
    objects: int, heights: bool, axes: Any | None
) -> tuple[Figure | None, list[Axes]]:
    """The figure made (None when ``axes`` are given) and the axes to draw on:
    one row per object, and with ``heights`` a taller last row."""
    from matplotlib.figure import Figure

    rows = max(1, objects)
    if axes is None:
        if heights:
            figure = Figure(figsize=(9, 0.5 + 1.0 * rows + 2.4), layout="constrained")
            created = figure.subplots(
                rows + 1, 1, sharex=True, squeeze=False, height_ratios=[1.0] * rows + [2.4]
            )
        else:
            figure = Figure(figsize=(9, 0.3 + 1.25 * rows), layout="constrained")
            created = figure.subplots(rows, 1, sharex=True, squeeze=False)
        return figure, [row[0] for row in created]
    axes_list = list(axes)
    wanted = objects + (1 if heights else 0)
    if len(axes_list) < wanted:
        what = "one per object" + (" and one for the heights" if heights else "")
        raise ValueError(f"{wanted} axes expected ({what}), got {len(axes_list)}")
    return None, axes_list


def _speed_thresholds(ax: Axes, settings: SegmentationSettings) -> None:
    """The start and stop speeds as labelled lines."""
    ax.axhline(
        settings.start_speed,
        color="0.3",
        linestyle="--",
        linewidth=0.7,
        label=f"start speed {settings.start_speed:.2f} m/s",
    )
    ax.axhline(
        settings.stop_speed,
        color="0.3",
        linestyle=":",
        linewidth=0.9,
        label=f"stop speed {settings.stop_speed:.2f} m/s",
    )


def plot_heights(segmentation: Segmentation, ax: Axes | None = None) -> Axes:
    """Draw every object's height z (m) over time (s from the stream's start) on
    one axes, one line per object: each step's span shaded in its object's
    colour and numbered in step order, pushes hatched, nudges grey, and a dot
    where each step's placement is read (its rest pose's height at the end of
    the move). Objects whose trace has no heights are left out.
    Returns the axes.
    """
    if ax is None:
        from matplotlib.figure import Figure

        use_agg()
        ax = Figure(figsize=(9, 3), layout="constrained").subplots()
    origin = _origin(segmentation)
    colours = assign_colours(trace.object for trace in segmentation.traces)
    bottom, peak = _height_range(segmentation)
    label_at = peak + 0.06 * max(peak - bottom, 0.05)
    for trace in segmentation.traces:
        if trace.height is not None:
            ax.plot(
                trace.times - origin,
                trace.height,
                color=colours[trace.object],
                linewidth=1.2,
                label=trace.object,
            )
    for k, move in enumerate(segmentation.moves, 1):
        colour = colours.get(move.object, "0.5")
        ax.axvspan(move.start - origin, move.end - origin, color=colour, alpha=0.18)
        ax.annotate(
            str(k),
            ((move.start + move.end) / 2 - origin, label_at),
            ha="center",
            va="bottom",
            fontsize=8,
        )
        ax.scatter(
            [move.end - origin],
            [move.pose.position[2]],
            s=28,
            color=colour,
            edgecolors="k",
            linewidths=0.7,
            zorder=3,
        )
    for move in segmentation.nudges:
        ax.axvspan(move.start - origin, move.end - origin, color="0.6", alpha=0.3)
    for move in segmentation.pushes:
        colour = colours.get(move.object, "0.5")
        _hatch_push(ax, move, origin, colour)
        ax.annotate(
            f"push {move.distance * 100:.0f} cm",
            (move.end - origin, label_at),
            ha="left",
            va="bottom",
            fontsize=7,
        )
    ax.set_ylim(bottom - 0.04 * max(peak - bottom, 0.05), label_at + 0.1 * max(peak - bottom, 0.05))
    ax.set_ylabel("height z (m)", fontsize=8)
    ax.tick_params(labelsize=7)
    _heights_legend(ax)
    return ax


def _height_range(segmentation: Segmentation) -> tuple[float, float]:
    """The lowest and the highest height of every trace (0 and 0.1 m without any)."""
    bottom = min(
        (
            float(t.height.min())
            for t in segmentation.traces
            if t.height is not None and t.height.size
        ),
        default=0.0,
    )
    peak = max(
        (
            float(t.height.max())
            for t in segmentation.traces
            if t.height is not None and t.height.size
        ),
        default=0.1,
    )
    return bottom, peak


def _heights_legend(ax: Axes) -> None:
    """The objects' lines, and what a shaded, a hatched span and a dot mean."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles, _ = ax.get_legend_handles_labels()
    handles += [
        Patch(facecolor="0.5", alpha=0.3, label="step (numbered)"),
        Patch(facecolor="none", edgecolor="0.3", hatch=PUSH_HATCH, label="push (not a step)"),
        Line2D(
            [],
            [],
            linestyle="none",
            marker="o",
            markerfacecolor="0.6",
            markeredgecolor="k",
            label="placement: rest pose",
        ),
    ]
    ax.legend(
        handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7, frameon=False
    )


def _hatch_push(ax: Axes, move: Move, origin: float, colour: str) -> None:
    """A push's time span, hatched in its object's colour."""
    ax.axvspan(
        move.start - origin,
        move.end - origin,
        facecolor="none",
        edgecolor=colour,
        hatch=PUSH_HATCH,
        linewidth=0.0,
    )
