"""Whether a file's numbers fit the units it declares (docs/formats.md "Units",
docs/limits.md "Numbers that no tabletop holds").

A demonstration or scene written in millimetres without ``"units"`` is read in
metres: a 30 cm table becomes 300 m, and everything after — precision, states,
plans — is nonsense without a word. :func:`check_units` looks at the file as a
whole, after its length unit, and refuses it in one line naming ``units`` when

- its positions spread more than :data:`MAX_SPREAD_M` along an axis (a tabletop
  is smaller),
- an object it moves is larger than :data:`MAX_CARRIED_M` (a hand or gripper
  carries smaller things), or
- its positions spread more than :data:`MAX_SPREAD_PER_OBJECT` times the
  largest object it moves (sizes and positions written in different units).

A file that declares its length unit (``"units": {"length": "m"}``) is taken
at its word on the first rule: a warehouse or a mobile robot's task may span
more than 10 m, and then gets one ``demoplan: WARNING:`` line, not a refusal
(the other two rules still refuse: a declared unit does not make a 3 m object
carried, nor sizes and positions agree). A file that declares nothing is
refused as before.

Angles read in degrees (the default) whose values all lie within ±2π, not all
whole numbers, two of them at least π/4, look like radians:
one ``demoplan: WARNING:`` line names the file and the field (a warning, not an
error: a task where every object stands within 6° of the axes is possible).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterator, Mapping
from typing import Any

from demoplan.documents.poses import LENGTH_SCALE, UnitsSchema, check_physical
from demoplan.errors import InputError

__all__ = [
    "MAX_CARRIED_M",
    "MAX_SPREAD_M",
    "MAX_SPREAD_PER_OBJECT",
    "check_document",
    "check_measured",
    "check_units",
    "radians_suspected",
]

logger = logging.getLogger(__name__)

MAX_SPREAD_M = 10.0
"""The widest the positions of one file may spread along an axis: 10 m."""
MAX_CARRIED_M = 2.0
"""The largest extent of an object a demonstration or scene moves: 2 m."""
MAX_SPREAD_PER_OBJECT = 1000.0
"""How many times the largest moved object the positions may spread."""
TYPICAL_SPREAD_M = 0.5
"""How far a tabletop task's positions typically spread (to suggest a unit)."""
SMALLEST_SUSPECT_ANGLE = math.pi / 4
"""Radians are suspected only where two angles at least reach this (two objects
turned 45° or more, were they radians): below it a degree file's objects stand
within a degree of the axes, as careful placements do."""

_UNIT_NAMES = {"m": "metres", "cm": "centimetres", "mm": "millimetres"}
_SMALLER_UNITS = {"m": ("cm", "mm"), "cm": ("mm",), "mm": ()}


def check_units(
    document: Mapping[str, Any], units: UnitsSchema, source: str, prefix: str = ""
) -> None:
    """Refuse a (schema-valid) demonstration or scene document whose lengths do
    not fit ``units.length`` (an :class:`InputError` on the field ``units``);
    log one warning when its angles look like radians read as degrees."""
    field = f"{prefix}.units" if prefix else "units"
    declared = isinstance(document.get("units"), Mapping) and "length" in document["units"]
    problem = _length_problem(document, units.length, wide_ok=declared)
    spread, axis, low, high = _spread(list(_positions(document)))
    spread_m = spread * LENGTH_SCALE[units.length]
    if problem is None and declared and spread_m > MAX_SPREAD_M:
        logger.warning(
            "%s: %s: its positions spread %.4g m along %s (%s to %s), wider than a tabletop's "
            "%g m; read in %s, as its units say (a large workspace)",
            source,
            field,
            spread_m,
            axis,
            low,
            high,
            MAX_SPREAD_M,
            _UNIT_NAMES[units.length],
        )
    if problem is not None:
        given = "as its units say" if "units" in document else 'the default: it gives no "units"'
        raise InputError(
            f"lengths read in {_UNIT_NAMES[units.length]} ({given}), {problem}",
            source=source,
            field=field,
        )
    if units.angle == "deg":
        suspect = radians_suspected(document)
        if suspect is not None:
            where, value = suspect
            logger.warning(
                "%s: %s: every angle of the file lies within ±2π (this one %g) and they are read "
                'in degrees; if they are radians, give "units": {"angle": "rad"}',
                source,
                f"{prefix}.{where}" if prefix else where,
                value,
            )


