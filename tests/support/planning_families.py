"""Generated planning problems for tests and benchmarks (paper §V.B geometry);
benchmarks/planning.py imports them from here too.

Objects are 4 cm blocks on a table; each allows two side grasps, fingers along
x or along y. Collision facts follow the paper's rule for blocks: location a
collides with location b for grasp g if ``|b_p − (a_p ± ĝ_p)| < r + g_r``
(:func:`grasp_collides`), with r = g_r = 2 cm and the finger offset ĝ 4 cm.

- :func:`table_problem`: move N objects from scattered places to their places
  on a table-setting grid; a fraction of the goal places start occupied by
  other objects, and a few free-space spots lie apart.
- :func:`blocks_problem`: build pyramids (two blocks and one bridging them,
  which needs both) from a start where some blocks stand on others.
- :func:`parking_problem`: the hard kind, where objects must be parked: a
  dense grid whose neighbours collide for a grasp, objects that start on each
  other's goal places in cycles (swaps and longer), distractors (objects
  without a goal) standing on goal places, and objects starting on the
  grid's free cells between goal places; two free-space spots.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from demoplan.planning.problem import Problem

__all__ = [
    "CROWDED_FAMILIES",
    "PARKING_FAMILIES",
    "blocks_problem",
    "collision_facts",
    "grasp_collides",
    "parking_problem",
    "ring_problem",
    "table_problem",
]

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
    (``grasps`` maps a grasp name to its axis, ``"x"`` or ``"y"``), in the
    order of ``locations`` (a, then b) and of ``grasps``.

    The pairs near enough are found for each axis at once (NumPy), and each is
    decided by :func:`grasp_collides` itself: the same facts as asking it of
    every pair and grasp, without the hundreds of thousands of calls (a crowded
    parking draw of 30 objects: 80 locations, 60 grasps)."""
    names = list(locations)
    points = np.array([(*p[:2], p[2] if len(p) > 2 else 0.0) for p in locations.values()])
    colliding = {axis: _colliding_pairs(names, locations, points, axis) for axis in _AXES}
    pairs = sorted(set().union(*colliding.values()))  # a's index, then b's: the order asked
    return [
        (names[i], names[j], grasp)
        for i, j in pairs
        for grasp, axis in grasps.items()
        if (i, j) in colliding[axis]
    ]


def _colliding_pairs(
    names: list[str],
    locations: dict[str, tuple[float, float, float]],
    points: np.ndarray,
    axis: str,
) -> set[tuple[int, int]]:
    """The index pairs (a, b), a ≠ b, where grasp ``axis`` at a collides with b."""
    finger = FINGER * np.array([*_AXES[axis], 0.0])
    limit = RADIUS + GRIPPER + 1e-9  # a margin over rounding: grasp_collides decides
    near = np.zeros((len(names), len(names)), dtype=bool)
    for sign in (1.0, -1.0):
        fingers = points + sign * finger
        near |= np.linalg.norm(fingers[:, None, :] - points[None, :, :], axis=2) < limit
    np.fill_diagonal(near, False)
    return {
        (int(i), int(j))
        for i, j in zip(*np.nonzero(near), strict=True)
        if grasp_collides(locations[names[i]], 0.0, locations[names[j]], axis)
    }


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
        goal=list(zip(objects[: len(goal)], goal, strict=True)),  # the first ones have goals
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


PARKING_FAMILIES: dict[str, dict[str, float]] = {
    "parking": {"cycled": 0.3, "distractors": 0.1, "on_grid": 0.2, "density": 3.0},
    "parking-dense": {"cycled": 0.5, "distractors": 0.2, "on_grid": 0.3, "density": 2.0},
    "parking-crowded": {"cycled": 0.7, "distractors": 0.3, "on_grid": 0.5, "density": 1.5},
}
"""Two settings of :func:`parking_problem` for tests and benchmarks: ``parking``
(about half of which the A* of before the anytime planner could not solve in
20 s at 15–30 objects), ``parking-dense`` (more cycles, distractors and
neighbours) and ``parking-crowded`` (most objects in cycles or on the grid, a
grid barely larger than the objects: the hardest we generate, beyond the
planner's reach at 20–30 objects — some draws defeat Fast Downward's
lama-first too)."""

CROWDED_FAMILIES: dict[str, dict[str, float]] = {
    "crowded-swaps": {"cycled": 0.9, "distractors": 0.4, "on_grid": 0.5, "density": 1.4},
    "crowded-distractors": {"cycled": 0.6, "distractors": 0.6, "on_grid": 0.5, "density": 1.6},
    "crowded-stacks": {
        "cycled": 0.7,
        "distractors": 0.3,
        "on_grid": 0.5,
        "density": 1.5,
        "stacked": 0.2,
    },
}
"""Crowded tables for the comparison with lama-first (issue 44;
``tests/data/planning/crowded/``): parking forced by swaps and 3-cycles *and*
distractors on goal places, on a grid barely larger than the objects —
``crowded-swaps`` nearly every object in a cycle, ``crowded-distractors``
more distractors than cycles, ``crowded-stacks`` parking-crowded with caps
stacked on a fifth of the objects (which the tight phase does not take: it
plans flat problems only)."""


