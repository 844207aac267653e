"""Support geometry of a recording's model: what its objects rest on (the
table top, a bin's floor), where a body's collision geoms end, when an object
has settled, and the landmarks (top-level static bodies that collide), as the
docstring of :mod:`~demoplan.segmentation.readers.hdf5` describes them."""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from demoplan.documents.compartments import compartments
from demoplan.model import Compartment, ObjectGeometry, Pose
from demoplan.rotations import (
    quat_from_yaw,
)
from demoplan.segmentation.readers.mjcf import PRIMITIVES, Geom, ModelLayout

FloatArray = NDArray[np.float64]

__all__ = [
    "EXCLUDED_LANDMARKS",
    "SETTLE_TOLERANCE",
    "SETTLE_WINDOW_S",
    "SUPPORT_SLACK",
    "Surface",
    "body_geoms",
    "geom_bounds",
    "geom_corners",
    "landmark_poses",
    "object_geometry",
    "settled_sample",
    "static_surfaces",
    "support_top",
    "table_top",
]

logger = logging.getLogger(__name__)

EXCLUDED_LANDMARKS = re.compile(r"^(table|floor|ground)$|mount|pedestal|^visual", re.IGNORECASE)


SETTLE_WINDOW_S = 0.25  # s: an object has settled when it stays within SETTLE_TOLERANCE this long


SETTLE_TOLERANCE = 0.001  # m


SUPPORT_SLACK = 0.005  # m: a surface counts as "under" a point up to this far above it


def geom_corners(geom: Geom) -> FloatArray | None:
    """The 8 corners of a primitive geom's box (or its bounding box) in its body's frame."""
    if geom.type not in PRIMITIVES or not geom.size:
        return None
    s = geom.size
    if geom.type in {"box", "ellipsoid"} and len(s) >= 3:
        half = np.array(s[:3])
    elif geom.type == "sphere":
        half = np.full(3, s[0])
    elif geom.type == "cylinder" and len(s) >= 2:
        half = np.array([s[0], s[0], s[1]])
    elif geom.type == "capsule" and len(s) >= 2:
        half = np.array([s[0], s[0], s[1] + s[0]])
    else:
        return None
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    return np.asarray(geom.pos + (signs * half) @ geom.rot.T, dtype=float)


def body_geoms(layout: ModelLayout, index: int) -> list[Geom]:
    """Geoms of body ``index`` and of the bodies rigidly attached below it, in its frame."""
    body = layout.bodies[index]
    out = list(body.geoms)
    for child_index in body.children:
        child = layout.bodies[child_index]
        if child.joints:
            continue
        to_body = body.rot.T
        for geom in body_geoms(layout, child_index):
            pos = to_body @ (child.pos - body.pos) + to_body @ child.rot @ geom.pos
            rot = to_body @ child.rot @ geom.rot
            out.append(Geom(geom.type, geom.size, pos, rot, geom.collides))
    return out


def geom_bounds(geoms: Sequence[Geom]) -> tuple[FloatArray, FloatArray] | None:
    """Body-frame bounding box (low, high) of colliding primitive geoms; None if any is not one."""
    colliding = [g for g in geoms if g.collides]
    if not colliding:
        return None
    corners = [geom_corners(g) for g in colliding]
    if any(c is None for c in corners):
        return None
    points = np.concatenate([c for c in corners if c is not None])
    return points.min(axis=0), points.max(axis=0)


def object_geometry(geoms: Sequence[Geom], low: FloatArray, high: FloatArray) -> ObjectGeometry:
    colliding = [g for g in geoms if g.collides]
    x, y, z = (float(v) for v in high - low)
    if (
        len(colliding) == 1
        and colliding[0].type == "cylinder"
        and np.allclose(colliding[0].rot[:, 2], [0.0, 0.0, 1.0])
    ):
        return ObjectGeometry("cylinder", (x, y, z))
    return ObjectGeometry("box", (x, y, z))


@dataclass(frozen=True, slots=True)
class Surface:
    """A static colliding geom's world axis-aligned bounding box."""

    low: FloatArray
    high: FloatArray


