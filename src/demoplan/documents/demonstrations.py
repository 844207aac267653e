"""Demonstration files (docs/formats.md ``demoplan/demonstration-1`` / ``demonstrations-1``).

Files are validated with pydantic schemas; any problem becomes one
:class:`~demoplan.errors.InputError` naming the file, the field and what was
expected. Lengths are converted to metres (``"units": {"length": "cm"}``),
orientations (``yaw`` / ``rpy`` / ``quat``) to unit quaternions.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    StrictFloat,
    StrictInt,
    StrictStr,
    ValidationError,
    field_validator,
)

from demoplan.documents.masses import with_mass
from demoplan.documents.names import ObjectName
from demoplan.documents.poses import (
    LENGTH_SCALE,
    LandmarkSchema,
    ObjectSchema,
    PoseSchema,
    UnitsSchema,
    pose_from_dict,
    pose_to_dict,
)
from demoplan.documents.releases import warn_unsupported_releases
from demoplan.documents.units import check_document, check_measured
from demoplan.errors import InputError
from demoplan.fileio import check_format, describe_validation_error, read_document
from demoplan.model import Demonstration, ObjectGeometry, Step
from demoplan.wording import did_you_mean, plural

__all__ = [
    "check_demonstrations",
    "check_geometry_names",
    "demonstration_to_dict",
    "demonstrations_from_document",
    "demonstrations_from_path",
    "load_demonstrations",
    "load_object_colours",
    "load_object_geometry",
    "load_object_types",
    "warn_differing_colours",
    "with_declared_types",
    "with_given_colours",
]

logger = logging.getLogger(__name__)

GEOMETRY_TOLERANCE = 1e-6  # m: sizes of one object must agree across demonstrations


class _Schema(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class StepSchema(PoseSchema):
    object: ObjectName


class ObjectsFileSchema(_Schema):
    """A file of object geometry: a demonstration file's ``objects`` (and ``units``) alone."""

    format: str | None = None
    description: str | None = None
    units: UnitsSchema = UnitsSchema()
    objects: dict[ObjectName, ObjectSchema] = Field(min_length=1)


class DemonstrationSchema(_Schema):
    format: str | None = None
    name: str | None = None
    description: str | None = None
    units: UnitsSchema = UnitsSchema()
    objects: dict[ObjectName, ObjectSchema] = {}
    landmarks: dict[ObjectName, LandmarkSchema] = {}
    initial: dict[ObjectName, PoseSchema] = {}
    provenance: dict[str, StrictStr | StrictInt | StrictFloat] = {}
    steps: list[StepSchema]

    @field_validator("provenance", mode="before")
    @classmethod
    def _plain_values(cls, provenance: Any) -> Any:
        if isinstance(provenance, dict):
            for key, value in provenance.items():
                if isinstance(value, bool) or not isinstance(value, str | int | float):
                    raise ValueError(
                        f"provenance {key!r} is {value!r}; a string or a number expected"
                    )
        return provenance

    @field_validator("steps")
    @classmethod
    def _not_empty(cls, steps: list[StepSchema]) -> list[StepSchema]:
        if not steps:
            raise ValueError("empty demonstration; at least one step expected")
        return steps


class DemonstrationsSchema(_Schema):
    format: str
    description: str | None = None
    units: UnitsSchema | None = None
    demonstrations: list[dict[str, Any]]

    @field_validator("demonstrations")
    @classmethod
    def _not_empty(cls, demos: list[dict[str, Any]]) -> list[dict[str, Any]]:
        if not demos:
            raise ValueError("no demonstrations; at least one expected")
        return demos


def demonstration_to_dict(demo: Demonstration) -> dict[str, Any]:
    """A demonstration in the file form of docs/formats.md (metres, quaternions)."""
    out: dict[str, Any] = {"format": "demoplan/demonstration-1", "name": demo.name}
    types, colours, landmarks = dict(demo.types), demo.given_colours, dict(demo.landmarks)
    if demo.objects:
        out["objects"] = {
            n: {"shape": g.shape, "size": list(g.size)}
            | ({} if g.mass is None else {"mass": g.mass})
            | ({"type": types[n]} if n in types else {})
            | ({"colour": colours[n]} if n in colours and n not in landmarks else {})
            for n, g in demo.objects
        }
    if demo.landmarks:
        compartments = dict(demo.compartments)
        out["landmarks"] = {
            n: pose_to_dict(p)
            | ({"compartments": [list(c) for c in compartments[n]]} if n in compartments else {})
            | ({"colour": colours[n]} if n in colours else {})
            for n, p in demo.landmarks
        }
    if demo.initial:
        out["initial"] = {n: pose_to_dict(p) for n, p in demo.initial}
    if demo.provenance:
        out["provenance"] = dict(demo.provenance)
    out["steps"] = [{"object": s.object, **pose_to_dict(s.pose)} for s in demo.steps]
    return out


