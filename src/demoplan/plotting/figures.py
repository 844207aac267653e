"""Top-view plots of demonstrations (like the paper's Fig. 3 and Fig. 4, left) and plans;
a plan that stacks is drawn with its side view (:mod:`~demoplan.plotting.side_view`)
beside it, both with :mod:`~demoplan.plotting.patches`.

matplotlib is imported lazily (the ``plot`` extra); every function takes an
optional ``ax`` and returns the axes it drew on.

Labels of objects and moves are made with :func:`add_label`; when a figure is
written (:mod:`~demoplan.plotting.output`) :func:`place_labels` moves
them, at the written resolution, so that no two texts of an axes overlap and
none runs off its axes (:func:`place_boxes` is the placement itself).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from demoplan.learning.constraints import GoalOrder
from demoplan.model import Demonstration, TaskModel, demonstrated_colours
from demoplan.plotting.backend import tight_layout, use_agg
from demoplan.plotting.captions import fit_title
from demoplan.plotting.colours import assign_colours, ink, object_colour
from demoplan.plotting.labels import (
    BoxPlacement,
    Leader,
    add_label,
    figure_renderer,
    place_boxes,
    place_labels,
    role_label,
)
from demoplan.plotting.output import save_figure
from demoplan.plotting.patches import (
    LANDMARK_COLOUR,
    draw_landmarks,
    legend,
    object_patch,
    scene_label,
    table_xy,
)
from demoplan.plotting.side_view import plan_stacks, plot_scene_side

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from demoplan.planning.problem import Plan
    from demoplan.scenes.plan import SceneLimitReachedError, SceneNoPlanError
    from demoplan.scenes.problems import SceneProblem
    from demoplan.scenes.scene import Scene

__all__ = [
    "BoxPlacement",
    "Leader",
    "add_label",
    "constraint_caption",
    "demonstration_instances",
    "figure_renderer",
    "fill_panels",
    "object_colour",
    "place_boxes",
    "place_labels",
    "plot_constraints",
    "plot_demonstration",
    "plot_scene_plan",
    "plot_scene_targets",
    "role_label",
    "save_demonstrations",
    "save_no_plan",
    "save_scene_plan",
    "save_scene_targets",
    "share_limits",
]

logger = logging.getLogger(__name__)


def plot_demonstration(
    demo: Demonstration,
    ax: Axes | None = None,
    *,
    title: str | None = None,
    states: Sequence[str] = (),
    instances: Mapping[str, str] | None = None,
    task_colours: Mapping[str, str] | None = None,
) -> Axes:
    """Draw one demonstration from above: initial poses faint, each step's placement
    solid and numbered in the order it happened (with its learned state, when
    ``states`` gives one per step: ``2 B knife``), an arrow for every move.
    ``instances`` (role → instance, :func:`demonstration_instances`): a role's
    step names the instance that filled it, under the role (``1 A plate#1``,
    ``← plate-b``). Each thing in the colour the demonstration gives it, else
    in ``task_colours``' (the colours its task's other demonstrations give),
    else the palette's."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    geometry = demo.geometry()
    current = demo.initial_poses()
    given = {**(task_colours or {}), **demo.given_colours}  # else the palette's
    assign_colours([*(name for name, _ in demo.initial), *(s.object for s in demo.steps)], given)
    for name, pose in demo.landmarks:
        patch = object_patch(pose, geometry.get(name), given.get(name, LANDMARK_COLOUR), 0.6)
        patch.set_hatch("//")
        patch.set_zorder(0.5)
        ax.add_patch(patch)
        add_label(ax, name, table_xy(pose.position), fontsize=7, color="0.3")
    for name, pose in demo.initial:
        ax.add_patch(object_patch(pose, geometry.get(name), object_colour(name), 0.2))
    for number, step in enumerate(demo.steps, start=1):
        colour = object_colour(step.object)
        start = current.get(step.object)
        x, y, _ = step.pose.position
        if start is not None:
            ax.annotate(
                "",
                (x, y),
                start.position[:2],
                arrowprops={"arrowstyle": "->", "color": ink(colour), "lw": 0.8, "alpha": 0.6},
            )
        ax.add_patch(object_patch(step.pose, geometry.get(step.object), colour, 0.85))
        state = f"{states[number - 1]} " if number <= len(states) else ""
        add_label(
            ax,
            f"{number} {state}"
            + role_label(step.object, (instances or {}).get(step.object), separator="\n"),
            (x, y),
            offset=(4, 4),
            ha="left",
            va="bottom",
            fontsize=7,
        )
        current[step.object] = step.pose
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.08)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(title or demo.name, fontsize=9)
    legend(
        ax,
        [
            ("faint", "where the objects stood"),
            ("solid", "where step n put them"),
            ("arrow", "the move of step n"),
        ],
    )
    return ax


