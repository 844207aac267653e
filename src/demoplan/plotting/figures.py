"""Top-view plots of demonstrations (like the paper's Fig. 3 and Fig. 4, left) and plans,
and a side view of plans that stack.

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
from typing import TYPE_CHECKING, Any

from demoplan.learning.constraints import GoalOrder
from demoplan.model import Demonstration, ObjectGeometry, Pose, TaskModel
from demoplan.plotting.backend import tight_layout, use_agg
from demoplan.plotting.captions import fit_title
from demoplan.plotting.colours import assign_colours, object_colour
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
from demoplan.rotations import rpy_from_quat

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
    "object_patch",
    "place_boxes",
    "place_labels",
    "plan_stacks",
    "plot_constraints",
    "plot_demonstration",
    "plot_scene_plan",
    "plot_scene_side",
    "plot_scene_targets",
    "role_label",
    "save_demonstrations",
    "save_no_plan",
    "save_scene_plan",
    "save_scene_targets",
    "scene_label",
    "share_limits",
    "side_patch",
]

logger = logging.getLogger(__name__)


def object_patch(pose: Pose, geometry: ObjectGeometry | None, colour: str, alpha: float) -> Any:
    """The object's outline from above as a matplotlib patch."""
    from matplotlib import patches

    x, y, _ = pose.position
    size = geometry.size if geometry else (0.03, 0.03, 0.03)
    yaw = 0.0
    if pose.orientation is not None:
        qx, qy, qz, qw = pose.orientation
        yaw = math.degrees(math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)))
    if geometry is not None and geometry.shape in {"cylinder", "sphere"}:
        return patches.Ellipse(
            (x, y), size[0], size[1], angle=yaw, fc=colour, ec="k", alpha=alpha, lw=0.8
        )
    return patches.Rectangle(
        (x - size[0] / 2, y - size[1] / 2),
        size[0],
        size[1],
        angle=yaw,
        rotation_point="center",
        fc=colour,
        ec="k",
        alpha=alpha,
        lw=0.8,
    )


LANDMARK_COLOUR = "#d9c9a8"
"""Landmarks (a tray, a fixture) are drawn hatched, under all, sandy unless given a colour."""


def draw_landmarks(ax: Axes, scene: Scene, *, side: bool = False) -> None:
    """The scene's landmarks that have a size, from above (or from the side),
    under the objects, each named, in its given colour (else :data:`LANDMARK_COLOUR`)."""
    shapes, given = dict(scene.landmark_geometry), scene.given_colours
    for name, pose in scene.landmarks:
        if name not in shapes:
            continue
        draw = side_patch if side else object_patch
        patch = draw(pose, shapes[name], given.get(name, LANDMARK_COLOUR), 0.6)
        patch.set_hatch("//")
        patch.set_zorder(0.5)
        ax.add_patch(patch)
        if side:
            add_label(ax, name, _side_middle(pose, shapes[name]), fontsize=7, color="0.3")
        else:
            corner = _landmark_corner(pose, shapes[name])
            add_label(ax, name, corner, fontsize=7, color="0.3", ha="left", va="bottom")


def _landmark_corner(pose: Pose, geometry: ObjectGeometry) -> tuple[float, float]:
    """A point just inside the landmark's first corner: its name there stays
    clear of what stands on its middle."""
    x, y, _ = pose.position
    yaw = 0.0 if pose.orientation is None else math.radians(rpy_from_quat(pose.orientation)[2])
    dx, dy = -0.4 * geometry.size[0], -0.4 * geometry.size[1]
    return (
        x + dx * math.cos(yaw) - dy * math.sin(yaw),
        y + dx * math.sin(yaw) + dy * math.cos(yaw),
    )