def check_measured_demonstration(demo: Demonstration, source: str) -> None:
    """A demonstration made from a pose stream or a recording (``segment``,
    ``import``, ``learn`` of a stream) keeps the limits of a demonstration file,
    checked by the same validation on its file form
    (:func:`~demoplan.documents.units.check_measured`): positions, landmarks
    and extents, the spread of its positions, the size of what it moves."""
    check_measured(demonstration_to_dict(demo), source)


def load_object_geometry(
    path: Path, *, known: Collection[str] | None = None
) -> dict[str, ObjectGeometry]:
    """Read ``{"objects": {"cup": {"shape": "cylinder", "size": [0.08, 0.08, 0.1]}}}``
    (JSON or YAML; the schema of a demonstration file's ``objects``, with optional
    ``units``) as geometry per object, in metres.

    ``known`` (e.g. a stream's objects): a name outside it is an
    :class:`~demoplan.errors.InputError` naming the object and listing ``known``.
    """
    source = str(path)
    try:
        parsed = ObjectsFileSchema.model_validate(read_document(path))
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None
    scale = LENGTH_SCALE[parsed.units.length]
    geometry = {name: _geometry(name, g, scale, source, "") for name, g in parsed.objects.items()}
    if known is not None:
        check_geometry_names(geometry, list(known), source)
    return geometry


def load_object_types(path: Path) -> dict[str, str]:
    """The ``type`` each entry of an objects file declares (objects of their own
    type left out): a stream's identical objects (docs/formats.md)."""
    parsed = _objects_file(path)
    return {n: e.type for n, e in parsed.objects.items() if e.type is not None and e.type != n}


def load_object_colours(path: Path) -> dict[str, str]:
    """The ``colour`` (``#rrggbb``) entries of an objects file give: written into
    the demonstrations of the streams or recording it describes (docs/formats.md)."""
    parsed = _objects_file(path)
    return {n: str(e.colour) for n, e in parsed.objects.items() if e.colour is not None}


def _objects_file(path: Path) -> ObjectsFileSchema:
    source = str(path)
    try:
        return ObjectsFileSchema.model_validate(read_document(path))
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None


def with_declared_types(demo: Demonstration, types: Mapping[str, str]) -> Demonstration:
    """``demo`` with the types of its objects that ``types`` declares."""
    names = {n for n, _ in demo.objects} | set(demo.moved_objects)
    declared = tuple((n, t) for n, t in types.items() if n in names)
    return replace(demo, types=declared) if declared else demo


def with_given_colours(demo: Demonstration, colours: Mapping[str, str]) -> Demonstration:
    """``demo`` with the colours ``colours`` gives its objects (those with a
    geometry: a file's ``objects``) and landmarks, in the order its file lists
    them (:func:`demonstration_to_dict`: objects, then landmarks)."""
    landmarks = [n for n, _ in demo.landmarks]
    names = [*(n for n, _ in demo.objects if n not in landmarks), *landmarks]
    given = tuple((n, colours[n]) for n in names if n in colours)
    return replace(demo, colours=given) if given else demo


def check_geometry_names(
    geometry: Mapping[str, ObjectGeometry], known: Sequence[str], source: str | None
) -> None:
    """Every object of an objects file must be one of the streams' objects
    (``known``): an :class:`InputError` naming the first other and listing them."""
    unknown = [name for name in geometry if name not in known]
    if unknown:
        raise InputError(
            f"unknown object{'s' if len(unknown) > 1 else ''} "
            f"{', '.join(map(repr, unknown))}; the stream's objects are "
            f"{', '.join(known) or 'none'}" + did_you_mean(unknown[0], known),
            source=source,
            field=f"objects.{unknown[0]}",
        )