def plot_constraints(model: TaskModel, goal: int, ax: Axes | None = None) -> Axes:
    """The constraints among demonstration ``goal``'s states (0-based) as a
    layered graph (like the paper's Fig. 2): their transitive reduction
    (:func:`~demoplan.learning.constraints.goal_order`), so that every drawn
    path is an order every plan for that goal keeps, and every constraint is
    a path. The title counts them and names any order the paths imply that
    is not itself a constraint.

    One graph per goal: the constraints of the whole model are not
    transitively closed where states occur in some demonstrations only (E<J
    and J<F, but F before E in a demonstration without J), and one graph of
    them would draw orders no demonstration supports.
    """
    import matplotlib.pyplot as plt

    from demoplan.learning.constraints import goal_order

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 3))
    order = goal_order(model.sequences[goal], model.constraints)
    depth = {label: 0 for label in order.labels}
    for label in order.labels:  # longest-path layering, in the sequence's order
        for x, y in order.drawn:
            if x == label:
                depth[y] = max(depth[y], depth[x] + 1)
    layers: dict[int, list[str]] = {}
    for label in order.labels:
        layers.setdefault(depth[label], []).append(label)
    position = {
        label: (layer, index - (len(members) - 1) / 2)
        for layer, members in layers.items()
        for index, label in enumerate(members)
    }
    objects = {s.id: s.object for s in model.states}
    for x, y in sorted(order.drawn):
        ax.annotate(
            "",
            position[y],
            position[x],
            arrowprops={
                "arrowstyle": "->",
                "lw": 0.9,
                "color": "0.35",
                "shrinkA": 11,
                "shrinkB": 11,
                "connectionstyle": f"arc3,rad={_bend(position, x, y)}",
            },
        )
    for label, (px, py) in position.items():
        ax.annotate(
            label,
            (px, py),
            ha="center",
            va="center",
            fontsize=9,
            bbox={"boxstyle": "circle", "fc": "white", "ec": "0.2"},
        )
        ax.annotate(  # under the circle, whatever the axes' scale
            objects[label.split("#")[0]],
            (px, py),
            xytext=(0, -11),
            textcoords="offset points",
            ha="center",
            va="top",
            fontsize=6,
            color="0.4",
        )
    ax.set_xlim(-0.6, max(depth.values(), default=0) + 0.6)
    spread = max((len(m) for m in layers.values()), default=1)
    ax.set_ylim(-spread / 2 - 0.3, spread / 2 + 0.1)
    ax.axis("off")
    ax.set_title(constraint_caption(order), fontsize=8)
    return ax


def _bend(position: Mapping[str, tuple[float, float]], start: str, end: str) -> float:
    """How much the edge ``start`` → ``end`` of :func:`plot_constraints` bends
    (``arc3``'s rad): 0, a straight line, unless it would pass through another
    state's circle (C → E straight through B reads as C → B → E); then bent
    round it, away from it."""
    (x1, y1), (x2, y2) = position[start], position[end]
    dx, dy = x2 - x1, y2 - y1
    length = math.hypot(dx, dy) or 1.0
    for label, (x, y) in position.items():
        if label in (start, end):
            continue
        t = min(1.0, max(0.0, ((x - x1) * dx + (y - y1) * dy) / length**2))
        if math.hypot(x1 + t * dx - x, y1 + t * dy - y) < 0.3:
            left = dx * (y - y1) - dy * (x - x1) >= 0  # the state left of the way, or on it
            return 0.35 if left else -0.35  # arc3 bends a positive rad to the right
    return 0.0


