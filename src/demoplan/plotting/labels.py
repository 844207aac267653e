"""Text labels placed without overlap in matplotlib figures: a label made with
:func:`add_label` is moved, when its figure is written, to the nearest free
spot of a grid around where it was asked for (:func:`place_labels`), with a
thin leader line back to its point when it had to go far. :func:`place_boxes`
is the placement itself, on plain boxes (tested on its own).
"""

from __future__ import annotations

import logging
import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.backend_bases import RendererBase
    from matplotlib.figure import Figure
    from matplotlib.text import Annotation

__all__ = [
    "LABEL_GAP_POINTS",
    "Box",
    "BoxPlacement",
    "Leader",
    "add_label",
    "figure_renderer",
    "literal_texts",
    "place_boxes",
    "place_labels",
    "remove_leaders",
    "role_label",
]

logger = logging.getLogger(__name__)

Box = tuple[float, float, float, float]
"""An axis-aligned box ``(x0, y0, x1, y1)``, in display units (pixels)."""

LABEL_GAP_POINTS = 3.0
"""Clearance (pt) kept between two texts of an axes, and between a label and its axes' edge."""
LABEL_STEP_POINTS = 1.0
"""Spacing (pt) of the grid of positions a label may be moved to."""
LEADER_POINTS = 6.0
"""A label moved further than this (pt) from the point it names gets a thin line to it."""
LEADER_REACH = 3.0
"""How far (in label sizes) a label may go to keep its line clear of the other labels."""


def role_label(name: str, instance: str | None = None, separator: str = " ") -> str:
    """The label of an object that is a role of identical objects, with the
    instance that fills it: ``plate#1 ← plate-b`` (docs/learning.md, "Roles in
    tables and figures"; ``separator`` before the arrow: ``"\\n"`` puts the
    instance on a line of its own); ``name`` alone where no other instance
    fills it."""
    if instance is None or instance == name:
        return name
    return f"{name}{separator}← {instance}"


@dataclass(frozen=True)
class BoxPlacement:
    """Where :func:`place_boxes` put a box: its ``shift`` from where it was asked
    for, and whether that place is ``free`` (clear of every other box and
    obstacle and inside the bounds) or only the least crowded one there was."""

    shift: tuple[float, float]
    free: bool


def place_boxes(
    boxes: Sequence[Box],
    bounds: Box,
    obstacles: Sequence[Box] = (),
    *,
    step: float,
    gap: float = 0.0,
    leaders: Sequence[Leader | None] | None = None,
) -> list[BoxPlacement]:
    """Place ``boxes`` one after the other, in order, each at the free position
    nearest to where it is (its home): free of the obstacles and of the boxes
    placed before it by at least ``gap``, and inside ``bounds`` by ``gap``.

    A box's candidate positions are its home shifted by whole multiples of
    ``step`` in x and y (and its home pushed just inside the bounds), tried in
    order of distance from the home (ties: up before down, right before left),
    so a box that is free at home stays there and any other moves as little as
    the grid allows. The search grows from a window around the home to the
    whole bounds; only a box that fits nowhere (or is larger than the bounds)
    is left at its least crowded candidate, with ``free`` false.

    ``leaders`` (one per box, or None): the point a box names and how far from
    it the box may be before a line is drawn to it; a position whose line
    would cross an obstacle or an earlier box (one that does not cover the
    point itself) is taken only if no other is free within ``LEADER_REACH``
    times the box's size of its home.
    """
    if step <= 0:
        raise ValueError(f"step must be positive, got {step}")
    bx0, by0, bx1, by1 = bounds
    occupied = [_grown(box, gap) for box in obstacles]
    placements = []
    for k, (x0, y0, x1, y1) in enumerate(boxes):
        width, height = x1 - x0, y1 - y0
        xs = _positions(x0, bx0 + gap, bx1 - gap - width, step)
        ys = _positions(y0, by0 + gap, by1 - gap - height, step)
        fits = bool(bx1 - bx0 - 2 * gap >= width and by1 - by0 - 2 * gap >= height)
        taken = np.array(occupied, dtype=float).reshape(-1, 4)
        leader = leaders[k] if leaders is not None else None
        found = None
        if leader is not None:  # a line round the others, if there is one nearby
            reach = LEADER_REACH * max(width, height, step)
            near_x, near_y = xs[np.abs(xs - x0) <= reach], ys[np.abs(ys - y0) <= reach]
            found = _nearest_free(near_x, near_y, x0, y0, width, height, taken, reach, leader)
        reach = 8 * max(width, height, step)
        while found is None:
            near_x, near_y = xs[np.abs(xs - x0) <= reach], ys[np.abs(ys - y0) <= reach]
            found = _nearest_free(near_x, near_y, x0, y0, width, height, taken, reach)
            if reach >= math.hypot(np.abs(xs - x0).max(), np.abs(ys - y0).max()):
                break
            reach *= 3
        if found is None or not fits:
            found = _least_crowded(xs, ys, x0, y0, width, height, taken)
            free = False
        else:
            free = True
        placements.append(BoxPlacement((found[0] - x0, found[1] - y0), free))
        occupied.append(_grown((found[0], found[1], found[0] + width, found[1] + height), gap))
    return placements


