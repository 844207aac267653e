"""Top-view plots of demonstrations (like the paper's Fig. 3 and Fig. 4, left) and plans.

matplotlib is imported lazily (the ``plot`` extra); every function takes an
optional ``ax`` and returns the axes it drew on.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.colours import object_colour
from demoplan.learning.constraints import GoalOrder
from demoplan.model import Demonstration, ObjectGeometry, Pose, TaskModel

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from demoplan.planning.problem import Plan
    from demoplan.scenes.problems import SceneProblem
    from demoplan.scenes.scene import Scene

__all__ = [
    "constraint_caption",
    "object_colour",
    "object_patch",
    "plot_constraints",
    "plot_demonstration",
    "plot_scene_plan",
    "plot_scene_targets",
    "save_figure",
    "save_scene_plan",
    "save_scene_targets",
    "share_limits",
]


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


def plot_demonstration(
    demo: Demonstration, ax: Axes | None = None, *, title: str | None = None
) -> Axes:
    """Draw one demonstration from above: initial poses faint, each step's placement
    solid and numbered in the order it happened, an arrow for every move."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    geometry = demo.geometry()
    current = demo.initial_poses()
    for name, pose in demo.landmarks:
        ax.add_patch(object_patch(pose, geometry.get(name), "#cccccc", 0.5))
        ax.annotate(name, pose.position[:2], ha="center", va="center", fontsize=7, color="0.3")
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
        ax.annotate(
            f"{number} {step.object}", (x, y), xytext=(4, 4), textcoords="offset points", fontsize=7
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
        ax.annotate(
            objects[label.split("#")[0]], (px, py - 0.32), ha="center", fontsize=6, color="0.4"
        )
    ax.set_xlim(-0.6, max(depth.values(), default=0) + 0.6)
    spread = max((len(m) for m in layers.values()), default=1)
    ax.set_ylim(-spread / 2 - 0.3, spread / 2 + 0.1)
    ax.axis("off")
    ax.set_title(constraint_caption(order), fontsize=8)
    return ax


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
) -> Axes:
    """A plan in its scene from above: where the objects stand now (faint), where
    the plan leaves them (solid, higher objects drawn last) and each move as a
    numbered arrow; free-space spots as dashed circles."""
    import matplotlib.pyplot as plt
    from matplotlib import patches

    from demoplan.scenes.problems import pose_of

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 5))
    colours = {obj.name: object_colour(obj.name) for obj in scene.objects}
    geometry = {obj.name: obj.geometry for obj in scene.objects}
    final = {obj.name: obj.pose for obj in scene.objects}
    moves = []
    for grasp, put in zip(plan.actions[::2], plan.actions[1::2], strict=True):
        source, target = problem.location(grasp.location), problem.location(put.location)
        moves.append((grasp.object, source.position, target.position))
        final[put.object] = pose_of(target)
    for spot in problem.locations:
        if spot.kind == "freespace":
            radius = max(max(s.size[0], s.size[1]) for s in spot.shapes) / 2
            ax.add_patch(
                patches.Circle(spot.position[:2], radius, fill=False, ls="--", ec="0.6", lw=0.8)
            )
            ax.annotate(spot.name, spot.position[:2], fontsize=6, color="0.5", ha="center")
    for obj in sorted(scene.objects, key=lambda o: o.pose.position[2]):
        ax.add_patch(object_patch(obj.pose, geometry[obj.name], colours[obj.name], 0.25))
    for name, pose in sorted(final.items(), key=lambda item: item[1].position[2]):
        ax.add_patch(object_patch(pose, geometry[name], colours[name], 0.85))
        ax.annotate(name, pose.position[:2], fontsize=7, ha="center", va="center")
    for number, (name, start, end) in enumerate(moves, 1):
        ax.annotate(
            "",
            xy=end[:2],
            xytext=start[:2],
            arrowprops={
                "arrowstyle": "->",
                "color": colours[name],
                "lw": 1.2,
                "connectionstyle": "arc3,rad=0.15",
            },
        )
        middle = ((start[0] + end[0]) / 2, (start[1] + end[1]) / 2)
        ax.annotate(str(number), middle, fontsize=7, color=colours[name], fontweight="bold")
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
    written on them): ``faint``/``solid`` shapes, ``arrow``s, ``dashed`` circles."""
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
        else:
            handles.append(Circle((0, 0), 1, fill=False, ls="--", ec="0.6", label=text))
    ax.legend(handles=handles, loc="best", fontsize=6, framealpha=0.8)


def plot_scene_targets(
    scene: Scene, problem: SceneProblem, reason: str, ax: Axes | None = None, title: str = ""
) -> Axes:
    """A scene that has no plan, from above: the objects where they stand
    (solid), the targets of one candidate goal as dashed outlines named after
    their objects, the free-space spots, and why there is no plan (wrapped
    under the title)."""
    import textwrap

    import matplotlib.pyplot as plt
    from matplotlib import patches

    from demoplan.scenes.problems import pose_of

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 5))
    colours = {obj.name: object_colour(obj.name) for obj in scene.objects}
    geometry = {obj.name: obj.geometry for obj in scene.objects}
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
                ax.annotate(
                    f"{name}'s target",
                    spot.position[:2],
                    fontsize=6,
                    color=colours[name],
                    ha="center",
                    va="top",
                )
    for obj in sorted(scene.objects, key=lambda o: o.pose.position[2]):
        ax.add_patch(object_patch(obj.pose, geometry[obj.name], colours[obj.name], 0.85))
        ax.annotate(obj.name, obj.pose.position[:2], fontsize=7, ha="center", va="center")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.12)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    heading = title or "No plan"
    ax.set_title(heading + "\n" + textwrap.fill(reason, 90), fontsize=8)
    return ax


def save_scene_targets(
    scene: Scene, problem: SceneProblem, reason: str, path: Path, title: str
) -> None:
    """:func:`plot_scene_targets` into an image file, written atomically."""
    _save_one_axes(lambda ax: plot_scene_targets(scene, problem, reason, ax, title), path)


def _save_one_axes(draw: Callable[[Axes], object], path: Path) -> None:
    """A one-axes figure drawn by ``draw``, saved atomically (raises ImportError
    without matplotlib)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, ax = plt.subplots(figsize=(6.5, 5.8))
    try:
        draw(ax)
        figure.tight_layout()
        save_figure(figure, path)
    finally:
        plt.close(figure)