def save_demonstrations(model: TaskModel, path: Path, heading: str) -> None:
    """Every demonstration of ``model`` from above (like the paper's Fig. 3),
    each with the constraints among its states below it, on shared axes, in
    one image written atomically; ``heading`` names the task in the title."""

    use_agg()
    import matplotlib.pyplot as plt

    demos = model.demonstrations
    colours = demonstrated_colours(demos)  # one per thing where a demonstration gives none
    fig = plt.figure(figsize=(4.2 * len(demos), 7.6))
    grid = fig.add_gridspec(2, len(demos), height_ratios=[4.4, 2.8])
    panels = []
    for k, demo in enumerate(demos):
        title = f"Demonstration {k + 1}: {'-'.join(model.sequences[k])}"
        panels.append(
            plot_demonstration(
                demo,
                fig.add_subplot(grid[0, k]),
                title=title,
                states=model.sequences[k],
                instances=demonstration_instances(model, k),
                task_colours=colours,
            )
        )
        plot_constraints(model, k, fig.add_subplot(grid[1, k]))
    share_limits(panels)
    fig.suptitle(
        f"{heading}: the demonstrations from above (numbers: order of the moves),\nand below "
        f"each the constraints among its states ({len(model.constraints)} learned in all)",
        fontsize=10,
    )
    tight_layout(fig)
    if model.roles:  # two-line labels ("1 A plate#1", "← plate-b"): the panels' room for them
        fill_panels(fig, panels)
        tight_layout(fig)  # again, around the filled panels' tick labels,
        fill_panels(fig, panels)  # and filled to the panels that leaves
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)


def fill_panels(figure: Figure, axes: Sequence[Axes]) -> None:
    """Grow the limits of top views drawn at equal aspect, about their middle,
    until the data fill each axes' panel: a long, narrow layout (a table for
    two, its seats one behind the other) then leaves room beside it for the
    labels instead of drawing narrow axes in a wide panel. Call it once the
    figure is laid out (its panels placed)."""
    for ax in axes:
        box = ax.get_position(original=True)
        width, height = figure.get_size_inches() * (box.width, box.height)
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        if width <= 0 or height <= 0 or x1 <= x0 or y1 <= y0:
            continue
        if (x1 - x0) / (y1 - y0) < width / height:
            grow = ((y1 - y0) * width / height - (x1 - x0)) / 2
            ax.set_xlim(x0 - grow, x1 + grow)
        else:
            grow = ((x1 - x0) * height / width - (y1 - y0)) / 2
            ax.set_ylim(y0 - grow, y1 + grow)


def demonstration_instances(model: TaskModel, demonstration: int) -> dict[str, str]:
    """Role → the instance that filled it in ``model``'s demonstration
    ``demonstration`` (0-based); empty for a model without roles."""
    return {
        role.name: filled
        for role in model.roles
        if demonstration < len(role.instances)
        and (filled := role.instances[demonstration]) is not None
    }


def share_limits(axes: list[Axes]) -> None:
    """One x and one y range for side-by-side top views (the union of theirs), so
    that the same spot is in the same place in every panel."""
    if not axes:
        return
    x_low = min(ax.get_xlim()[0] for ax in axes)
    x_high = max(ax.get_xlim()[1] for ax in axes)
    y_low = min(ax.get_ylim()[0] for ax in axes)
    y_high = max(ax.get_ylim()[1] for ax in axes)
    for ax in axes:
        ax.set_xlim(x_low, x_high)
        ax.set_ylim(y_low, y_high)


def constraint_caption(order: GoalOrder) -> str:
    """What a constraint graph shows, exactly (:func:`plot_constraints`)."""
    n = len(order.constraints)
    text = (
        f"{n} constraint{'' if n == 1 else 's'} here: {len(order.drawn)} drawn, the rest are paths"
    )
    if order.implied:
        pairs = ", ".join(f"{x}<{y}" for x, y in sorted(order.implied))
        text += f";\nthe paths also order {pairs}, as every plan for this goal does"
    return text