@dataclass(frozen=True)
class Leader:
    """The point ``(x, y)`` a box names, and the distance ``beyond`` which a
    line is drawn from it to the box (:func:`place_boxes`)."""

    x: float
    y: float
    beyond: float


def _crossed(
    cx: np.ndarray[Any, Any],
    cy: np.ndarray[Any, Any],
    width: float,
    height: float,
    leader: Leader,
    taken: np.ndarray[Any, Any],
) -> np.ndarray[Any, Any]:
    """For each candidate lower-left corner, whether the line from the leader's
    point to the box there (drawn only beyond ``leader.beyond``) crosses a
    taken box that does not cover the point itself."""
    px = np.clip(leader.x, cx, cx + width)
    py = np.clip(leader.y, cy, cy + height)
    drawn = np.hypot(px - leader.x, py - leader.y) > leader.beyond
    covers = (
        (taken[:, 0] <= leader.x)
        & (leader.x <= taken[:, 2])
        & (taken[:, 1] <= leader.y)
        & (leader.y <= taken[:, 3])
    )
    others = taken[~covers]
    if not len(others) or not drawn.any():
        return np.zeros(cx.shape, dtype=bool)
    x_low, x_high = _slab(leader.x, (px - leader.x)[:, None], others[:, 0], others[:, 2])
    y_low, y_high = _slab(leader.y, (py - leader.y)[:, None], others[:, 1], others[:, 3])
    enter = np.maximum(np.maximum(x_low, y_low), 0.0)
    leave = np.minimum(np.minimum(x_high, y_high), 1.0)
    return np.asarray(drawn & (enter < leave).any(axis=1))


