"""An object's mass from its file: ``"mass"`` (kg) or ``"density"`` (kg/m³) beside
its ``"size"`` (docs/formats.md), checked for a plausible solid.

Neither given: the object is solid wood (:data:`demoplan.model.WOOD_DENSITY`), as
before these fields existed. Both given is an error (one of them decides). The
mean density they imply over the solid the physics simulates
(:attr:`ObjectGeometry.volume`) must lie between air's and osmium's: lighter,
the object would float away; heavier, no material is — a unit mistake (grams
for kilograms) or a typo.
"""

from __future__ import annotations

from dataclasses import replace

from demoplan.errors import InputError
from demoplan.model import ObjectGeometry

__all__ = ["MAX_DENSITY", "MIN_DENSITY", "with_mass"]

MIN_DENSITY = 1.2
"""kg/m³: air's; an object's mean density below it would float away."""
MAX_DENSITY = 22_600.0
"""kg/m³: osmium's, the densest element's."""


def with_mass(
    geometry: ObjectGeometry,
    mass: float | None,
    density: float | None,
    source: str,
    field: str,
) -> ObjectGeometry:
    """``geometry`` with the mass a file gave for it (``mass`` in kg, or
    ``density`` in kg/m³ times its volume); unchanged when neither is given.
    One :class:`InputError` naming ``field`` (the object's entry) for both
    given, or a mean density outside [:data:`MIN_DENSITY`, :data:`MAX_DENSITY`]."""
    if mass is None and density is None:
        return geometry
    if mass is not None and density is not None:
        raise InputError(
            'gives both "mass" and "density"; one of them expected',
            source=source,
            field=field,
        )
    volume = geometry.volume
    key = "mass" if mass is not None else "density"
    implied = mass / volume if mass is not None else density
    assert implied is not None
    if not MIN_DENSITY <= implied <= MAX_DENSITY:
        what = (
            f"{mass:g} kg in {volume * 1e6:.4g} cm³ is a mean density of {implied:.4g} kg/m³"
            if mass is not None
            else f"{implied:g} kg/m³"
        )
        raise InputError(
            f"{what}; between {MIN_DENSITY:g} (air) and {MAX_DENSITY:g} (osmium) expected",
            source=source,
            field=f"{field}.{key}",
        )
    return replace(geometry, mass=mass if mass is not None else implied * volume)