def _geometry(
    name: str, entry: ObjectSchema, scale: float, source: str, where: str
) -> ObjectGeometry:
    """An ``objects`` entry in metres, its mass by :func:`~demoplan.documents.masses.with_mass`."""
    size = (entry.size[0] * scale, entry.size[1] * scale, entry.size[2] * scale)
    return with_mass(
        ObjectGeometry(entry.shape, size),
        entry.mass,
        entry.density,
        source,
        f"{where}objects.{name}",
    )


def demonstrations_from_document(data: dict[str, Any], source: str) -> list[Demonstration]:
    """Parse a ``demonstration-1`` or ``demonstrations-1`` document."""
    kind, _ = check_format(data, {"demonstration", "demonstrations"}, source)
    if kind == "demonstration":
        return [_one(data, source, prefix="", default_name=Path(source).stem)]
    try:
        collection = DemonstrationsSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None
    demos = []
    for index, item in enumerate(collection.demonstrations):
        if not isinstance(item, dict):
            raise InputError(
                "expected a demonstration object", source=source, field=f"demonstrations[{index}]"
            )
        if collection.units is not None and "units" not in item:
            item = {**item, "units": collection.units.model_dump()}
        if "format" in item:
            check_format(item, {"demonstration"}, f"{source}: demonstrations[{index}]")
        demos.append(
            _one(item, source, f"demonstrations[{index}]", f"{Path(source).stem}-{index + 1}")
        )
    return demos


def _one(data: dict[str, Any], source: str, prefix: str, default_name: str) -> Demonstration:
    try:
        parsed = DemonstrationSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source, prefix) from None
    where = f"{prefix}." if prefix else ""
    units = parsed.units
    check_document(data, units, source, prefix)
    scale = LENGTH_SCALE[units.length]
    objects = tuple(
        (name, _geometry(name, g, scale, source, where)) for name, g in parsed.objects.items()
    )
    # A landmark's size may stand in its entry (as in a scene) or under objects.
    for name, entry in parsed.landmarks.items():
        geometry = entry.geometry(units)
        if geometry is None:
            continue
        if name in parsed.objects:
            raise InputError(
                "a landmark's size is given both here and under objects; once expected",
                source=source,
                field=f"{where}landmarks.{name}.size",
            )
        objects += ((name, geometry),)
    for index, step in enumerate(parsed.steps):
        if parsed.objects and step.object not in parsed.objects:
            raise InputError(
                f"unknown object {step.object!r}; expected one of {sorted(parsed.objects)}",
                source=source,
                field=f"{where}steps[{index}].object",
            )
        if step.object in parsed.landmarks:
            raise InputError(
                f"{step.object!r} is a landmark (static) and cannot be moved",
                source=source,
                field=f"{where}steps[{index}].object",
            )
    steps = tuple(
        Step(s.object, pose_from_dict(PoseSchema(**s.model_dump(exclude={"object"})), units))
        for s in parsed.steps
    )
    return Demonstration(
        name=parsed.name or default_name,
        steps=steps,
        objects=objects,
        landmarks=tuple((n, entry.pose(units)) for n, entry in parsed.landmarks.items()),
        compartments=tuple(
            (n, entry.compartment_boxes(units))
            for n, entry in parsed.landmarks.items()
            if entry.compartments
        ),
        initial=tuple((n, pose_from_dict(p, units)) for n, p in parsed.initial.items()),
        source=f"{source}: {prefix}" if prefix else source,
        provenance=tuple(parsed.provenance.items()),
        types=tuple(
            (name, entry.type)
            for name, entry in parsed.objects.items()
            if entry.type is not None and entry.type != name
        ),
        colours=_colours(parsed, source, where),
    )


def _colours(parsed: DemonstrationSchema, source: str, where: str) -> tuple[tuple[str, str], ...]:
    """The colours a demonstration gives (read as ``#rrggbb``, GivenColour):
    its objects', then its landmarks' — the order :func:`demonstration_to_dict`
    writes them in — a landmark's standing in its entry or, where its size
    does, under ``objects``; given in both, an :class:`InputError`."""
    for name, entry in parsed.landmarks.items():
        elsewhere = parsed.objects.get(name)
        if entry.colour is not None and elsewhere is not None and elsewhere.colour is not None:
            raise InputError(
                "a landmark's colour is given both here and under objects; once expected",
                source=source,
                field=f"{where}landmarks.{name}.colour",
            )
    objects = [(n, e.colour) for n, e in parsed.objects.items() if n not in parsed.landmarks]
    landmarks = [
        (n, e.colour if e.colour is not None else getattr(parsed.objects.get(n), "colour", None))
        for n, e in parsed.landmarks.items()
    ]
    return tuple((n, str(c)) for n, c in [*objects, *landmarks] if c is not None)