def _slab(
    start: float, delta: np.ndarray[Any, Any], low: np.ndarray[Any, Any], high: np.ndarray[Any, Any]
) -> tuple[np.ndarray[Any, Any], np.ndarray[Any, Any]]:
    """The parameters t of ``start + t·delta`` between which it is within ``low..high``
    (all t, or none, where ``delta`` is 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        first, second = (low - start) / delta, (high - start) / delta
    inside = (low <= start) & (start <= high)
    still = delta == 0
    t_low = np.where(still, np.where(inside, -np.inf, np.inf), np.minimum(first, second))
    t_high = np.where(still, np.where(inside, np.inf, -np.inf), np.maximum(first, second))
    return t_low, t_high


def _grown(box: Box, margin: float) -> Box:
    return (box[0] - margin, box[1] - margin, box[2] + margin, box[3] + margin)


def _positions(home: float, low: float, high: float, step: float) -> np.ndarray[Any, Any]:
    """The lower edges a box may take along one axis: ``home`` plus whole steps
    within ``low..high``, and ``home`` pushed into that range; the middle of the
    range when the box is longer than it."""
    if high < low:
        return np.array([(low + high) / 2])
    first = math.ceil((low - home) / step)
    last = math.floor((high - home) / step)
    grid = home + step * np.arange(first, last + 1, dtype=float)
    return np.unique(np.append(grid, min(max(home, low), high)))


def _candidates(
    xs: np.ndarray[Any, Any], ys: np.ndarray[Any, Any], x0: float, y0: float
) -> tuple[np.ndarray[Any, Any], np.ndarray[Any, Any], np.ndarray[Any, Any]]:
    """Every (x, y) of the grid, nearest to ``(x0, y0)`` first (ties: higher,
    then further right, first), and its distance."""
    grid_x, grid_y = np.meshgrid(xs, ys, indexing="ij")
    cx, cy = grid_x.ravel(), grid_y.ravel()
    cost = np.hypot(cx - x0, cy - y0)
    order = np.lexsort((-cx, -cy, cost))
    return cx[order], cy[order], cost[order]


def _collides(
    cx: np.ndarray[Any, Any],
    cy: np.ndarray[Any, Any],
    width: float,
    height: float,
    taken: np.ndarray[Any, Any],
) -> np.ndarray[Any, Any]:
    """For each candidate lower-left corner, whether the box there overlaps any taken box."""
    if not len(taken):
        return np.zeros(cx.shape, dtype=bool)
    hit = (
        (cx[:, None] < taken[None, :, 2])
        & (cx[:, None] + width > taken[None, :, 0])
        & (cy[:, None] < taken[None, :, 3])
        & (cy[:, None] + height > taken[None, :, 1])
    )
    return np.asarray(hit.any(axis=1))


def _nearest_free(
    xs: np.ndarray[Any, Any],
    ys: np.ndarray[Any, Any],
    x0: float,
    y0: float,
    width: float,
    height: float,
    taken: np.ndarray[Any, Any],
    reach: float,
    leader: Leader | None = None,
) -> tuple[float, float] | None:
    """The nearest free candidate no further than ``reach`` (beyond it a nearer
    one may lie outside the window searched), or None; with a ``leader``, one
    whose line crosses no taken box."""
    if not len(xs) or not len(ys):
        return None
    cx, cy, cost = _candidates(xs, ys, x0, y0)
    keep = cost <= reach
    cx, cy = cx[keep], cy[keep]
    chunk = 4096
    for start in range(0, len(cx), chunk):
        part_x, part_y = cx[start : start + chunk], cy[start : start + chunk]
        free = np.flatnonzero(~_collides(part_x, part_y, width, height, taken))
        if leader is None:
            if len(free):
                return float(part_x[free[0]]), float(part_y[free[0]])
            continue
        for first in range(0, len(free), 256):  # the nearest first: most lines cross nothing
            batch = free[first : first + 256]
            clear = batch[~_crossed(part_x[batch], part_y[batch], width, height, leader, taken)]
            if len(clear):
                return float(part_x[clear[0]]), float(part_y[clear[0]])
    return None


def _least_crowded(
    xs: np.ndarray[Any, Any],
    ys: np.ndarray[Any, Any],
    x0: float,
    y0: float,
    width: float,
    height: float,
    taken: np.ndarray[Any, Any],
) -> tuple[float, float]:
    """The candidate whose box covers the least area of the taken boxes (the
    nearest to ``(x0, y0)`` of equally crowded ones)."""
    cx, cy, _ = _candidates(xs, ys, x0, y0)
    if not len(taken):
        return float(cx[0]), float(cy[0])
    best, best_area = (float(cx[0]), float(cy[0])), math.inf
    chunk = 4096
    for start in range(0, len(cx), chunk):
        part_x, part_y = cx[start : start + chunk, None], cy[start : start + chunk, None]
        across = np.clip(
            np.minimum(part_x + width, taken[None, :, 2]) - np.maximum(part_x, taken[None, :, 0]),
            0,
            None,
        )
        up = np.clip(
            np.minimum(part_y + height, taken[None, :, 3]) - np.maximum(part_y, taken[None, :, 1]),
            0,
            None,
        )
        area = (across * up).sum(axis=1)
        k = int(np.argmin(area))
        if area[k] < best_area:
            best, best_area = (float(part_x[k, 0]), float(part_y[k, 0])), float(area[k])
    return best


@dataclass
class _Label:
    """What :func:`place_labels` keeps of a label: where it was asked to be (an
    offset in points from the point it names) and the leader line it drew last."""

    home: tuple[float, float]
    leader: Any = None


_LABELS: weakref.WeakKeyDictionary[Any, _Label] = weakref.WeakKeyDictionary()


def add_label(
    ax: Axes,
    text: str,
    xy: tuple[float, float],
    *,
    offset: tuple[float, float] = (0.0, 0.0),
    ha: str = "center",
    va: str = "center",
    **style: Any,
) -> Annotation:
    """A text naming the data point ``xy``, ``offset`` points from it, that
    :func:`place_labels` may move (to keep it clear of the axes' other texts
    and inside the axes). It has a thin white halo, to be read over a shape
    or a line."""
    from matplotlib import patheffects

    style.setdefault("path_effects", [patheffects.withStroke(linewidth=2.0, foreground="white")])
    annotation = ax.annotate(
        text, xy, xytext=offset, textcoords="offset points", ha=ha, va=va, **style
    )
    _LABELS[annotation] = _Label(home=offset)
    return annotation


def figure_renderer(figure: Figure) -> RendererBase:
    """The renderer ``figure`` is measured with (Agg, at the figure's dpi)."""
    get = getattr(figure.canvas, "get_renderer", None)
    if get is None:  # a plain Figure(): give it an Agg canvas, as savefig would
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        get = FigureCanvasAgg(figure).get_renderer
    renderer: RendererBase = get()
    return renderer


def literal_texts(figure: Figure) -> None:
    """Every text of ``figure`` but its tick labels — titles, axis labels,
    annotations, legends — drawn as written, never as TeX: an object's name
    read from a file may hold ``$`` (``$\\sqrt{$`` would fail to parse,
    ``$x$`` would show an italic x). Tick labels keep matplotlib's own
    notation (a log axis writes ``$10^{2}$``)."""
    from matplotlib.axis import Axis
    from matplotlib.text import Text

    # the figure's artists, walked as figure.findobj(Text) walks them but for
    # an axis: of its children (its label, its offset text, its ticks) only
    # the label is taken; the rest is tick labels, and walking the ticks
    # would make them for the axis' tick locations (a whole axis' ticks made
    # before the drawing needs them, or for an axis never drawn)
    stack: list[Any] = [figure]
    while stack:
        artist = stack.pop()
        if isinstance(artist, Text):
            artist.set_usetex(False)
            artist.set_parse_math(False)
        stack.extend([artist.label] if isinstance(artist, Axis) else artist.get_children())


def remove_leaders(ax: Axes) -> None:
    """Take away the leader lines :func:`place_labels` drew for ``ax``'s
    labels: the axes is as it was before its labels were placed (a figure
    drawn again with other artists, as a run's frames are)."""
    for text in list(ax.texts):
        state = _LABELS.get(text)
        if state is not None and state.leader is not None:
            state.leader.remove()
            state.leader = None


def place_labels(figure: Figure) -> list[Annotation]:
    """Move the figure's labels (:func:`add_label`) so that no two texts of an
    axes overlap and every label lies inside its axes, at the figure's current
    size and dpi; returns the labels that found no free place (left where they
    overlap least).

    Each axes' labels are placed in the order they were made (:func:`place_boxes`),
    each at the free spot nearest to where it was asked to be, clear of the
    axes' other texts and of its legend (whose position is fixed first). A
    label moved away from the point it names gets a thin line to it. Calling
    this again starts from the asked-for positions. Every text but the tick
    labels is made literal first (:func:`literal_texts`).
    """
    from matplotlib.text import Annotation

    literal_texts(figure)
    axes_labels = [
        (ax, [t for t in ax.texts if isinstance(t, Annotation) and t in _LABELS])
        for ax in figure.axes
        if ax.get_visible()
    ]
    axes_labels = [(ax, labels) for ax, labels in axes_labels if labels]
    for _, labels in axes_labels:
        for label in labels:
            state = _LABELS[label]
            label.xyann = state.home
            if state.leader is not None:
                state.leader.remove()
                state.leader = None
    if not axes_labels:
        return []
    _lay_out(figure, [ax for ax, _ in axes_labels])
    renderer = figure_renderer(figure)
    to_points = 72.0 / figure.dpi
    gap = LABEL_GAP_POINTS / to_points
    crowded: list[Annotation] = []
    for ax, labels in axes_labels:
        frame = ax.get_window_extent(renderer)
        obstacles = [
            _text_box(t, renderer)
            for t in ax.texts
            if t not in _LABELS and t.get_visible() and t.get_text()
        ]
        legend = ax.get_legend()
        if legend is not None and legend.get_visible():
            _freeze_legend(ax, legend, renderer)
            obstacles.append(_box(legend.get_frame().get_window_extent(renderer)))
        anchors = {id(t): ax.transData.transform(t.xy) for t in labels}
        shown = [
            t
            for t in labels
            if t.get_visible()
            and t.get_text()
            and frame.x0 <= anchors[id(t)][0] <= frame.x1
            and frame.y0 <= anchors[id(t)][1] <= frame.y1
        ]
        homes = [_text_box(t, renderer) for t in shown]
        leaders = []
        for label, home in zip(shown, homes, strict=True):
            x, y = (float(v) for v in anchors[id(label)])
            leaders.append(Leader(x, y, max(LEADER_POINTS / to_points, _distance((x, y), home))))
        placements = place_boxes(
            homes,
            _box(frame),
            obstacles,
            step=LABEL_STEP_POINTS / to_points,
            gap=gap,
            leaders=leaders,
        )
        for label, home, leader, placement in zip(shown, homes, leaders, placements, strict=True):
            dx, dy = placement.shift
            x, y = _LABELS[label].home
            label.xyann = (x + dx * to_points, y + dy * to_points)
            if not placement.free:
                crowded.append(label)
            placed = (home[0] + dx, home[1] + dy, home[2] + dx, home[3] + dy)
            if _distance((leader.x, leader.y), placed) > leader.beyond:
                _LABELS[label].leader = _leader(ax, label, (leader.x, leader.y), placed, to_points)
    return crowded


def _box(bbox: Any) -> Box:
    return (float(bbox.x0), float(bbox.y0), float(bbox.x1), float(bbox.y1))


def _text_box(text: Any, renderer: RendererBase) -> Box:
    """What a text covers: its letters and the box drawn around them, if any."""
    x0, y0, x1, y1 = _box(text.get_window_extent(renderer))
    patch = text.get_bbox_patch()
    if patch is not None:
        px0, py0, px1, py1 = _box(patch.get_window_extent(renderer))
        x0, y0, x1, y1 = min(x0, px0), min(y0, py0), max(x1, px1), max(y1, py1)
    return (x0, y0, x1, y1)


def _lay_out(figure: Figure, axes: list[Axes]) -> None:
    """Lay ``figure`` out as drawing it would, for what placing the labels of
    ``axes`` reads: where each of them stands, its limits, its legend's place.
    A figure with a layout engine, an axes placed by a locator or one with a
    legend (``loc="best"`` is found while drawing) is drawn, unrendered;
    otherwise each axes' limits and aspect are all the drawing would settle
    for them (a run's frame is saved with one draw less)."""
    if figure.get_layout_engine() is not None or any(
        ax.get_axes_locator() is not None or ax.get_legend() is not None for ax in axes
    ):
        figure.draw_without_rendering()
        return
    for ax in axes:
        ax.viewLim  # noqa: B018 (the property brings autoscaled limits up to date)
        ax.apply_aspect()


def _freeze_legend(ax: Axes, legend: Any, renderer: RendererBase) -> None:
    """Pin a legend where it was drawn (``loc="best"`` would look again once
    the labels have moved)."""
    box = legend.get_window_extent(renderer).transformed(ax.transAxes.inverted())
    legend.set_loc((float(box.x0), float(box.y0)))


def _nearest_point(point: tuple[float, float], box: Box) -> tuple[float, float]:
    return (min(max(point[0], box[0]), box[2]), min(max(point[1], box[1]), box[3]))


def _distance(point: tuple[float, float], box: Box) -> float:
    near = _nearest_point(point, box)
    return math.hypot(point[0] - near[0], point[1] - near[1])


def _leader(
    ax: Axes, label: Annotation, anchor: tuple[float, float], box: Box, to_points: float
) -> Any:
    """A thin line from the point a label names to the label's nearest edge."""
    end = _nearest_point(anchor, box)
    return ax.annotate(
        "",
        label.xy,
        xytext=((end[0] - anchor[0]) * to_points, (end[1] - anchor[1]) * to_points),
        textcoords="offset points",
        arrowprops={
            "arrowstyle": "-",
            "color": label.get_color(),
            "lw": 0.5,
            "alpha": 0.7,
            "shrinkA": 0.0,
            "shrinkB": 1.5,
        },
    )
