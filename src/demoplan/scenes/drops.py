"""Where a released thing comes to rest on a table of standing things (the
studio's drag and drop, docs/studio-api.md): on the highest top under it that
holds it up, never through what stands higher, never on what it carries.

The rule is the scene's support rule (:func:`demoplan.scenes.geometry.supports`,
docs/scenes.md): a top holds a thing up when it covers at least
``GeometrySettings.support_fraction`` of the thing's outline, and outlines that
overlap by less than ``touch_tolerance`` only touch.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from shapely.geometry.base import BaseGeometry

from demoplan.errors import InputError
from demoplan.model import ObjectGeometry, Vector3, footprint
from demoplan.scenes.geometry import GeometrySettings, Location, supports

__all__ = ["Landing", "Standing", "carried_by", "landing", "landmark_clear"]


@dataclass(frozen=True, slots=True)
class Standing:
    """A thing where it stands: its bottom centre, its yaw (deg), its shape."""

    position: Vector3
    yaw: float
    geometry: ObjectGeometry

    @property
    def outline(self) -> BaseGeometry:
        return footprint(self.geometry, self.position, self.yaw)

    @property
    def top(self) -> float:
        return self.position[2] + self.geometry.size[2]


@dataclass(frozen=True, slots=True)
class Landing:
    """A released object at rest: its bottom centre, its yaw (deg), and what it
    stands on (``None``: the table)."""

    position: Vector3
    yaw: float
    on: str | None


def carried_by(
    name: str, standing: Mapping[str, Standing], settings: GeometrySettings
) -> frozenset[str]:
    """The objects standing on ``name``, directly or on each other: they move
    with it (the support rule of :func:`demoplan.scenes.geometry.supports`)."""
    locations = [
        Location(n, thing.position, thing.yaw, "current", (n,), (thing.geometry,))
        for n, thing in standing.items()
    ]
    pairs, _ = supports(locations, settings)
    carried: set[str] = set()
    frontier = {name}
    while frontier:
        below = frontier
        frontier = {upper for upper, lower in pairs if lower in below} - carried - {name}
        carried |= frontier
    return frozenset(carried)


def landing(
    name: str,
    position: tuple[float, float],
    yaw: float,
    objects: Mapping[str, Standing],
    landmarks: Mapping[str, Standing],
    settings: GeometrySettings,
) -> Landing:
    """Where object ``name`` comes to rest released over ``position`` at ``yaw``:
    on the highest top under it that holds it up (an object or a landmark whose
    outline covers at least the support share of its own), else on the table.

    Things do not pass through each other: a release whose outline overlaps
    something standing higher than where it would rest, by more than the touch
    tolerance (a box's rim it barely covers, an apple beside its landing spot),
    is refused (an :class:`InputError` on ``position``), as is landing on what
    stands on ``name`` (it moves with it)."""
    if name not in objects:
        raise InputError(
            f"unknown object {name!r}; expected one of {sorted(objects)}", field="object"
        )
    riders = carried_by(name, objects, settings)
    moved = footprint(objects[name].geometry, position, yaw)
    core = moved.buffer(-settings.touch_tolerance)  # a graze within the tolerance is a touch
    landing_on: list[tuple[float, str]] = []
    touched: list[tuple[float, str]] = []  # (top, name) of everything the outline overlaps
    for other, thing in _others(objects, landmarks, exclude=name):
        outline = thing.outline
        if moved.intersection(outline).area >= settings.support_fraction * moved.area:
            landing_on.append((thing.top, other))
        if core.intersects(outline) and other not in riders:
            touched.append((thing.top, other))
    top, support = max(landing_on) if landing_on else (0.0, None)
    if support is not None and support in riders:
        raise InputError(
            f"{name!r} would land on {support!r}, which stands on it and moves with it; "
            "a place clear of what it carries expected",
            field="position",
        )
    blocking = sorted(other for height, other in touched if height > top + 1e-6)
    if blocking:
        raise InputError(
            f"{name!r} would pass through {', '.join(map(repr, blocking))}; "
            "a free place, or one on top of a single thing, expected",
            field="position",
        )
    return Landing((position[0], position[1], top), yaw, support)


def landmark_clear(
    name: str,
    moved: Standing,
    objects: Mapping[str, Standing],
    landmarks: Mapping[str, Standing],
    settings: GeometrySettings,
) -> None:
    """Landmark ``name`` put down as ``moved`` stands on the table clear of every
    object and other landmark (overlaps within the touch tolerance only touch);
    else an :class:`InputError` on ``position`` naming what it would stand on."""
    core = moved.outline.buffer(-settings.touch_tolerance)
    hit = sorted(
        other
        for other, thing in _others(objects, landmarks, exclude=name)
        if core.intersects(thing.outline)
    )
    if hit:
        raise InputError(
            f"landmark {name!r} would be put down on {', '.join(map(repr, hit))}; "
            "a clear place on the table expected (move the objects first)",
            field="position",
        )


def _others(
    objects: Mapping[str, Standing], landmarks: Mapping[str, Standing], exclude: str
) -> Iterator[tuple[str, Standing]]:
    """Every object and landmark but ``exclude``, objects first."""
    for group in (objects, landmarks):
        for other, thing in group.items():
            if other != exclude:
                yield other, thing