def load_demonstrations(paths: Iterable[str | Path]) -> list[Demonstration]:
    """Read demonstration files and folders (``*.json``, ``*.yaml``, in name order)
    and check them together (:func:`check_demonstrations`).

    Pose streams (CSV, ROS 2 bags) are segmented first by
    :func:`demoplan.commands.inputs.load_inputs`, which reads both."""
    demos: list[Demonstration] = []
    for path in map(Path, paths):
        demos += demonstrations_from_path(path)
    check_demonstrations(demos)
    return demos


def demonstrations_from_path(path: Path) -> list[Demonstration]:
    """The demonstrations of one file, or of every ``*.json`` / ``*.yaml`` file of a
    folder (in name order); not yet checked against each other.

    A folder's task models, scenes and object geometry files are skipped —
    the studio's work folder holds them beside the demonstrations — and named
    in one warning line (:func:`not_a_demonstration`); a file named on its own
    is read as a demonstration whatever it is."""
    if path.is_dir():
        # Hidden files (editor back-ups, "._x.json" from macOS) are not demonstrations.
        files = sorted(
            p
            for p in path.iterdir()
            if p.suffix.lower() in {".json", ".yaml", ".yml"}
            and not p.name.startswith(".")
            and p.is_file()
        )
        if not files:
            recordings = sorted(p.name for p in path.glob("*.hdf5") if not p.name.startswith("."))
            hint = (
                f" (it holds {recordings[0]}{' and others' if len(recordings) > 1 else ''}: "
                "demoplan import RECORDING -o FOLDER makes a recording's demonstration files)"
                if recordings
                else ""
            )
            raise InputError(
                f"folder holds no .json or .yaml demonstration files{hint}", source=str(path)
            )
        _refuse_links_out_of(path, files)
    else:
        files = [path]
    demos: list[Demonstration] = []
    skipped: list[str] = []
    for file in files:
        document = read_document(file)
        other = not_a_demonstration(document) if path.is_dir() else None
        if other is not None:
            skipped.append(f"{file.name} ({other})")
            continue
        demos += demonstrations_from_document(document, str(file))
    if skipped and not demos:
        raise InputError(
            f"folder holds no demonstration files, only {', '.join(skipped)}; "
            "demonstrations ('demoplan/demonstration-1') expected",
            source=str(path),
        )
    if skipped:
        logger.warning(
            "%s: skipped %s that %s not a demonstration: %s",
            path,
            plural(len(skipped), "file"),
            "is" if len(skipped) == 1 else "are",
            ", ".join(skipped),
        )
    warn_unsupported_releases(demos)
    return demos


def not_a_demonstration(document: Any) -> str | None:
    """What a folder's file is where it is one of demoplan's other files — ``a
    task model``, ``a scene``, ``an objects file`` (an object geometry file:
    ``objects`` without steps, docs/formats.md) — else None (read it as a
    demonstration, and let its faults be told)."""
    if not isinstance(document, dict):
        return None
    tag = document.get("format")
    kind = tag.split("/", 1)[1].rsplit("-", 1)[0] if isinstance(tag, str) and "/" in tag else None
    if isinstance(tag, str) and tag.startswith("demoplan/") and kind in {"model", "scene"}:
        return "a task model" if kind == "model" else "a scene"
    if (
        (tag is None or kind == "objects")
        and "objects" in document
        and not {"steps", "demonstrations"} & set(document)
    ):
        return "an objects file"
    return None


def _refuse_links_out_of(folder: Path, files: Sequence[Path]) -> None:
    """A folder named is read, not what its links lead to: a file that is a
    link leading out of the folder (an unpacked archive's ``demo.json`` →
    ``~/.ssh/id_rsa``) is refused before anything is opened (docs/limits.md,
    "What demoplan opens"). A file meant to be read is named itself."""
    inside = folder.resolve()
    for file in files:
        target = file.resolve()
        if not target.is_relative_to(inside):
            raise InputError(
                f"a link leading out of the folder (to {str(target)!r}); a folder's own "
                "demonstration files expected (name a file elsewhere on the command line)",
                source=str(file),
            )


