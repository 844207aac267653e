"""What a target stands on stays under it (docs/scenes.md "From a goal to targets").

In the demonstrations each release rests on something: the table, an object
standing there at that moment, or a landmark's top — the support rule of the
scene geometry (:mod:`demoplan.scenes.geometry`: the lower top at the upper
bottom, covering at least ``support_fraction`` of its outline). A state whose
every member stood on the same object or landmark keeps that **support**, with
the most any member hung over its edge (:func:`demonstrated_supports`).

At plan time the target must lie on the support as it stands then (the
landmark where the scene puts it, the object at its target or where it
stands): hanging over its edge by more than the demonstrations did plus
:data:`OVERHANG_TOLERANCE` makes the candidate impossible, with a reason
naming both (:func:`overhang_obstacles`). A sandwich learned in world yaw,
placed relative to a lunch box the scene turns 30°, hangs over the box's edge:
that is said, not planned.

How far an outline hangs over another is the largest distance from a corner of
it to the other outline (the farthest point of a polygon from a convex outline
is a corner): 0 when it lies wholly on it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import shapely
from shapely.geometry.base import BaseGeometry

from demoplan.model import (
    ObjectGeometry,
    Pose,
    TaskModel,
    Vector3,
    demonstrated_shapes,
    footprint,
)
from demoplan.rotations import rpy_from_quat
from demoplan.scenes.geometry import GeometrySettings

__all__ = [
    "OVERHANG_TOLERANCE",
    "Support",
    "demonstrated_supports",
    "overhang",
    "overhang_obstacles",
]

OVERHANG_TOLERANCE = 0.005
"""m: a target may hang this much further over its support's edge than any
demonstration did (the learned position is the members' mean; 5 mm is the
level tolerance, well beyond a demonstration's placement noise)."""
TILTED = 10.0
"""deg: a support tilted more than this (roll or pitch) has no flat top here."""


@dataclass(frozen=True, slots=True)
class Support:
    """What a state's object stood on in every demonstration, and the most it
    hung over that thing's edge there (m)."""

    name: str
    overhang: float


def overhang(upper: BaseGeometry, lower: BaseGeometry) -> float:
    """How far ``upper`` hangs over ``lower``'s edge (m): the largest distance
    from a vertex of ``upper`` to ``lower`` (0 when it lies wholly on it)."""
    corners = shapely.points(shapely.get_coordinates(upper))
    return float(shapely.distance(corners, lower).max(initial=0.0))


def _yaw(pose: Pose) -> float:
    return 0.0 if pose.orientation is None else rpy_from_quat(pose.orientation)[2]


def _flat(pose: Pose) -> bool:
    if pose.orientation is None:
        return True
    roll, pitch, _ = rpy_from_quat(pose.orientation)
    return abs(roll) <= TILTED and abs(pitch) <= TILTED


def _supports_of(
    shape: ObjectGeometry,
    pose: Pose,
    others: Mapping[str, tuple[Pose, ObjectGeometry]],
    settings: GeometrySettings,
) -> dict[str, float]:
    """What ``shape`` at ``pose`` rests on among ``others`` (the support rule),
    each with how far it hangs over it."""
    if not _flat(pose) or pose.position[2] <= settings.level_tolerance:
        return {}
    upper: BaseGeometry | None = None
    found: dict[str, float] = {}
    for name, (at, body) in others.items():
        top = at.position[2] + body.size[2]
        if abs(top - pose.position[2]) > settings.level_tolerance or not _flat(at):
            continue
        if upper is None:
            upper = footprint(shape, pose.position, _yaw(pose))
        lower = footprint(body, at.position, _yaw(at))
        if upper.intersection(lower).area >= settings.support_fraction * upper.area:
            found[name] = overhang(upper, lower)
    return found


def demonstrated_supports(
    model: TaskModel, settings: GeometrySettings = GeometrySettings()
) -> dict[str, tuple[Support, ...]]:
    """Per state id, what its object stood on in every member (objects standing
    there at that moment, landmarks with a size), with the most it hung over;
    states that stood on the table, or on different things, and states placed
    anywhere (their object stays where it stands), have none."""
    shapes = demonstrated_shapes(model.demonstrations)
    # the world just before each step: (demonstration, step) -> what stands where
    found: dict[tuple[int, int], dict[str, float]] = {}
    wanted = {member for state in model.states for member in state.members}
    for d, demo in enumerate(model.demonstrations):
        standing: dict[str, Pose] = dict(demo.initial)
        landmarks = dict(demo.landmarks)
        for k, step in enumerate(demo.steps):
            shape = shapes.get(step.object)
            if (d, k) in wanted and shape is not None:
                others = {
                    name: (pose, shapes[name])
                    for name, pose in {**standing, **landmarks}.items()
                    if name != step.object and name in shapes
                }
                found[(d, k)] = _supports_of(shape, step.pose, others, settings)
            standing[step.object] = step.pose
    supports: dict[str, tuple[Support, ...]] = {}
    for state in model.states:
        if state.position.anywhere:  # it stays where it stands: no support to keep
            continue
        members = [found.get(member) for member in state.members]
        if not members or any(m is None for m in members):
            continue
        common = set.intersection(*(set(m) for m in members if m is not None))
        supports[state.id] = tuple(
            Support(name, max(m[name] for m in members if m is not None)) for name in sorted(common)
        )
    return {state: held for state, held in supports.items() if held}


def overhang_obstacles(
    placements: Sequence[tuple[str, str, Sequence[Support], ObjectGeometry, Vector3, float]],
    standing: Mapping[str, tuple[Vector3, float, ObjectGeometry, str]],
    source: str,
    tolerance: float = OVERHANG_TOLERANCE,
) -> list[str]:
    """Why a candidate's targets cannot stand where they are: each placement
    ``(label, object, supports, shape, position, yaw)``, in the candidate's
    order, that hangs over a support further than the demonstrations did plus
    ``tolerance``. ``standing``: where each object and landmark is before the
    first placement, ``(position, yaw, shape, field)`` (``field``: the scene's
    field that says so, ``landmarks.box``); a placement moves its object."""
    where = dict(standing)
    reasons = []
    for label, obj, supports, shape, position, yaw in placements:
        upper = footprint(shape, position, yaw)
        for support in supports:
            if support.name not in where:
                continue
            at, turn, body, field = where[support.name]
            over = overhang(upper, footprint(body, at, turn))
            if over > support.overhang + tolerance:
                xyz = ", ".join(f"{v:.3f}" for v in position)
                reasons.append(
                    f"{obj}'s target {label} at ({xyz}) would hang {over * 1000:.0f} mm over "
                    f"the edge of {support.name} ({source}: {field}, yaw {turn:.0f}°), which "
                    f"held it up in every demonstration ({support.overhang * 1000:.0f} mm over "
                    f"at most; {tolerance * 1000:g} mm tolerated)"
                )
        previous = where.get(obj)
        where[obj] = (position, yaw, shape, previous[3] if previous else f"objects.{obj}")
    return reasons
