"""Where a region goal puts its object (docs/learning.md, "Region goals"): a
state placed anywhere inside a compartment of a landmark (a bin's).

The object stays where it stands when it stands inside the compartment (the
goal holds already). Otherwise its target is the point of the compartment,
its footprint kept :data:`WALL_CLEARANCE` from the walls,
nearest the demonstrations' mean — among the points the robot reaches
(``Scene.reach``) when the mean lies out of its reach.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry
from shapely.ops import nearest_points

from demoplan.learning.regions import in_compartment, local_point
from demoplan.model import Compartment, ObjectGeometry, Pose, Vector3
from demoplan.rotations import rotate_vectors

__all__ = ["WALL_CLEARANCE", "region_target"]

WALL_CLEARANCE = 0.01
"""m: how far a region goal's target keeps its object's footprint from the walls."""


def _world(local: np.ndarray, frame: Pose) -> Vector3:
    turned = local
    if frame.orientation is not None:
        turned = rotate_vectors(np.asarray([frame.orientation], dtype=float), local[None, :])[0]
    x, y, z = (float(v) for v in turned + np.asarray(frame.position, dtype=float))
    return (x, y, z)


def _half_extents(shape: ObjectGeometry | None, yaw: float) -> tuple[float, float]:
    """Half the extents along the landmark's x and y of ``shape``'s footprint
    turned by ``yaw`` (deg) from the landmark's axes (a round one: its radius)."""
    if shape is None:
        return (0.0, 0.0)
    sx, sy = shape.size[0] / 2, shape.size[1] / 2
    if shape.shape in {"cylinder", "sphere"}:
        return (max(sx, sy), max(sx, sy))
    c, s = abs(math.cos(math.radians(yaw))), abs(math.sin(math.radians(yaw)))
    return (c * sx + s * sy, s * sx + c * sy)


def region_target(
    region: Compartment,
    landmark: Pose,
    mean: Vector3,
    standing: Pose | None,
    shape: ObjectGeometry | None,
    yaw: float,
    reach: tuple[float, float, float] | None,
) -> Vector3:
    """The target (world) of an object whose goal is anywhere inside ``region``
    (``landmark``'s frame; ``mean``: the demonstrations' mean, world):
    ``standing``, where it stands now, when that is inside; else the point
    nearest ``mean`` of the compartment less its walls' clearance (the
    object's footprint at ``yaw``, deg, world), within
    ``reach`` ((x, y) of the robot's base and the radius, world) where any of
    it is. The height is the mean's."""
    if standing is not None and in_compartment(local_point(standing.position, landmark), region):
        return standing.position
    centre = local_point(mean, landmark)
    hx, hy = _half_extents(shape, yaw - landmark.yaw)
    x0, y0, _, x1, y1, _ = region
    ix = min(hx + WALL_CLEARANCE, (x1 - x0) / 2)
    iy = min(hy + WALL_CLEARANCE, (y1 - y0) / 2)
    area: BaseGeometry = shapely.box(x0 + ix, y0 + iy, x1 - ix, y1 - iy)
    if area.is_empty:  # the object fills the compartment: its middle
        area = shapely.Point((x0 + x1) / 2, (y0 + y1) / 2)
    if reach is not None:
        base = local_point((reach[0], reach[1], mean[2]), landmark)
        reachable = area.intersection(shapely.Point(base[0], base[1]).buffer(reach[2], 64))
        area = reachable if not reachable.is_empty else area
    point = nearest_points(area, shapely.Point(centre[0], centre[1]))[0]
    return _world(np.array([point.x, point.y, centre[2]]), landmark)