def static_surfaces(layout: ModelLayout) -> list[Surface]:
    """World boxes of static colliding primitives (bodies that cannot move, world geoms)."""
    out = []
    placed: list[tuple[FloatArray, FloatArray, Geom]] = [
        (np.zeros(3), np.eye(3), g) for g in layout.world_geoms
    ]
    for index, body in enumerate(layout.bodies):
        if not layout.moves(index):
            placed += [(body.pos, body.rot, g) for g in body.geoms]
    for pos, rot, geom in placed:
        corners = geom_corners(geom) if geom.collides else None
        if corners is None:
            continue
        world = pos + corners @ rot.T
        out.append(Surface(world.min(axis=0), world.max(axis=0)))
    return out


def support_top(surfaces: Sequence[Surface], point: FloatArray) -> float | None:
    """Height of the highest static surface under ``point`` (its top at most slightly above)."""
    tops = [
        float(s.high[2])
        for s in surfaces
        if s.low[0] <= point[0] <= s.high[0]
        and s.low[1] <= point[1] <= s.high[1]
        and s.high[2] <= point[2] + SUPPORT_SLACK
    ]
    return max(tops) if tops else None


def settled_sample(times: FloatArray, positions: FloatArray) -> int:
    """Index of the first sample after which the object stays put for SETTLE_WINDOW_S."""
    n = len(times)
    ends = np.searchsorted(times, times + SETTLE_WINDOW_S, side="right")
    for i in range(n):
        if ends[i] >= n and i > 0:
            break
        window = positions[i : ends[i]]
        if float(np.max(np.linalg.norm(window - positions[i], axis=1))) <= SETTLE_TOLERANCE:
            return i
    return 0


def table_top(
    layout: ModelLayout,
    surfaces: Sequence[Surface],
    rests: Sequence[FloatArray],
    source: str,
) -> float:
    """World z of the table top (module docstring: site, table body, supports)."""
    if "table_top" in layout.sites:
        return float(layout.sites["table_top"][2])
    for body in layout.bodies:
        if body.name == "table":
            tops = []
            for geom in body.geoms:
                corners = geom_corners(geom) if geom.collides and geom.type == "box" else None
                if corners is not None:
                    tops.append(float((body.pos + corners @ body.rot.T)[:, 2].max()))
            if tops:
                return max(tops)
    supports = [top for p in rests if (top := support_top(surfaces, p)) is not None]
    if supports:
        return min(supports)
    logger.warning("%s: no table or support found under the objects; z is kept as is", source)
    return 0.0


def landmark_poses(
    layout: ModelLayout, table_z: float, objects: set[str]
) -> tuple[
    list[tuple[str, Pose]],
    list[tuple[str, ObjectGeometry]],
    list[tuple[str, tuple[Compartment, ...]]],
]:
    """The static top-level bodies that collide: their poses, their sizes, and
    the compartments of those that have some (a bin's, in its frame)."""
    poses, geometry, found = [], [], []
    for index, body in enumerate(layout.bodies):
        if body.parent != -1 or layout.jointed_subtree(index):
            continue
        if EXCLUDED_LANDMARKS.search(body.name) or body.name in objects:
            continue
        geoms = [g for g in body_geoms(layout, index) if g.collides]
        if not geoms:
            continue
        yaw = math.degrees(math.atan2(body.rot[1, 0], body.rot[0, 0]))
        bounds = geom_bounds(geoms)
        point = body.pos.copy()
        if bounds is not None:
            low, high = bounds
            local = np.array([(low[0] + high[0]) / 2, (low[1] + high[1]) / 2, low[2]])
            point = body.pos + body.rot @ local
            geometry.append((body.name, object_geometry(geoms, low, high)))
            parts = [geom_bounds([g]) for g in geoms]
            boxes = compartments([(p[0] - local, p[1] - local) for p in parts if p is not None])
            if boxes:
                found.append((body.name, boxes))
        x, y, z = (float(v) for v in point)
        poses.append((body.name, Pose((x, y, z - table_z), quat_from_yaw(yaw))))
    return poses, geometry, found