def check_document(
    document: Mapping[str, Any], units: UnitsSchema, source: str, prefix: str = ""
) -> None:
    """The one validation of a demonstration's or scene's lengths (docs/limits.md
    "Numbers that no tabletop holds"): the file-wide bounds of
    :func:`check_units`, then every position and extent
    (:func:`~demoplan.documents.poses.check_physical`). Files call it as they
    are read; a demonstration made from a stream or a recording, through
    :func:`check_measured`."""
    check_units(document, units, source, prefix)
    check_physical(document, units.length, source, prefix)


def check_measured(document: Mapping[str, Any], source: str, field: str | None = None) -> None:
    """:func:`check_document` for a document in metres made from measurements
    (a pose stream, a recording: ``segment``, ``import``): the same bounds, and
    no unit to suggest — a CSV's unit is its ``--units``, a recording's is metres."""
    problem = _length_problem(document, "m", advise=False)
    if problem is not None:
        raise InputError(
            f"{problem} (a documented limit: docs/limits.md)", source=source, field=field
        )
    check_physical(document, "m", source)


def _length_problem(
    document: Mapping[str, Any], length: str, advise: bool = True, wide_ok: bool = False
) -> str | None:
    """What in ``document`` does not fit ``length``, or None (``advise``: with
    the unit that would fit; ``wide_ok``: the unit is declared, so positions
    spread wider than a tabletop are no problem: :func:`check_units` warns)."""
    scale = LENGTH_SCALE[length]
    positions = list(_positions(document))
    carried = list(_carried_sizes(document))
    spread, axis, low, high = _spread(positions)
    largest_name, largest = max(carried, key=lambda item: max(item[1]), default=("", (0.0,)))
    largest_m = max(largest) * scale
    spread_m = spread * scale

    def advice() -> str:
        """The smaller unit under which the file fits and looks most like a
        tabletop (positions spread about :data:`TYPICAL_SPREAD_M`)."""
        fitting = []
        for other in _SMALLER_UNITS[length]:
            ratio = LENGTH_SCALE[other] / scale
            spread_in, largest_in = spread_m * ratio, largest_m * ratio
            if spread_in <= MAX_SPREAD_M and largest_in <= MAX_CARRIED_M:
                typical = spread_in / TYPICAL_SPREAD_M if spread_in else largest_in / 0.1
                fitting.append((abs(math.log10(typical or 1.0)), other, spread_in, largest_in))
        if not fitting:
            return 'give the unit the file is written in: "units": {"length": …}'
        _, other, spread_in, largest_in = min(fitting)
        shown = (
            f"the positions spread {spread_in:.3g} m"
            if spread_in
            else f"objects.{largest_name} is {largest_in:.3g} m across"
        )
        return f'in {other}, {shown}: give the unit, "units": {{"length": "{other}"}}'

    def tail() -> str:
        return f": {advice()}" if advise else ""

    if spread_m > MAX_SPREAD_M and not wide_ok:
        return (
            f"its positions spread {spread_m:.4g} m along {axis} ({low} to {high}); a tabletop "
            f"spans less than {MAX_SPREAD_M:g} m{tail()}"
        )
    if largest_m > MAX_CARRIED_M:
        return (
            f"objects.{largest_name} is {largest_m:.4g} m across; an object a hand or gripper "
            f"moves is under {MAX_CARRIED_M:g} m{tail()}"
        )
    if largest_m > 0 and spread_m > MAX_SPREAD_PER_OBJECT * largest_m:
        return (
            f"its positions spread {spread_m:.4g} m along {axis}, {spread_m / largest_m:.4g} "
            f"times the largest object it moves (objects.{largest_name}, "
            f"{largest_m * 1000:.3g} mm): sizes and positions in different units? every "
            "length of a file is in its one length unit"
        )
    return None


