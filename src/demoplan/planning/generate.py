"""Generated planning problems for tests and benchmarks (paper §V.B geometry).

Objects are 4 cm blocks on a table; each allows two side grasps, fingers along
x or along y. Collision facts follow the paper's rule for blocks: location a
collides with location b for grasp g if ``|b_p − (a_p ± ĝ_p)| < r + g_r``
(:func:`grasp_collides`), with r = g_r = 2 cm and the finger offset ĝ 4 cm.

- :func:`table_problem`: move N objects from scattered places to their places
  on a table-setting grid; a fraction of the goal places start occupied by
  other objects, and a few free-space spots lie apart.
- :func:`blocks_problem`: build pyramids (two blocks and one bridging them,
  which needs both) from a start where some blocks stand on others.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from demoplan.planning.problem import Problem

__all__ = ["blocks_problem", "collision_facts", "grasp_collides", "table_problem"]

BLOCK = 0.04  # side of a block (m)
RADIUS = BLOCK / 2  # r of §V.B
GRIPPER = BLOCK / 2  # g_r of §V.B
FINGER = BLOCK  # |ĝ_p|: the finger stands one block width beside the centre
_AXES = {"x": (1.0, 0.0), "y": (0.0, 1.0)}


def grasp_collides(a: Sequence[float], a_yaw_deg: float, b: Sequence[float], axis: str) -> bool:
    """The paper's §V.B test: does grasp ``axis`` at location a collide with an
    object at b? Fingers at ``a ± ĝ`` (ĝ rotated with a's yaw), 3-D distance."""
    ux, uy = _AXES[axis]
    yaw = math.radians(a_yaw_deg)
    gx = FINGER * (ux * math.cos(yaw) - uy * math.sin(yaw))
    gy = FINGER * (ux * math.sin(yaw) + uy * math.cos(yaw))
    limit = RADIUS + GRIPPER
    for sign in (1.0, -1.0):
        finger = (a[0] + sign * gx, a[1] + sign * gy, a[2] if len(a) > 2 else 0.0)
        target = (b[0], b[1], b[2] if len(b) > 2 else 0.0)
        if math.dist(finger, target) < limit:
            return True
    return False


def collision_facts(
    locations: dict[str, tuple[float, float, float]],
    grasps: dict[str, str],
) -> list[tuple[str, str, str]]:
    """Facts ``(a, b, g)`` for every pair of locations and every grasp name
    (``grasps`` maps a grasp name to its axis, ``"x"`` or ``"y"``)."""
    facts = []
    for a, pa in locations.items():
        for b, pb in locations.items():
            if a == b:
                continue
            for grasp, axis in grasps.items():
                if grasp_collides(pa, 0.0, pb, axis):
                    facts.append((a, b, grasp))
    return facts


def _problem(
    name: str,
    objects: list[str],
    locations: dict[str, tuple[float, float, float]],
    start: list[str],
    goal: list[str],
    n_freespace: int,
    *,
    free_y: float,
    supports: list[tuple[str, str]] | None = None,
) -> Problem:
    """Add free-space spots (a row apart, spaced so that no grasp there
    collides), two grasps per object and the collision facts."""
    locations = dict(locations)
    freespace = []
    for k in range(n_freespace):
        spot = f"freespace{k + 1}"
        locations[spot] = (0.3 + k * 0.12, free_y, 0.0)
        freespace.append(spot)
    grasp_axes, allowed = _grasps(objects)
    return Problem.create(
        objects=objects,
        locations=list(locations),
        grasps=list(grasp_axes),
        allowed=allowed,
        collisions=collision_facts(locations, grasp_axes),
        initial=list(zip(objects, start, strict=True)),
        goal=list(zip(objects, goal, strict=True)),
        freespace=freespace,
        supports=supports or (),
        name=name,
    )


def _grasps(objects: list[str]) -> tuple[dict[str, str], list[tuple[str, str]]]:
    names: dict[str, str] = {}
    allowed = []
    for index, obj in enumerate(objects):
        for axis in ("x", "y"):
            name = f"grasp{2 * index + (1 if axis == 'x' else 2)}"
            names[name] = axis
            allowed.append((obj, name))
    return names, allowed


def table_problem(
    n_objects: int,
    rng: np.random.Generator | int | None = None,
    *,
    n_freespace: int = 3,
    occupied_goals: float = 0.3,
    spacing: float = 0.06,
    density: float = 5.0,
) -> Problem:
    """Move ``n_objects`` objects to their places (see the module docstring).

    Goal places lie on a grid of about ``density × n_objects`` cells,
    ``spacing`` apart (neighbours along a grasp's axis collide); the objects
    start scattered on a side table, 10 cm apart, except those that start on
    another object's goal place.
    """
    generator = np.random.default_rng(rng)
    objects = [f"obj{i + 1}" for i in range(n_objects)]
    side = math.ceil(math.sqrt(density * n_objects + 4))
    cells = [(i, j) for i in range(side) for j in range(side)]
    goal_cells = [cells[int(k)] for k in generator.permutation(len(cells))[:n_objects]]
    locations: dict[str, tuple[float, float, float]] = {}
    names: dict[tuple[int, int], str] = {}
    for cell in goal_cells:
        names[cell] = f"loc{len(names) + 1}"
        locations[names[cell]] = (0.3 + cell[0] * spacing, 0.1 + cell[1] * spacing, 0.0)
    start = []
    columns = math.ceil(math.sqrt(n_objects))
    for k in range(n_objects):
        name = f"loc{len(locations) + 1}"
        locations[name] = (0.3 + (k % columns) * 0.1, -0.4 - (k // columns) * 0.1, 0.0)
        start.append(name)
    # Some objects start on another object's goal place.
    order = generator.permutation(n_objects)
    for k in range(round(occupied_goals * n_objects)):
        blocker, owner = int(order[k]), int(order[(k + 1) % n_objects])
        if blocker != owner:
            start[blocker] = names[goal_cells[owner]]
    return _problem(
        f"table-{n_objects}",
        objects,
        locations,
        start,
        [names[c] for c in goal_cells],
        n_freespace,
        free_y=-0.2,
    )


def blocks_problem(
    n_objects: int,
    rng: np.random.Generator | int | None = None,
    *,
    n_freespace: int = 3,
    stacked_start: float = 0.3,
) -> Problem:
    """Build pyramids of three 4 cm blocks (blocks left over stay single)."""
    generator = np.random.default_rng(rng)
    objects = [f"block{i + 1}" for i in range(n_objects)]
    locations: dict[str, tuple[float, float, float]] = {}
    supports: list[tuple[str, str]] = []
    goal_locations: list[str] = []
    x = 0.3
    remaining = n_objects
    while remaining > 0:
        if remaining >= 3:
            left, right, top = (f"loc{len(locations) + k + 1}" for k in range(3))
            locations[left] = (x, 0.3, 0.0)
            locations[right] = (x + BLOCK, 0.3, 0.0)
            locations[top] = (x + BLOCK / 2, 0.3, BLOCK)
            supports += [(top, left), (top, right)]
            goal_locations += [left, right, top]
            x += 3 * BLOCK + 0.04
            remaining -= 3
        else:
            name = f"loc{len(locations) + 1}"
            locations[name] = (x, 0.3, 0.0)
            goal_locations.append(name)
            x += 2 * BLOCK
            remaining -= 1
    goal_order = [goal_locations[int(k)] for k in generator.permutation(n_objects)]
    # Start: scattered on a grid in front, some standing on another block.
    side = math.ceil(math.sqrt(n_objects + 2))
    cells = [(i, j) for i in range(side) for j in range(side)]
    start: list[str] = []
    towers: list[str] = []
    for cell in (cells[int(k)] for k in generator.permutation(len(cells))):
        if len(start) == n_objects:
            break
        name = f"loc{len(locations) + 1}"
        locations[name] = (0.3 + cell[0] * 0.09, -0.05 - cell[1] * 0.09, 0.0)
        start.append(name)
        towers.append(name)
        if len(start) < n_objects and generator.random() < stacked_start:
            upper = f"loc{len(locations) + 1}"
            locations[upper] = (locations[name][0], locations[name][1], BLOCK)
            supports.append((upper, name))
            start.append(upper)
    return _problem(
        f"blocks-{n_objects}",
        objects,
        locations,
        start,
        goal_order,
        n_freespace,
        free_y=-0.5,
        supports=supports,
    )