def parking_problem(
    n_objects: int,
    rng: np.random.Generator | int | None = None,
    **options: Any,
) -> Problem:
    """:func:`parking_draw` until the draw is not unsolvable on its face
    (:func:`~demoplan.planning.search.explain_unsolvable`: a goal place every
    grasp of which the other goals block, a start where objects block each
    other for good) — at most 100 draws."""
    from demoplan.planning.search import explain_unsolvable

    generator = np.random.default_rng(rng)
    for _ in range(100):
        problem = parking_draw(n_objects, generator, **options)
        if not explain_unsolvable(problem):
            return problem
    raise ValueError(f"no solvable-looking parking problem with {n_objects} objects in 100 draws")


def parking_draw(
    n_objects: int,
    rng: np.random.Generator | int | None = None,
    *,
    n_freespace: int = 2,
    cycled: float = 0.5,
    distractors: float = 0.2,
    on_grid: float = 0.3,
    density: float = 2.0,
    stacked: float = 0.0,
) -> Problem:
    """A table problem where parking is forced (see the module docstring); it
    may be unsolvable (:func:`parking_problem` draws until it is not on its face).

    Goal places lie on a grid of about ``density × n_objects`` cells 6 cm
    apart, so neighbours along a grasp's axis block that grasp. A share
    ``cycled`` of the objects start on one another's goal places in cycles of
    two or three (each needs a parking move or a free goal place first);
    ``distractors × n_objects`` extra objects without a goal (``distractor1``
    …) stand on other goal places; of the rest, a share ``on_grid`` start on
    free grid cells (in the way of their neighbours' grasps), the others on a
    side table. ``stacked × n_objects`` further distractors (``cap1`` …) stand
    on top of objects with a goal (a ``support`` fact): each must be lifted
    off, and parked, before the object under it can be grasped.
    """
    generator = np.random.default_rng(rng)
    objects = [f"obj{i + 1}" for i in range(n_objects)]
    n_distractors = round(distractors * n_objects)
    side = math.ceil(math.sqrt(density * n_objects + n_distractors + 2))
    cells = [(i, j) for i in range(side) for j in range(side)]
    shuffled = [cells[int(k)] for k in generator.permutation(len(cells))]
    goal_cells, spare_cells = shuffled[:n_objects], shuffled[n_objects:]
    locations: dict[str, tuple[float, float, float]] = {}
    cell_name: dict[tuple[int, int], str] = {}
    for cell in (*goal_cells, *spare_cells):
        cell_name[cell] = f"loc{len(locations) + 1}"
        locations[cell_name[cell]] = (0.3 + cell[0] * 0.06, 0.1 + cell[1] * 0.06, 0.0)
    goal = [cell_name[c] for c in goal_cells]
    start: list[str | None] = [None] * n_objects
    order = [int(k) for k in generator.permutation(n_objects)]
    n_cycled = round(cycled * n_objects)
    k = 0
    while n_cycled - k >= 2:  # cycles of 2 or 3: each object on the next one's goal
        length = 3 if n_cycled - k >= 5 and generator.random() < 0.5 else 2
        cycle = order[k : k + length]
        for a, b in zip(cycle, cycle[1:] + cycle[:1], strict=True):
            start[a] = goal[b]
        k += length
    rest = order[k:]
    free_goal_places = [goal[o] for o in rest]
    generator.shuffle(free_goal_places)
    distractor_places = free_goal_places[:n_distractors]
    grid_cells = [cell_name[c] for c in spare_cells]
    table_row = 0
    for obj in rest:
        if grid_cells and generator.random() < on_grid:
            start[obj] = grid_cells.pop()
        else:
            name = f"loc{len(locations) + 1}"
            locations[name] = (0.3 + table_row * 0.1, -0.3, 0.0)
            table_row += 1
            start[obj] = name
    names = objects + [f"distractor{i + 1}" for i in range(len(distractor_places))]
    starts = [s for s in start if s is not None] + distractor_places
    supports: list[tuple[str, str]] = []
    if stacked > 0:
        capped = generator.permutation(n_objects)[: round(stacked * n_objects)]
        for index, under in enumerate(capped):
            lower = starts[int(under)]
            upper = f"loc{len(locations) + 1}"
            x, y, _ = locations[lower]
            locations[upper] = (x, y, BLOCK)
            supports.append((upper, lower))
            names.append(f"cap{index + 1}")
            starts.append(upper)
    assert len(starts) == len(names)
    return _problem(
        f"parking-{n_objects}",
        names,
        locations,
        starts,
        goal,
        n_freespace,
        free_y=-0.45,
        supports=supports,
    )


def ring_problem(n: int) -> Problem:
    """n objects, 2n locations: each object to the next one's target row, each
    target blocking its neighbour's grasp."""
    objects = [f"o{i}" for i in range(n)]
    return Problem.create(
        objects=objects,
        locations=[f"s{i}" for i in range(n)] + [f"t{i}" for i in range(n)],
        grasps=[f"g{i}" for i in range(n)],
        allowed=[(o, f"g{i}") for i, o in enumerate(objects)],
        collisions=[(f"t{i}", f"t{i + 1}", f"g{i}") for i in range(n - 1)],
        initial=[(o, f"s{i}") for i, o in enumerate(objects)],
        goal=[(o, f"t{(i + 1) % n}") for i, o in enumerate(objects)],
    )
