"""Geometry of a scene for the planner (paper §IV.C, §V.B): footprints, grasps,
collision facts, support and free space.

Every location is a pose with the objects it was made for (the object standing
there now, the object whose target it is; both when a target coincides with an
occupied spot). Its footprint is the union of those objects' outlines on the
table (boxes rotated by their yaw, cylinders and spheres as discs); it spans
heights ``bottom..top``.

- **Grasps.** A grasp is a finger axis u in the object's frame. The fingers are
  discs of radius g_r (``Gripper.finger_radius``) at ``a ± ĝ``, ĝ = u rotated
  with the location's yaw, ``|ĝ|`` = half the object's extent along u + g_r
  (+ clearance): the fingers touch the object's sides.
- **Collision facts** ``(a, b, g)``: grasp g at a hits whatever stands at b.
  Blocks (cubes) at both: the paper's §V.B rule ``|b_p − (a_p ± ĝ_p)| < r + g_r``
  with r the block's half side, in 3-D. Any other shapes: a finger disc reaches
  into b's footprint and b rises above a's bottom (the fingers come from above).
- **Support.** A location above the table (bottom > ``level_tolerance``) holds
  an object only while every location whose top is at its bottom and whose
  footprint overlaps it is occupied (a block bridging two needs both). A
  location made for several objects has a top for each of them; any matches.
- **Exclusion.** Two locations whose footprints overlap (after shrinking each by
  ``touch_tolerance``, so touching neighbours do not) at overlapping heights,
  and neither supports the other, cannot both be occupied.
- **What a location takes.** The objects it was made for, and any other object
  as tall as one of them whose outline there lies within the location's
  footprint (grown by ``touch_tolerance``): a smaller object on a bigger
  object's spot, never the food on a fork's spot. A free-space spot is a disc
  (:func:`spot_shape`) and takes every object whose outline fits in it turned
  any way (the scene's own spots are sized for the largest object).
- **Free space** (when the scene gives none): ``n_freespace`` spots on a grid
  over the table (the scene's ``table``, else the one
  :mod:`demoplan.scenes.table` infers), each sized for an object (the k-th
  spot for the k-th largest, a smaller one where that has no room) and far
  enough from every location, landmark outline and other spot that no grasp
  there or next to it collides, nearest to the centre of the targets first;
  then a spot for any object none takes yet (:func:`free_space`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from demoplan.budget import check_time
from demoplan.model import (
    LEVEL_TOLERANCE,
    SUPPORT_FRACTION,
    ObjectGeometry,
    Vector3,
    footprint,
)
from demoplan.scenes.scene import Gripper, Scene

__all__ = [
    "MAX_GRID",
    "FreeSpot",
    "GeometrySettings",
    "Location",
    "accepted_objects",
    "collision_facts",
    "exclusions",
    "finger_offset",
    "footprint",
    "free_space",
    "is_block",
    "spot_reach",
    "spot_shape",
    "supports",
    "symmetry",
    "yaw_difference",
]


MAX_GRID = 250_000
"""Most candidate free-space spots searched (the grid coarsens on a wider table)."""


class CollisionSimulator(Protocol):
    """Decides collision facts ``(a, b, g)`` by simulation: for grasps
    ``(name, object, shape, axis)`` at the (location, grasp) ``pairs``, the
    facts and the pairs it could not reach to check."""

    def __call__(
        self,
        scene: Scene,
        locations: Sequence[Location],
        grasps: Sequence[tuple[str, str, ObjectGeometry, float]],
        pairs: set[tuple[str, str]],
    ) -> tuple[list[tuple[str, str, str]], list[tuple[str, str]]]: ...


@dataclass(frozen=True, slots=True)
class GeometrySettings:
    """Tolerances and defaults of scene geometry (metres)."""

    merge_distance: float = 0.01
    """A target closer than this (and at the same height) to a location is that location."""
    merge_angle: float = 5.0
    """… and, when its orientation was learned, turned less than this (deg) from it."""
    level_tolerance: float = LEVEL_TOLERANCE
    """Heights closer than this are one level (a top meets a bottom)."""
    touch_tolerance: float = 0.002
    """Footprints overlapping by less than this are neighbours, not in each other's way."""
    support_fraction: float = SUPPORT_FRACTION
    """An upper footprint rests on a lower one that covers at least this fraction of it."""
    n_freespace: int = 3
    """Free-space spots generated when the scene gives none."""
    table_margin: float = 0.15
    """How far around the scene's poses generated free space may lie, where the
    demonstrations' workspace has no room (docs/scenes.md "Free space")."""
    workspace_margin: float = 0.1
    """How far around the demonstrations' workspace free space is sought first:
    the table the studio draws for them."""
    grid_step: float = 0.01
    """Spacing of the candidate free-space spots."""
    collisions: str = "rule"
    """Where collision facts come from: ``rule`` (the finger discs, §V.B) or
    ``simulation`` (the arm of ``--sim arm`` posed in MuJoCo, §IV.C's path
    planner: :mod:`demoplan.execution.collision_simulation`, given as
    ``simulator``)."""
    simulator: CollisionSimulator | None = None
    """What decides the facts with ``collisions="simulation"``: the command layer
    gives the arm's (:func:`demoplan.commands.settings.geometry_settings`)."""