def plot_scene_plan(
    scene: Scene,
    problem: SceneProblem,
    plan: Plan,
    ax: Axes | None = None,
    title: str | None = None,
    roles: Mapping[str, str] | None = None,
) -> Axes:
    """A plan in its scene from above: where the objects stand now (faint), where
    the plan leaves them (solid, higher objects drawn last) and each move as a
    numbered arrow; free-space spots as dashed circles. ``roles`` (role → the
    scene's instance that fills it, as the plan bound them): an instance
    filling a role is named ``plate#1 ← plate-b``."""
    import matplotlib.pyplot as plt
    from matplotlib import patches

    from demoplan.scenes.problems import pose_of

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 5))
    colours = assign_colours(scene.names, scene.given_colours)
    geometry = {obj.name: obj.geometry for obj in scene.objects}
    final = {obj.name: obj.pose for obj in scene.objects}
    moves = []
    for grasp, put in zip(plan.actions[::2], plan.actions[1::2], strict=True):
        source, target = problem.location(grasp.location), problem.location(put.location)
        moves.append((grasp.object, source.position, target.position))
        final[put.object] = pose_of(target)
    draw_landmarks(ax, scene)
    spots = [spot for spot in problem.locations if spot.kind == "freespace"]
    for spot in spots:
        radius = max(max(s.size[0], s.size[1]) for s in spot.shapes) / 2
        ax.add_patch(
            patches.Circle(spot.position[:2], radius, fill=False, ls="--", ec="0.6", lw=0.8)
        )
    for obj in sorted(scene.objects, key=lambda o: o.pose.position[2]):
        ax.add_patch(object_patch(obj.pose, geometry[obj.name], colours[obj.name], 0.25))
    for name, pose in sorted(final.items(), key=lambda item: item[1].position[2]):
        ax.add_patch(object_patch(pose, geometry[name], colours[name], 0.85))
        add_label(ax, scene_label(name, roles), table_xy(pose.position), fontsize=7)
    rad = 0.15
    for number, (name, start, end) in enumerate(moves, 1):
        ax.annotate(
            "",
            xy=table_xy(end),
            xytext=table_xy(start),
            arrowprops={
                "arrowstyle": "->",
                "color": ink(colours[name]),
                "lw": 1.2,
                "connectionstyle": f"arc3,rad={rad}",
            },
        )
        add_label(
            ax,
            str(number),
            _arc_middle(table_xy(start), table_xy(end), rad),
            fontsize=7,
            color=ink(colours[name]),
            fontweight="bold",
        )
    for spot in spots:
        add_label(ax, spot.name, table_xy(spot.position), fontsize=6, color="0.5")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.08)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or f"Plan: {len(moves)} moves", fontsize=9)
    legend(
        ax,
        [
            ("faint", "where the objects stand now"),
            ("solid", "where the plan leaves them"),
            ("arrow", "move n of the plan"),
            ("dashed", "free-space spot"),
        ],
    )
    return ax


def plot_scene_targets(
    scene: Scene,
    problem: SceneProblem,
    reason: str,
    ax: Axes | None = None,
    title: str = "",
    roles: Mapping[str, str] | None = None,
) -> Axes:
    """A scene that has no plan, from above: the objects where they stand
    (solid), the targets of one candidate goal as dashed outlines named after
    their objects, the free-space spots, and why there is no plan (wrapped
    under the title). ``roles`` (role → instance): as :func:`plot_scene_plan`;
    a role's target is named after the role."""
    import matplotlib.pyplot as plt
    from matplotlib import patches

    from demoplan.scenes.problems import pose_of

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 5))
    colours = assign_colours(scene.names, scene.given_colours)
    geometry = {obj.name: obj.geometry for obj in scene.objects}
    draw_landmarks(ax, scene)
    targets = []
    for spot in problem.locations:
        if spot.kind == "freespace":
            radius = max(max(s.size[0], s.size[1]) for s in spot.shapes) / 2
            ax.add_patch(
                patches.Circle(spot.position[:2], radius, fill=False, ls="--", ec="0.6", lw=0.8)
            )
        elif "target" in spot.kind:
            for name in spot.objects:
                outline = object_patch(pose_of(spot), geometry.get(name), colours[name], 1.0)
                outline.set_fill(False)
                outline.set_edgecolor(ink(colours[name]))
                outline.set_linestyle("--")
                outline.set_linewidth(1.2)
                ax.add_patch(outline)
                targets.append((name, table_xy(spot.position)))
    for obj in sorted(scene.objects, key=lambda o: o.pose.position[2]):
        ax.add_patch(object_patch(obj.pose, geometry[obj.name], colours[obj.name], 0.85))
        add_label(ax, scene_label(obj.name, roles), table_xy(obj.pose.position), fontsize=7)
    filled = {instance: role for role, instance in (roles or {}).items()}
    for name, xy in targets:  # placed after the objects' names, which stay on their objects
        owner = filled.get(name, name)
        add_label(ax, f"{owner}'s target", xy, fontsize=6, color=colours[name], va="top")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.12)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    heading = title or "No plan"
    fit_title(ax, f"{heading}\n{reason}", fontsize=8)  # the reason wrapped to the width
    return ax