FIGURE_FORMATS = frozenset(
    {"png", "pdf", "svg", "svgz", "jpg", "jpeg", "tif", "tiff", "webp", "eps", "ps", "gif"}
)
"""Image formats a figure can be written in, by file extension."""


def check_figure_path(path: Path, option: str) -> None:
    """One InputError, before any work, if ``path`` cannot take a figure: a
    folder, or an extension that names no image format."""
    from demoplan.errors import InputError
    from demoplan.fileio import display_path

    if path.is_dir():
        raise InputError(
            "is a folder; an image file name expected", source=display_path(path), field=option
        )
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in FIGURE_FORMATS:
        raise InputError(
            f"'.{suffix}' is not an image format; one of "
            f"{', '.join('.' + f for f in sorted(FIGURE_FORMATS))} expected",
            source=display_path(path),
            field=option,
        )


def figure_bytes(figure: Any, path: Path, dpi: int = 110) -> bytes:
    """``figure`` encoded in the image format of ``path``'s extension."""
    import io

    check_figure_path(path, "figure")
    buffer = io.BytesIO()
    figure.savefig(buffer, format=path.suffix.lower().lstrip("."), dpi=dpi)
    return buffer.getvalue()


def save_figure(figure: Any, path: Path, dpi: int = 110) -> None:
    """Write ``figure`` to ``path`` atomically (a temporary file, then a rename)."""
    from demoplan.fileio import write_atomic_bytes

    write_atomic_bytes(path, figure_bytes(figure, path, dpi))


def save_scene_plan(
    scene: Scene, problem: SceneProblem, plan: Plan, path: Path, title: str
) -> None:
    """:func:`plot_scene_plan` into an image file, written atomically (raises
    ImportError without matplotlib)."""
    _save_one_axes(lambda ax: plot_scene_plan(scene, problem, plan, ax, title), path)