@dataclass(frozen=True, slots=True)
class Location:
    """A place an object can stand: pose, the objects it was made for, and its kind
    (``current``, ``target``, ``current+target`` or ``freespace``)."""

    name: str
    position: Vector3
    yaw: float
    kind: str
    objects: tuple[str, ...]
    shapes: tuple[ObjectGeometry, ...]

    @property
    def bottom(self) -> float:
        return self.position[2]

    @property
    def top(self) -> float:
        return self.position[2] + max(shape.size[2] for shape in self.shapes)


def symmetry(shape: ObjectGeometry) -> float:
    """The turn (deg) after which the shape looks the same from above
    (:attr:`ObjectGeometry.yaw_period`, which learning uses too): 90° for a
    square box, 180° for other boxes, 0 (any turn) for cylinders and spheres,
    360° for meshes."""
    return shape.yaw_period


def yaw_difference(shape: ObjectGeometry, a: float, b: float) -> float:
    """How far apart two yaws (deg) of ``shape`` look, given its symmetry."""
    period = symmetry(shape)
    if period == 0.0:
        return 0.0
    return abs(((a - b + period / 2) % period) - period / 2)


def is_block(shape: ObjectGeometry) -> bool:
    """A cube (to 1 mm): the shape §V.B's collision rule is stated for."""
    sx, sy, sz = shape.size
    return shape.shape == "box" and max(sx, sy, sz) - min(sx, sy, sz) <= 0.001


@functools.lru_cache(maxsize=4096)
def location_footprint(location: Location) -> BaseGeometry:
    """The union of the outlines of the objects a location is made for (cached:
    collision facts, support, exclusion and what a location takes all need it)."""
    shapes = [footprint(s, location.position, location.yaw) for s in location.shapes]
    return shapely.union_all(shapes)


def half_extent(shape: ObjectGeometry, axis: float) -> float:
    """Half the object's width along the finger axis ``axis`` (degrees, object frame)."""
    if shape.shape != "box":
        return max(shape.size[0], shape.size[1]) / 2
    c, s = abs(math.cos(math.radians(axis))), abs(math.sin(math.radians(axis)))
    return c * shape.size[0] / 2 + s * shape.size[1] / 2


def finger_offset(shape: ObjectGeometry, axis: float, gripper: Gripper) -> float:
    """``|ĝ|``: from the object's centre to a finger's centre along the grasp axis."""
    return half_extent(shape, axis) + gripper.finger_radius + gripper.clearance


def bounding_radius(shape: ObjectGeometry) -> float:
    if shape.shape == "box":
        return math.hypot(shape.size[0], shape.size[1]) / 2
    return max(shape.size[0], shape.size[1]) / 2


def fingers(location: Location, shape: ObjectGeometry, axis: float, gripper: Gripper) -> np.ndarray:
    """The two finger centres ``a ± ĝ`` (2×3) of grasp ``axis`` for ``shape`` at ``location``."""
    offset = finger_offset(shape, axis, gripper)
    angle = math.radians(location.yaw + axis)
    g = np.array([offset * math.cos(angle), offset * math.sin(angle), 0.0])
    a = np.asarray(location.position, dtype=float)
    return np.stack([a + g, a - g])