def check_demonstrations(demos: Sequence[Demonstration]) -> None:
    """Cross-demonstration checks: at least one, consistent geometry, objects vs landmarks."""
    if not demos:
        raise InputError("no demonstrations given; at least one expected", field="demonstrations")
    geometry: dict[str, tuple[ObjectGeometry, str]] = {}
    landmarks: dict[str, str] = {}
    for demo in demos:
        source = demo.source or demo.name
        for name, shape in demo.objects:
            if name in geometry:
                known, where = geometry[name]
                if known.shape != shape.shape or any(
                    abs(a - b) > GEOMETRY_TOLERANCE
                    for a, b in zip(known.size, shape.size, strict=True)
                ):
                    raise InputError(
                        f"{shape.shape} {_metres(shape.size)} differs from {known.shape} "
                        f"{_metres(known.size)} in {where}; one geometry per object expected",
                        source=source,
                        field=f"objects.{name}",
                    )
                if not math.isclose(known.kg, shape.kg, rel_tol=0.01):
                    raise InputError(
                        f"weighs {shape.kg:.3g} kg here and {known.kg:.3g} kg in {where}; "
                        "one mass per object expected",
                        source=source,
                        field=f"objects.{name}",
                    )
            else:
                geometry[name] = (shape, source)
        for name, _ in demo.landmarks:
            landmarks.setdefault(name, source)
    _check_types(demos)
    for demo in demos:
        for index, step in enumerate(demo.steps):
            if step.object in landmarks:
                raise InputError(
                    f"{step.object!r} is moved here but is a landmark (static) in "
                    f"{landmarks[step.object]}; a movable object expected",
                    source=demo.source or demo.name,
                    field=f"steps[{index}].object",
                )


def warn_differing_colours(demos: Sequence[Demonstration]) -> None:
    """One warning line for each object or landmark two demonstrations give
    different colours: each demonstration's figure draws its own, a scene
    naming none takes the first's (docs/formats.md, ``colour``). Not refused,
    as a differing size is: a colour changes no plan."""
    first: dict[str, tuple[str, str]] = {}
    warned: set[str] = set()
    for demo in demos:
        landmarks = {n for n, _ in demo.landmarks}
        for name, colour in demo.colours:
            known, where = first.setdefault(name, (colour, demo.source or demo.name))
            if known != colour and name not in warned:
                warned.add(name)
                group = "landmarks" if name in landmarks else "objects"
                logger.warning(
                    "%s: %s.%s.colour: %s here and %s in %s; a scene naming no colour for "
                    "it draws it in %s",
                    demo.source or demo.name,
                    group,
                    name,
                    colour,
                    known,
                    where,
                    known,
                )


def _check_types(demos: Sequence[Demonstration]) -> None:
    """Instances of one type are interchangeable, so they must be alike: one
    shape and size per type; and no object may be named as another's role
    (``plate#1``) or as a type other than its own."""
    shapes: dict[str, tuple[ObjectGeometry, str, str]] = {}
    types: dict[str, str] = {}
    for demo in demos:
        source = demo.source or demo.name
        for name, shape in demo.objects:
            kind = demo.type_of(name)
            if "#" in name and kind == name:
                raise InputError(
                    "'#' names a role of a type (plate#1); an object name without '#' expected",
                    source=source,
                    field=f"objects.{name}",
                )
            types.setdefault(name, kind)
            if kind not in shapes:
                shapes[kind] = (shape, name, source)
                continue
            known, other, where = shapes[kind]
            if known.shape != shape.shape or any(
                abs(a - b) > GEOMETRY_TOLERANCE for a, b in zip(known.size, shape.size, strict=True)
            ):
                raise InputError(
                    f"{shape.shape} {_metres(shape.size)} differs from {other!r} of the same type "
                    f"{kind!r} ({known.shape} {_metres(known.size)}, {where}); instances of a type "
                    "are interchangeable: one shape and size expected",
                    source=source,
                    field=f"objects.{name}.type",
                )
    for name, kind in types.items():
        if kind != name and kind in types and types[kind] != kind:
            raise InputError(
                f"type {kind!r} is also the name of an object of type {types[kind]!r}; "
                "a type other objects' names do not use expected",
                field=f"objects.{name}.type",
            )


def _metres(size: Sequence[float]) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in size) + "] m"