def plot_demonstration(
    demo: Demonstration,
    ax: Axes | None = None,
    *,
    title: str | None = None,
    states: Sequence[str] = (),
    instances: Mapping[str, str] | None = None,
) -> Axes:
    """Draw one demonstration from above: initial poses faint, each step's placement
    solid and numbered in the order it happened (with its learned state, when
    ``states`` gives one per step: ``2 B knife``), an arrow for every move.
    ``instances`` (role → instance, :func:`demonstration_instances`): a role's
    step names the instance that filled it, under the role (``1 A plate#1``,
    ``← plate-b``)."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    geometry = demo.geometry()
    current = demo.initial_poses()
    given = demo.given_colours  # the file's colours, else the palette's
    assign_colours([*(name for name, _ in demo.initial), *(s.object for s in demo.steps)], given)
    for name, pose in demo.landmarks:
        patch = object_patch(pose, geometry.get(name), given.get(name, LANDMARK_COLOUR), 0.6)
        patch.set_hatch("//")
        patch.set_zorder(0.5)
        ax.add_patch(patch)
        add_label(ax, name, _xy(pose.position), fontsize=7, color="0.3")
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
                arrowprops={"arrowstyle": "->", "color": colour, "lw": 0.8, "alpha": 0.6},
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
    _legend(
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


def save_demonstrations(model: TaskModel, path: Path, heading: str) -> None:
    """Every demonstration of ``model`` from above (like the paper's Fig. 3),
    each with the constraints among its states below it, on shared axes, in
    one image written atomically; ``heading`` names the task in the title."""

    use_agg()
    import matplotlib.pyplot as plt

    demos = model.demonstrations
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
        add_label(ax, scene_label(name, roles), _xy(pose.position), fontsize=7)
    rad = 0.15
    for number, (name, start, end) in enumerate(moves, 1):
        ax.annotate(
            "",
            xy=_xy(end),
            xytext=_xy(start),
            arrowprops={
                "arrowstyle": "->",
                "color": colours[name],
                "lw": 1.2,
                "connectionstyle": f"arc3,rad={rad}",
            },
        )
        add_label(
            ax,
            str(number),
            _arc_middle(_xy(start), _xy(end), rad),
            fontsize=7,
            color=colours[name],
            fontweight="bold",
        )
    for spot in spots:
        add_label(ax, spot.name, _xy(spot.position), fontsize=6, color="0.5")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.08)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or f"Plan: {len(moves)} moves", fontsize=9)
    _legend(
        ax,
        [
            ("faint", "where the objects stand now"),
            ("solid", "where the plan leaves them"),
            ("arrow", "move n of the plan"),
            ("dashed", "free-space spot"),
        ],
    )
    return ax


def _legend(ax: Axes, entries: list[tuple[str, str]]) -> None:
    """A legend of what the marks mean (not of the objects: their names are
    written on them): ``faint``/``solid`` shapes, ``arrow``s, dashed ``outline``s,
    ``dashed`` circles."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Patch

    handles: list[Any] = []
    for mark, text in entries:
        if mark == "faint":
            handles.append(Patch(fc="0.5", alpha=0.25, ec="0.5", label=text))
        elif mark == "solid":
            handles.append(Patch(fc="0.5", alpha=0.85, ec="black", label=text))
        elif mark == "arrow":
            handles.append(Line2D([], [], color="0.3", marker=">", lw=1.2, label=text))
        elif mark == "outline":
            handles.append(Patch(fill=False, ls="--", ec="0.3", label=text))
        else:
            handles.append(Circle((0, 0), 1, fill=False, ls="--", ec="0.6", label=text))
    ax.legend(handles=handles, loc="best", fontsize=6, framealpha=0.8)


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
                outline.set_edgecolor(colours[name])
                outline.set_linestyle("--")
                outline.set_linewidth(1.2)
                ax.add_patch(outline)
                targets.append((name, _xy(spot.position)))
    for obj in sorted(scene.objects, key=lambda o: o.pose.position[2]):
        ax.add_patch(object_patch(obj.pose, geometry[obj.name], colours[obj.name], 0.85))
        add_label(ax, scene_label(obj.name, roles), _xy(obj.pose.position), fontsize=7)
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


LEVEL_TOLERANCE = 0.001
"""Heights (m) closer than this are one level: the plan's objects stack where any
stands or is put down higher than this above the lowest."""


def plan_stacks(scene: Scene, problem: SceneProblem, plan: Plan) -> bool:
    """Whether an object of the scene stands, or is put down by the plan, on
    another level than the rest (its bottom's z differs): a top view hides that."""
    heights = [obj.pose.position[2] for obj in scene.objects]
    heights += [problem.location(a.location).position[2] for a in plan.actions]
    return bool(heights) and max(heights) - min(heights) > LEVEL_TOLERANCE


def side_patch(pose: Pose, geometry: ObjectGeometry | None, colour: str, alpha: float) -> Any:
    """The object's outline seen from the side (looking along y: x across, z up;
    ``pose``'s z is its bottom) as a matplotlib patch: a box's x extent as it
    is turned, a cylinder's diameter, a sphere's circle."""
    from matplotlib import patches

    x, _, z = pose.position
    size = geometry.size if geometry else (0.03, 0.03, 0.03)
    if geometry is not None and geometry.shape in {"cylinder", "sphere"}:
        across = size[0]
    else:
        yaw = 0.0
        if pose.orientation is not None:
            qx, qy, qz, qw = pose.orientation
            yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
        across = abs(size[0] * math.cos(yaw)) + abs(size[1] * math.sin(yaw))
    if geometry is not None and geometry.shape == "sphere":
        return patches.Ellipse(
            (x, z + size[2] / 2), across, size[2], fc=colour, ec="k", alpha=alpha, lw=0.8
        )
    return patches.Rectangle(
        (x - across / 2, z), across, size[2], fc=colour, ec="k", alpha=alpha, lw=0.8
    )


def plot_scene_side(
    scene: Scene,
    problem: SceneProblem,
    plan: Plan,
    ax: Axes | None = None,
    title: str | None = None,
    roles: Mapping[str, str] | None = None,
) -> Axes:
    """A plan in its scene from the side (x across, height z up, the table at
    z = 0): where the objects stand now (faint), where the plan leaves them
    (solid), where a move puts an object down on its way (dashed outline), and
    each move as a numbered arrow: up from the top of the object where it is
    picked up, across above everything (move n at the n-th level), down to
    where its top is once put down, so that unstacking and stacking show.
    ``roles`` (role → instance): as :func:`plot_scene_plan`."""
    import matplotlib.pyplot as plt

    from demoplan.scenes.problems import pose_of

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 3))
    colours = assign_colours(scene.names, scene.given_colours)
    geometry = {obj.name: obj.geometry for obj in scene.objects}
    final = {obj.name: obj.pose for obj in scene.objects}
    moves: list[tuple[str, Pose, Pose]] = []
    for grasp, put in zip(plan.actions[::2], plan.actions[1::2], strict=True):
        source = pose_of(problem.location(grasp.location))
        target = pose_of(problem.location(put.location))
        moves.append((put.object, source, target))
        final[put.object] = target
    last = {name: k for k, (name, _, _) in enumerate(moves)}
    ax.axhline(0.0, color="0.4", lw=0.8)
    draw_landmarks(ax, scene, side=True)
    for obj in sorted(scene.objects, key=lambda o: o.pose.position[2]):
        ax.add_patch(side_patch(obj.pose, geometry[obj.name], colours[obj.name], 0.25))
    between = False
    for k, (name, _, target) in enumerate(moves):
        if last[name] != k:  # put down on its way, moved again later
            outline = side_patch(target, geometry[name], colours[name], 1.0)
            outline.set_fill(False)
            outline.set_edgecolor(colours[name])
            outline.set_linestyle("--")
            outline.set_zorder(1.5)  # over the solid shapes it may stand behind
            ax.add_patch(outline)
            between = True
    for name, pose in sorted(final.items(), key=lambda item: item[1].position[2]):
        ax.add_patch(side_patch(pose, geometry[name], colours[name], 0.85))
        add_label(ax, scene_label(name, roles), _side_middle(pose, geometry[name]), fontsize=7)
    tops = [obj.pose.position[2] + _height(obj.geometry) for obj in scene.objects]
    tops += [target.position[2] + _height(geometry[name]) for name, _, target in moves]
    highest = max(tops, default=0.05)
    spacing = 0.1 * highest
    carry = _draw_side_moves(ax, moves, geometry, colours, highest, spacing)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(x=0.08)
    ax.set_ylim(-0.5 * spacing, carry + 2.5 * spacing)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("height z [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(title or "From the side: the height of each move", fontsize=9)
    entries = [
        ("faint", "where the objects stand now"),
        ("solid", "where the plan leaves them"),
        ("arrow", "move n of the plan"),
    ]
    if between:
        entries.append(("outline", "put down on its way"))
    _legend(ax, entries)
    return ax


def _draw_side_moves(
    ax: Axes,
    moves: Sequence[tuple[str, Pose, Pose]],
    geometry: Mapping[str, ObjectGeometry | None],
    colours: Mapping[str, str],
    highest: float,
    spacing: float,
) -> float:
    """Each move as a numbered arrow (:func:`plot_scene_side`); the height of
    the highest carry."""
    carry = highest
    for number, (name, source, target) in enumerate(moves, 1):
        # Lifted from the top of where it stood, carried above everything (each
        # move a level higher than the one before), set down with its top where
        # the arrow ends.
        (x0, z0), (x1, z1) = _side_top(source, geometry[name]), _side_top(target, geometry[name])
        carry = highest + (number + 0.5) * spacing
        ax.plot([x0, x0, x1], [z0, carry, carry], color=colours[name], lw=1.2)
        ax.annotate(
            "",
            xy=(x1, z1),
            xytext=(x1, carry),
            arrowprops={"arrowstyle": "->", "color": colours[name], "lw": 1.2, "shrinkA": 0},
        )
        add_label(
            ax,
            str(number),
            ((x0 + x1) / 2, carry),
            offset=(0.0, 1.5),
            va="bottom",
            fontsize=7,
            color=colours[name],
            fontweight="bold",
        )
    return carry


def scene_label(name: str, roles: Mapping[str, str] | None) -> str:
    """A scene object's label: ``plate#1 ← plate-b`` where ``roles`` (role →
    instance) has it fill a role of another name, else its name."""
    for role, instance in (roles or {}).items():
        if instance == name:
            return role_label(role, instance)
    return name


def _xy(position: Sequence[float]) -> tuple[float, float]:
    return (float(position[0]), float(position[1]))


def _height(geometry: ObjectGeometry | None) -> float:
    return geometry.size[2] if geometry else 0.03


def _side_middle(pose: Pose, geometry: ObjectGeometry | None) -> tuple[float, float]:
    """The middle of an object seen from the side: (x, z halfway up)."""
    return (float(pose.position[0]), float(pose.position[2]) + _height(geometry) / 2)


def _side_top(pose: Pose, geometry: ObjectGeometry | None) -> tuple[float, float]:
    """The top of an object seen from the side: (x, z of its top)."""
    return (float(pose.position[0]), float(pose.position[2]) + _height(geometry))


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