TOUCHING = 1e-9
"""m: a finger this close to touching a block exactly does not hit it (the
distance's rounding, which differs between NumPy's ways of summing, does not
decide)."""


def collision_facts(
    locations: Sequence[Location],
    grasps: Sequence[tuple[str, str, ObjectGeometry, float]],
    gripper: Gripper,
    settings: GeometrySettings = GeometrySettings(),
) -> list[tuple[str, str, str]]:
    """Facts ``(a, b, g)`` for grasps ``(name, object, shape, axis)`` (see the module
    docstring), in the order grasp, a, b. Vectorised with NumPy over the pairs
    (a, b) where a finger at a is within reach of b's bounding circle along x
    (a binary search in the locations sorted by x finds them, a block of rows
    a at a time); shapely measures a finger's reach into a footprint only there."""
    if not locations:
        return []
    prints = np.array([location_footprint(loc) for loc in locations], dtype=object)
    centres = np.array([loc.position for loc in locations], dtype=float).reshape(-1, 3)
    tops = np.array([loc.top for loc in locations])
    blocks = np.array([all(is_block(s) for s in loc.shapes) for loc in locations], dtype=bool)
    radii = np.array([max(s.size[0] for s in loc.shapes) / 2 for loc in locations])
    circles = np.array([max(bounding_radius(s) for s in loc.shapes) for loc in locations])
    finger = gripper.finger_radius
    by_x = np.argsort(centres[:, 0], kind="stable")
    xs = centres[by_x, 0]
    within = float(max(circles.max(), radii.max())) + finger + 1e-9  # any b a finger hits

    def hits(rows: int, tips: np.ndarray, block_grasp: bool) -> set[tuple[int, int]]:
        """The pairs (a, b), a from ``rows`` on, where a finger at ``tips`` hits b."""
        low = np.searchsorted(xs, tips[:, 0] - within, side="left")
        counts = np.searchsorted(xs, tips[:, 0] + within, side="right") - low
        a = np.repeat(np.arange(len(tips)), counts)
        if len(a) == 0:
            return set()
        starts = np.repeat(np.cumsum(counts) - counts, counts)
        b = by_x[np.arange(len(a)) - starts + np.repeat(low, counts)]
        apart = centres[b] - tips[a]
        # a finger that touches b exactly does not hit it (nor one within a rounding error)
        paper = np.linalg.norm(apart, axis=1) < radii[b] + finger - TOUCHING
        above = tops[b] > centres[rows + a, 2] + settings.level_tolerance
        near = np.linalg.norm(apart[:, :2], axis=1) - circles[b] < finger + 1e-9
        paper_rule = blocks[b] & block_grasp
        ask = np.flatnonzero(near & above & ~paper_rule)
        reach = np.zeros(len(a), dtype=bool)
        reach[ask] = shapely.distance(prints[b[ask]], shapely.points(tips[a[ask], :2])) < finger
        hit = np.where(paper_rule, paper, reach)
        return set(zip((rows + a[hit]).tolist(), b[hit].tolist(), strict=True))

    facts: list[tuple[str, str, str]] = []
    where = f"at the collision facts ({len(locations)} locations × {len(grasps)} grasps)"
    for grasp, _obj, shape, axis in grasps:
        block_grasp = is_block(shape)
        offset = finger_offset(shape, axis, gripper)
        turns = [math.radians(loc.yaw + axis) for loc in locations]  # as fingers() does
        g = np.array([[offset * math.cos(t), offset * math.sin(t), 0.0] for t in turns])
        for rows in range(0, len(locations), _FACT_ROWS):
            check_time(where)  # a budget set by the caller (demoplan.budget), if any
            block = slice(rows, rows + _FACT_ROWS)
            pairs = hits(rows, centres[block] + g[block], block_grasp)
            pairs |= hits(rows, centres[block] - g[block], block_grasp)
            facts += [
                (locations[a].name, locations[b].name, grasp) for a, b in sorted(pairs) if a != b
            ]
    return facts


