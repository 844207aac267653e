"""What every figure of a scene is drawn with: an object's outline from above
(:func:`object_patch`) and from the side (:func:`side_patch`), the landmarks
under the objects (:func:`draw_landmarks`), an object's label
(:func:`scene_label`) and a figure's legend of line styles (:func:`legend`).

matplotlib is imported lazily (the ``plot`` extra).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from demoplan.model import ObjectGeometry, Pose
from demoplan.plotting.labels import add_label, role_label
from demoplan.rotations import rpy_from_quat

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from demoplan.scenes.scene import Scene

__all__ = [
    "LANDMARK_COLOUR",
    "draw_landmarks",
    "height",
    "legend",
    "object_patch",
    "scene_label",
    "side_middle",
    "side_patch",
    "side_top",
    "table_xy",
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
            add_label(ax, name, side_middle(pose, shapes[name]), fontsize=7, color="0.3")
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


def scene_label(name: str, roles: Mapping[str, str] | None) -> str:
    """A scene object's label: ``plate#1 ← plate-b`` where ``roles`` (role →
    instance) has it fill a role of another name, else its name."""
    for role, instance in (roles or {}).items():
        if instance == name:
            return role_label(role, instance)
    return name


def legend(ax: Axes, entries: list[tuple[str, str]]) -> None:
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


def table_xy(position: Sequence[float]) -> tuple[float, float]:
    """A position's (x, y) on the table, as floats."""
    return (float(position[0]), float(position[1]))


def height(geometry: ObjectGeometry | None) -> float:
    return geometry.size[2] if geometry else 0.03


def side_middle(pose: Pose, geometry: ObjectGeometry | None) -> tuple[float, float]:
    """The middle of an object seen from the side: (x, z halfway up)."""
    return (float(pose.position[0]), float(pose.position[2]) + height(geometry) / 2)


def side_top(pose: Pose, geometry: ObjectGeometry | None) -> tuple[float, float]:
    """The top of an object seen from the side: (x, z of its top)."""
    return (float(pose.position[0]), float(pose.position[2]) + height(geometry))