def save_scene_targets(
    scene: Scene,
    problem: SceneProblem,
    reason: str,
    path: Path,
    title: str,
    roles: Mapping[str, str] | None = None,
) -> None:
    """:func:`plot_scene_targets` into an image file, written atomically."""
    _save_one_axes(lambda ax: plot_scene_targets(scene, problem, reason, ax, title, roles), path)


def save_no_plan(
    failure: SceneNoPlanError | SceneLimitReachedError,
    path: Path,
    roles: Mapping[str, str] | None = None,
) -> None:
    """What ``plan --plot`` draws when there is no plan: the prepared scene, the
    first candidate goal's targets and why (the problems carried by ``failure``;
    ``roles``: as :func:`plot_scene_plan`)."""
    first = failure.outcomes[0].problem
    if roles is None:
        roles = failure.outcomes[0].binding.roles
    goal = first.candidate.demonstrations[0]
    title = f"No plan; the targets of the goal of {failure.model.demonstration_label(goal)}"
    save_scene_targets(failure.scene, first, str(failure), path, title, roles)


def _save_one_axes(draw: Callable[[Axes], object], path: Path) -> None:
    """A one-axes figure drawn by ``draw``, saved atomically (raises ImportError
    without matplotlib)."""

    use_agg()
    import matplotlib.pyplot as plt

    figure, ax = plt.subplots(figsize=(6.5, 5.8))
    try:
        draw(ax)
        tight_layout(figure)
        save_figure(figure, path)
    finally:
        plt.close(figure)


def save_scene_plan(
    scene: Scene,
    problem: SceneProblem,
    plan: Plan,
    path: Path,
    title: str,
    roles: Mapping[str, str] | None = None,
) -> None:
    """:func:`plot_scene_plan` into an image file, written atomically (raises
    ImportError without matplotlib); where the plan stacks (:func:`plan_stacks`)
    its side view (:func:`plot_scene_side`) beside it. ``roles`` (role → the
    instance that fills it): as :func:`plot_scene_plan`."""
    if not plan_stacks(scene, problem, plan):
        _save_one_axes(lambda ax: plot_scene_plan(scene, problem, plan, ax, title, roles), path)
        return

    use_agg()
    import matplotlib.pyplot as plt

    figure = plt.figure(figsize=(12.5, 5.8))
    grid = figure.add_gridspec(1, 2, width_ratios=[1.0, 1.0])
    try:
        plot_scene_plan(scene, problem, plan, figure.add_subplot(grid[0, 0]), title, roles)
        plot_scene_side(scene, problem, plan, figure.add_subplot(grid[0, 1]), roles=roles)
        tight_layout(figure)
        save_figure(figure, path)
    finally:
        plt.close(figure)


def _arc_middle(
    start: tuple[float, float], end: tuple[float, float], rad: float
) -> tuple[float, float]:
    """The middle of matplotlib's ``arc3,rad=rad`` curve from ``start`` to ``end``
    (the quadratic Bézier's point at t = 1/2), on axes of equal aspect."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    return (
        (start[0] + end[0]) / 2 + rad * dy / 2,
        (start[1] + end[1]) / 2 - rad * dx / 2,
    )