_FACT_ROWS = 256
"""Locations a whose facts :func:`collision_facts` finds at once."""


def supports(
    locations: Sequence[Location],
    settings: GeometrySettings = GeometrySettings(),
    surfaces: Sequence[tuple[BaseGeometry, float]] = (),
) -> tuple[list[tuple[str, str]], list[str]]:
    """``(upper, lower)`` pairs, and the upper locations that nothing holds up.

    ``surfaces`` are fixed tops (a landmark's footprint and the height of its
    top: a tray): a location at that height over at least
    ``support_fraction`` of its footprint stands on it, as on the table."""
    prints = [location_footprint(loc) for loc in locations]
    pairs: list[tuple[str, str]] = []
    floating: list[str] = []
    for i, upper in enumerate(locations):
        check_time(f"at what stands on what ({len(locations)} locations)")
        if upper.bottom <= settings.level_tolerance:
            continue
        area = prints[i].area
        if any(
            abs(top - upper.bottom) <= settings.level_tolerance
            and prints[i].intersection(surface).area >= settings.support_fraction * area
            for surface, top in surfaces
        ):
            continue
        candidates = [
            (j, prints[i].intersection(prints[j]).area)
            for j, lower in enumerate(locations)
            if j != i
            and any(
                abs(lower.bottom + shape.size[2] - upper.bottom) <= settings.level_tolerance
                for shape in lower.shapes
            )
        ]
        # A target rests on targets (what the goal puts under it), a current place on
        # current places (what stands under it now): not on whatever else overlaps.
        # Of lower places that overlap each other (only one can be occupied), a
        # target and the one covering most of it holds it up.
        kinds = set(upper.kind.split("+"))
        alike = [c for c in candidates if kinds & set(locations[c[0]].kind.split("+"))]
        candidates = alike or candidates
        candidates.sort(key=lambda c: ("target" not in locations[c[0]].kind, -c[1], c[0]))
        chosen: list[int] = []
        for j, overlap in candidates:
            if overlap < settings.support_fraction * area:
                continue
            shrunk = prints[j].buffer(-settings.touch_tolerance)
            if all(
                not shrunk.intersects(prints[k].buffer(-settings.touch_tolerance)) for k in chosen
            ):
                chosen.append(j)
        lowers = [locations[j].name for j in sorted(chosen)]
        if lowers:
            pairs += [(upper.name, lower) for lower in lowers]
        else:
            floating.append(upper.name)
    return pairs, floating


def exclusions(
    locations: Sequence[Location],
    support_pairs: Sequence[tuple[str, str]],
    settings: GeometrySettings = GeometrySettings(),
) -> list[tuple[str, str]]:
    """Pairs of locations that cannot both be occupied (see the module docstring).
    Vectorised with NumPy over the second of each pair; shapely compares two
    footprints only where their bounding circles meet."""
    shrunk = np.array(
        [location_footprint(loc).buffer(-settings.touch_tolerance) for loc in locations],
        dtype=object,
    )
    centres = np.array([loc.position[:2] for loc in locations], dtype=float).reshape(-1, 2)
    circles = np.array([max(bounding_radius(s) for s in loc.shapes) for loc in locations])
    bottoms = np.array([loc.bottom for loc in locations])
    tops = np.array([loc.top for loc in locations])
    supported = set(support_pairs) | {(b, a) for a, b in support_pairs}
    tolerance = settings.level_tolerance
    pairs = []
    for i, a in enumerate(locations):
        check_time(f"at the locations that exclude each other ({len(locations)} locations)")
        rest = slice(i + 1, None)
        # One above the other — its bottom at or over the other's top (to the
        # tolerance) and higher than the other's bottom: no clash. Thin objects
        # side by side at one level do clash, however thin (a 5 mm knife on an
        # obstacle's spot).
        a_over = (a.bottom >= tops[rest] - tolerance) & (a.bottom > bottoms[rest] + tolerance)
        b_over = (bottoms[rest] >= tops[i] - tolerance) & (bottoms[rest] > a.bottom + tolerance)
        meet = (
            np.linalg.norm(centres[rest] - centres[i], axis=1) <= circles[rest] + circles[i] + 1e-9
        )
        others = np.flatnonzero(meet & ~a_over & ~b_over) + i + 1
        for j in others[shapely.intersects(shrunk[i], shrunk[others])]:
            b = locations[int(j)]
            if (a.name, b.name) not in supported:
                pairs.append((a.name, b.name))
    return pairs


