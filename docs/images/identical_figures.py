"""Render the figures of "Identical objects" in docs/learning.md and docs/planning.md.

From the repository root::

    python docs/images/identical_figures.py

learns the generated table for two (tests/support/identical_families.py: two plates,
forks, knives and glasses, instance names shuffled between three
demonstrations) and writes ``identical-roles.png`` (which instance filled
which role in each demonstration) and ``identical-binding.png`` (a scene's
instances given the roles by the planner, and its plan) next to this file.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

HERE = Path(__file__).resolve().parent
# the repository root, for tests.support.identical_families
sys.path.insert(1, str(HERE.parent.parent))

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402
from tests.support.identical_families import TABLE_TYPES, table_for_two, table_scene  # noqa: E402

from demoplan.budget import Clock  # noqa: E402
from demoplan.learning.learner import learn  # noqa: E402
from demoplan.model import ObjectGeometry, TaskModel  # noqa: E402
from demoplan.planning.search import Budget  # noqa: E402
from demoplan.scenes.plan import plan_in_scene  # noqa: E402
from demoplan.scenes.prepared import prepare  # noqa: E402
from demoplan.scenes.problems import pose_of  # noqa: E402

ORDERS = [
    {"plate": (0, 1), "fork": (1, 0), "knife": (0, 1), "glass": (1, 0)},
    {"plate": (1, 0), "fork": (0, 1), "knife": (1, 0), "glass": (1, 0)},
    {"plate": (0, 1), "fork": (0, 1), "knife": (1, 0), "glass": (0, 1)},
]
ROLE_COLOURS = {"#1": "tab:blue", "#2": "tab:orange"}


def _outline(axes: Axes, shape: ObjectGeometry, x: float, y: float, colour: str) -> None:
    if shape.shape == "box":
        w, h = shape.size[0], shape.size[1]
        axes.add_patch(Rectangle((x - w / 2, y - h / 2), w, h, fill=False, ec=colour, lw=1.5))
    else:
        axes.add_patch(Circle((x, y), shape.size[0] / 2, fill=False, ec=colour, lw=1.5))


def _roles_figure(model: TaskModel, path: Path) -> None:
    figure, panels = plt.subplots(1, len(model.demonstrations), figsize=(10, 6), sharey=True)
    instance_of = {role.name: role.instances for role in model.roles}
    for index, (axes, demo) in enumerate(zip(panels, model.demonstrations, strict=True)):
        shapes = dict(demo.objects)
        for step in demo.steps:
            role = step.object
            colour = ROLE_COLOURS[role[role.index("#") :]]
            x, y = step.pose.position[:2]
            _outline(axes, shapes[role], x, y, colour)
            instance = instance_of[role][index]
            axes.annotate(
                f"{instance}\n→ {role}",
                (x, y),
                fontsize=6.5,
                ha="center",
                va="center",
                color=colour,
            )
        axes.set_title(f"demonstration {index + 1} ({demo.name})", fontsize=9)
        axes.set_aspect("equal")
        axes.set_xlim(0.15, 0.7)
        axes.set_ylim(-0.5, 0.6)
        axes.set_xlabel("x [m]")
    panels[0].set_ylabel("y [m]")
    figure.suptitle(
        "Correspondence: each demonstration's instances renamed to the roles their placements "
        "agree on (blue #1, orange #2)",
        fontsize=10,
    )
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def _binding_figure(model: TaskModel, path: Path) -> None:
    scene = table_scene(np.random.default_rng(5), {k: (1, 0) for k in TABLE_TYPES})
    result = plan_in_scene(model, prepare(model, scene), clock=Clock(Budget(timeout=math.inf)))
    chosen = result.chosen
    assert chosen.plan is not None
    role_of = {instance: role for role, instance in chosen.binding.pairs}
    figure, axes = plt.subplots(figsize=(8, 6))
    for obj in scene.objects:
        assert obj.geometry is not None
        x, y = obj.pose.position[:2]
        role = role_of.get(obj.name, "")
        colour = ROLE_COLOURS.get(role[role.index("#") :] if "#" in role else "", "grey")
        _outline(axes, obj.geometry, x, y, colour)
        axes.annotate(obj.name, (x, y - 0.07), fontsize=7, ha="center", color=colour)
    problem = chosen.problem
    for grasp, put in zip(chosen.plan.actions[::2], chosen.plan.actions[1::2], strict=True):
        start = pose_of(problem.location(grasp.location)).position[:2]
        end = pose_of(problem.location(put.location)).position[:2]
        role = role_of[put.object]
        colour = ROLE_COLOURS[role[role.index("#") :]]
        axes.annotate(
            "", end, start, arrowprops={"arrowstyle": "->", "color": colour, "alpha": 0.6}
        )
        shape = next(o.geometry for o in scene.objects if o.name == put.object)
        assert shape is not None
        _outline(axes, shape, end[0], end[1], colour)
        axes.annotate(role, end, fontsize=7, ha="center", va="center", color=colour)
    axes.set_aspect("equal")
    axes.set_xlim(0.1, 1.05)
    axes.set_ylim(-0.9, 0.6)
    axes.set_xlabel("x [m]")
    axes.set_ylabel("y [m]")
    axes.set_title(
        f"Assignment: {len(chosen.plan)} actions, each object moved once, proved shortest "
        f"over {chosen.bindings_weighed} bindings",
        fontsize=10,
    )
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def main() -> None:
    taught = table_for_two(np.random.default_rng(3), ORDERS)
    model = learn(taught.demonstrations)
    _roles_figure(model, HERE / "identical-roles.png")
    _binding_figure(model, HERE / "identical-binding.png")
    print(f"wrote {HERE / 'identical-roles.png'} and {HERE / 'identical-binding.png'}")


if __name__ == "__main__":
    main()