def _positions(document: Mapping[str, Any]) -> Iterator[tuple[str, list[float]]]:
    """Every position of a demonstration or scene document (field, coordinates):
    poses, free-space spots, the robot's base — not the table, a region where
    free space may be generated, which may be as wide as a room."""

    def numbers(value: Any) -> list[float] | None:
        if isinstance(value, list) and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value
        ):
            return [float(v) for v in value]
        return None

    def walk(value: Any, where: str) -> Iterator[tuple[str, list[float]]]:
        if isinstance(value, dict):
            for key, item in value.items():
                field = f"{where}.{key}" if where else str(key)
                if key in ("position", "base") and numbers(item) is not None:
                    yield field, numbers(item) or []
                elif key == "freespace" and isinstance(item, list):
                    for index, spot in enumerate(item):
                        if numbers(spot) is not None:
                            yield f"{field}[{index}]", numbers(spot) or []
                elif key not in ("units", "provenance", "gripper", "table"):
                    yield from walk(item, field)
        elif isinstance(value, list):
            for index, item in enumerate(value):
                yield from walk(item, f"{where}[{index}]")

    yield from walk(dict(document), "")


def _carried_sizes(document: Mapping[str, Any]) -> Iterator[tuple[str, list[float]]]:
    """The sizes of the objects a document moves: its ``objects`` that are not landmarks."""
    objects = document.get("objects")
    landmarks = document.get("landmarks")
    static = set(landmarks) if isinstance(landmarks, dict) else set()
    if not isinstance(objects, dict):
        return
    for name, entry in objects.items():
        size = entry.get("size") if isinstance(entry, dict) else None
        if name not in static and isinstance(size, list) and size:
            yield str(name), [abs(float(v)) for v in size]


def _spread(positions: list[tuple[str, list[float]]]) -> tuple[float, str, str, str]:
    """The widest spread of the positions along an axis: (spread, axis, field of
    the lowest, field of the highest)."""
    best = (0.0, "x", "", "")
    for axis, name in enumerate("xyz"):
        on_axis = [(values[axis], field) for field, values in positions if len(values) > axis]
        if len(on_axis) < 2:
            continue
        low = min(on_axis)
        high = max(on_axis)
        if high[0] - low[0] > best[0]:
            best = (high[0] - low[0], name, low[1], high[1])
    return best


def radians_suspected(document: Mapping[str, Any]) -> tuple[str, float] | None:
    """The field and value of the largest angle when the document's angles look
    like radians (module docstring), else None."""
    angles = list(_angles(document))
    turned = [(field, value) for field, value in angles if value != 0]
    if len(turned) < 2:
        return None
    if any(abs(value) > 2 * math.pi for _, value in angles):
        return None
    if all(float(value).is_integer() for _, value in turned):
        return None
    if sum(abs(value) >= SMALLEST_SUSPECT_ANGLE for _, value in turned) < 2:
        return None
    return max(turned, key=lambda item: abs(item[1]))


def _angles(document: Mapping[str, Any]) -> Iterator[tuple[str, float]]:
    """Every ``yaw``, ``rpy`` and grasp angle of a document (field, value); the
    robot's yaw is always in degrees and not among them."""

    def number(value: Any) -> bool:
        return isinstance(value, int | float) and not isinstance(value, bool)

    def walk(value: Any, where: str) -> Iterator[tuple[str, float]]:
        if isinstance(value, dict):
            for key, item in value.items():
                field = f"{where}.{key}" if where else str(key)
                if key == "yaw" and number(item):
                    yield field, float(item)
                elif key in ("rpy", "grasps") and isinstance(item, list):
                    yield from (
                        (f"{field}[{i}]", float(v)) for i, v in enumerate(item) if number(v)
                    )
                elif key not in ("robot", "units", "provenance"):
                    yield from walk(item, field)
        elif isinstance(value, list):
            for index, item in enumerate(value):
                yield from walk(item, f"{where}[{index}]")

    yield from walk(dict(document), "")