@dataclass(frozen=True, slots=True)
class FreeSpot:
    """A generated parking spot: its centre on the table and the radius of the
    disc an object must fit in (any turn) to be parked there."""

    position: Vector3
    radius: float


def spot_shape(radius: float, height: float) -> ObjectGeometry:
    """The outline a free-space location stands for: a disc of ``radius`` (any
    object that fits in it, turned any way), as tall as the tallest such object."""
    return ObjectGeometry("cylinder", (2 * radius, 2 * radius, height))


def _distance_to_outline(
    grid: np.ndarray, shape: ObjectGeometry, position: Sequence[float], yaw: float
) -> np.ndarray:
    """From each point of ``grid`` (n×2) to :func:`footprint` (0 inside), in NumPy:
    a box in its own frame, a disc by its radius."""
    offset = grid - np.asarray(position[:2], dtype=float)
    if shape.shape != "box":
        radius = max(shape.size[0], shape.size[1]) / 2
        return np.asarray(np.maximum(np.linalg.norm(offset, axis=1) - radius, 0.0))
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    local = np.abs(offset @ np.array([[c, -s], [s, c]]))
    outside = np.maximum(local - np.array([shape.size[0] / 2, shape.size[1] / 2]), 0.0)
    return np.asarray(np.linalg.norm(outside, axis=1))


def _distances(
    grid: np.ndarray,
    location: Location,
    grasp_axes: Sequence[tuple[str, float]],
    gripper: Gripper,
) -> tuple[np.ndarray, np.ndarray]:
    """From each point of ``grid`` to what stands at ``location`` (its footprint),
    and to its grasp zone: the footprint and the finger discs of every grasp of
    the objects it was made for."""
    to_print = np.min(
        [_distance_to_outline(grid, s, location.position, location.yaw) for s in location.shapes],
        axis=0,
    )
    to_zone = to_print
    for shape, obj in zip(location.shapes, location.objects, strict=False):
        for owner, axis in grasp_axes:
            if owner == obj:
                for tip in fingers(location, shape, axis, gripper):
                    disc = np.linalg.norm(grid - tip[:2], axis=1) - gripper.finger_radius
                    to_zone = np.minimum(to_zone, np.maximum(disc, 0.0))
    return to_print, to_zone


def spot_reach(radius: float, gripper: Gripper) -> float:
    """How far from a spot's centre grasping anything that fits in its disc may
    reach: the far edge of a finger beside the widest such object."""
    return radius + 2 * gripper.finger_radius + gripper.clearance


