"""A plan in its scene from the side (x across, height z up), drawn beside its
top view where the plan stacks (:func:`plan_stacks`): unstacking and stacking
show as each move's arrow up, across and down.

matplotlib is imported lazily (the ``plot`` extra).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from demoplan.model import ObjectGeometry, Pose
from demoplan.plotting.colours import assign_colours, ink
from demoplan.plotting.labels import add_label
from demoplan.plotting.patches import (
    draw_landmarks,
    height,
    legend,
    scene_label,
    side_middle,
    side_patch,
    side_top,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from demoplan.planning.problem import Plan
    from demoplan.scenes.problems import SceneProblem
    from demoplan.scenes.scene import Scene

__all__ = ["LEVEL_TOLERANCE", "plan_stacks", "plot_scene_side"]


LEVEL_TOLERANCE = 0.001
"""Heights (m) closer than this are one level: the plan's objects stack where any
stands or is put down higher than this above the lowest."""


def plan_stacks(scene: Scene, problem: SceneProblem, plan: Plan) -> bool:
    """Whether an object of the scene stands, or is put down by the plan, on
    another level than the rest (its bottom's z differs): a top view hides that."""
    heights = [obj.pose.position[2] for obj in scene.objects]
    heights += [problem.location(a.location).position[2] for a in plan.actions]
    return bool(heights) and max(heights) - min(heights) > LEVEL_TOLERANCE


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
            outline.set_edgecolor(ink(colours[name]))
            outline.set_linestyle("--")
            outline.set_zorder(1.5)  # over the solid shapes it may stand behind
            ax.add_patch(outline)
            between = True
    for name, pose in sorted(final.items(), key=lambda item: item[1].position[2]):
        ax.add_patch(side_patch(pose, geometry[name], colours[name], 0.85))
        add_label(ax, scene_label(name, roles), side_middle(pose, geometry[name]), fontsize=7)
    tops = [obj.pose.position[2] + height(obj.geometry) for obj in scene.objects]
    tops += [target.position[2] + height(geometry[name]) for name, _, target in moves]
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
    legend(ax, entries)
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
        (x0, z0), (x1, z1) = side_top(source, geometry[name]), side_top(target, geometry[name])
        carry = highest + (number + 0.5) * spacing
        line = ink(colours[name])
        ax.plot([x0, x0, x1], [z0, carry, carry], color=line, lw=1.2)
        ax.annotate(
            "",
            xy=(x1, z1),
            xytext=(x1, carry),
            arrowprops={"arrowstyle": "->", "color": line, "lw": 1.2, "shrinkA": 0},
        )
        add_label(
            ax,
            str(number),
            ((x0 + x1) / 2, carry),
            offset=(0.0, 1.5),
            va="bottom",
            fontsize=7,
            color=line,
            fontweight="bold",
        )
    return carry