def free_space(
    locations: Sequence[Location],
    shapes: Sequence[ObjectGeometry],
    grasp_axes: Sequence[tuple[str, float]],
    gripper: Gripper,
    table: tuple[tuple[float, float], tuple[float, float]],
    focus: Sequence[float],
    settings: GeometrySettings = GeometrySettings(),
    keep_out: Sequence[BaseGeometry] = (),
) -> list[FreeSpot]:
    """Up to ``settings.n_freespace`` parking spots on ``table``, each sized for
    one of ``shapes`` (the disc around it, :func:`bounding_radius`), nearest to
    ``focus`` first; ``grasp_axes``: (object, axis) of every grasp.

    Spot k is sized for the k-th largest object (cycling), or, where the table
    has no room for that, for the next smaller object that fits: a tray gets a
    spot of its own where the table has room for one, two plates get two, and
    a small object still gets one where no tray fits. Then any object that no
    spot takes yet gets a spot of its size where one fits (none: no room).

    A spot keeps clear of everything: whatever fits in its disc, and the
    fingers grasping it (:func:`spot_reach`), touch no location's footprint
    nor ``keep_out`` (landmarks' outlines); no location's object or fingers
    (:func:`_distances`) reach into its disc; two spots keep clear of each
    other the same way.
    """
    (x0, y0), (x1, y1) = table
    radii = sorted({bounding_radius(s) for s in shapes}, reverse=True)
    # at most MAX_GRID candidate spots: a wide table gets a coarser grid
    area = max(x1 - x0, 0.0) * max(y1 - y0, 0.0)
    step = max(settings.grid_step, math.sqrt(area / MAX_GRID))
    gx = np.arange(x0, x1 + 1e-12, step)
    gy = np.arange(y0, y1 + 1e-12, step)
    if len(gx) == 0 or len(gy) == 0 or not radii:
        return []
    grid = np.stack(np.meshgrid(gx, gy, indexing="ij"), axis=-1).reshape(-1, 2)
    # the room each candidate has: to the nearest footprint (what a spot's own
    # fingers must miss) and to the nearest grasp zone (what its object must miss)
    to_print = np.full(len(grid), np.inf)
    to_zone = np.full(len(grid), np.inf)
    where = f"at the free space ({len(locations)} locations, {len(grid)} candidate spots)"
    for location in locations:
        check_time(where)
        print_distance, zone_distance = _distances(grid, location, grasp_axes, gripper)
        to_print = np.minimum(to_print, print_distance)
        to_zone = np.minimum(to_zone, zone_distance)
    points = shapely.points(grid) if keep_out else None
    for outline in keep_out:
        apart = shapely.distance(points, outline)
        to_print, to_zone = np.minimum(to_print, apart), np.minimum(to_zone, apart)
    to_edge = np.minimum.reduce(
        [grid[:, 0] - x0, x1 - grid[:, 0], grid[:, 1] - y0, y1 - grid[:, 1]]
    )
    order = np.argsort(np.linalg.norm(grid - np.asarray(focus[:2]), axis=1), kind="stable")
    margin = settings.touch_tolerance
    chosen: list[FreeSpot] = []

    def place(radius: float) -> bool:
        check_time(where)
        ok = (
            (to_edge >= radius)
            & (to_print >= spot_reach(radius, gripper) + margin)
            & (to_zone >= radius + margin)
        )
        for spot in chosen:
            apart = max(
                spot_reach(radius, gripper) + spot.radius, spot_reach(spot.radius, gripper) + radius
            )
            ok &= np.linalg.norm(grid - np.asarray(spot.position[:2]), axis=1) >= apart + margin
        free = order[ok[order]]
        if len(free) == 0:
            return False
        x, y = grid[int(free[0])]
        chosen.append(FreeSpot((round(float(x), 6), round(float(y), 6), 0.0), radius))
        return True

    # spot k is sized for the k-th largest object (a second plate gets a second
    # plate-sized spot), or where it has no room for the next smaller that fits
    wanted = sorted((bounding_radius(s) for s in shapes), reverse=True)
    for k in range(settings.n_freespace):
        size = wanted[k % len(wanted)]
        if not any(place(radius) for radius in radii if radius <= size):
            break
    for radius in radii:
        if not any(spot.radius >= radius for spot in chosen):
            place(radius)
    return chosen


def accepted_objects(
    location: Location,
    shapes: dict[str, ObjectGeometry],
    settings: GeometrySettings = GeometrySettings(),
) -> list[str]:
    """The objects that may be put down at ``location`` (see the module docstring)."""
    if location.kind == "freespace":
        room = max(bounding_radius(s) for s in location.shapes) + settings.touch_tolerance
        return [name for name, shape in shapes.items() if bounding_radius(shape) <= room]
    area = location_footprint(location).buffer(settings.touch_tolerance)
    heights = [s.size[2] for s in location.shapes]
    fits: dict[ObjectGeometry, bool] = {}  # many objects of one shape: one test
    for shape in shapes.values():
        if shape not in fits:
            fits[shape] = any(
                abs(shape.size[2] - h) <= settings.level_tolerance for h in heights
            ) and area.contains(footprint(shape, location.position, location.yaw))
    return [name for name, shape in shapes.items() if name in location.objects or fits[shape]]
