"""Task model files (docs/formats.md ``demoplan/model-1``), written by ``demoplan learn``.

Besides the required fields (``states``, ``sequences``,
``constraints``, ``goals``), a model records each state's statistics (spread,
members), each constraint's support (the demonstrations that show it,
recomputed from ``sequences`` when read), the teacher's constraints and any
demonstration that contradicts them, the learning settings, and the
demonstrations themselves, so that ``demoplan learn --update`` can add one
more and relearn.
"""

from __future__ import annotations

import math
import re
from dataclasses import asdict, fields
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StrictBool,
    StrictStr,
    ValidationError,
    create_model,
    field_validator,
)

from demoplan.documents.demonstrations import demonstration_to_dict, demonstrations_from_document
from demoplan.documents.names import ObjectName
from demoplan.documents.poses import Coordinate
from demoplan.errors import InputError
from demoplan.fileio import (
    check_format,
    describe_validation_error,
    dump_json,
    read_document,
    write_atomic,
)
from demoplan.learning.constraints import constraint_support, label_key
from demoplan.learning.settings import LearningSettings
from demoplan.model import (
    Compartment,
    Demonstration,
    Role,
    State,
    StateOrientation,
    StatePosition,
    TaskModel,
    demonstrated_types,
)
from demoplan.rotations import canonical_quat, quat_from_rpy, unit_length_expected
from demoplan.wording import plural

__all__ = [
    "load_model",
    "model_from_dict",
    "model_to_dict",
    "save_model",
    "settings_from_dict",
    "settings_to_dict",
]


# JSON numbers only: pydantic's lax mode would read "0.5" and true as numbers.
Number = Annotated[float, Field(strict=True)]
Integer = Annotated[int, Field(strict=True)]
_LABEL = re.compile(r"^[A-Z]+(?:#[1-9][0-9]*)?$")  # a state id, or a visit label "C#2"


class _Schema(BaseModel):
    model_config = ConfigDict(extra="allow", allow_inf_nan=False, frozen=True)


class _PositionSchema(_Schema):
    reference: str | None
    value: list[Coordinate] = Field(min_length=2, max_length=3)  # m, within ±MAX_COORDINATE
    spread: Number = 0.0
    frame: Literal["world", "reference"] = "world"
    anywhere: bool = False
    region: list[Coordinate] | None = Field(default=None, min_length=6, max_length=6)
    """A region goal's compartment (m, the reference's frame): low x, y, z, high x, y, z."""

    @field_validator("region")
    @classmethod
    def _low_below_high(cls, region: list[float] | None) -> list[float] | None:
        if region is not None and any(region[k] >= region[k + 3] for k in range(3)):
            raise ValueError(f"expected [x, y, z] low below [x, y, z] high, got {region}")
        return region


class _OrientationSchema(_Schema):
    reference: str | None = None
    value: list[Number] | None = Field(default=None, min_length=1, max_length=3)
    quat: list[Number] | None = Field(default=None, min_length=4, max_length=4)
    spread: Number = 0.0

    @field_validator("value")
    @classmethod
    def _yaw_or_rpy(cls, value: list[float] | None) -> list[float] | None:
        if value is not None and len(value) == 2:
            raise ValueError(f"expected [yaw] or [roll, pitch, yaw] in degrees, got {value}")
        return value

    @field_validator("quat")
    @classmethod
    def _unit_length(cls, quat: list[float] | None) -> list[float] | None:
        if quat is not None and (problem := unit_length_expected(math.hypot(*quat))):
            raise ValueError(f"quat [x, y, z, w]: {problem}")
        return quat


class _StateSchema(_Schema):
    id: str = Field(pattern=r"^[A-Z]+$")
    object: ObjectName
    position: _PositionSchema
    orientation: _OrientationSchema = _OrientationSchema()
    members: list[tuple[Integer, Integer]] = []
    margins: dict[str, Number] = {}
    notes: list[str] = []


class _ViolationSchema(_Schema):
    demonstration: Integer = Field(ge=0)
    required: tuple[str, str]


class _PrecisionSchema(_Schema):
    position: Number = Field(gt=0)
    orientation: Number = Field(gt=0)
    estimated: bool = True


class _RoleSchema(_Schema):
    name: str = Field(min_length=1)
    type: str = Field(min_length=1)
    instances: list[ObjectName | None]


class _ModelSchema(_Schema):
    format: str
    states: list[_StateSchema]
    sequences: list[list[str]]
    constraints: list[list[str]]
    support: list[Integer] = []  # written for people and tools; recomputed on reading
    goals: list[list[str]]
    teacher_constraints: list[list[str]] = []
    violations: list[_ViolationSchema] = []
    settings: dict[str, Any] = {}  # read by settings_from_dict
    precision: _PrecisionSchema | None = None
    roles: list[_RoleSchema] = []
    demonstrations: list[dict[str, Any]] = []


def _requirement_texts(value: Any) -> Any:
    """Model files before ``require`` was a list joined the texts with ';'."""
    return [text for text in value.split(";") if text] if isinstance(value, str) else value


def _settings_schema() -> type[BaseModel]:
    """The model file's ``settings``: the fields of :class:`LearningSettings` as JSON
    (strict numbers, no unknown names), built from the dataclass itself so that a
    new setting cannot be forgotten here. Ranges are checked by the dataclass."""
    kinds: dict[type, Any] = {
        type(None): Number | None,  # estimated from the demonstrations when null
        bool: StrictBool,
        float: Number,
        int: Integer,
        tuple: Annotated[list[StrictStr], BeforeValidator(_requirement_texts)],
    }
    definitions: dict[str, Any] = {
        f.name: (kinds[type(f.default)], list(f.default) if type(f.default) is tuple else f.default)
        for f in fields(LearningSettings)
    }
    config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
    return create_model("SettingsSchema", __config__=config, **definitions)


_SettingsSchema = _settings_schema()


def settings_to_dict(settings: LearningSettings) -> dict[str, Any]:
    """The settings as the model file stores them."""
    return _SettingsSchema.model_validate(asdict(settings)).model_dump()


def settings_from_dict(data: Any, source: str) -> LearningSettings:
    """A model file's ``settings``, or one InputError naming ``settings.<field>``."""
    try:
        parsed = _SettingsSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source, prefix="settings") from None
    values = parsed.model_dump()
    try:
        return LearningSettings(**{**values, "require": tuple(values["require"])})
    except InputError as exc:
        message = str(exc).removeprefix(f"{exc.field}: ")
        raise InputError(message, source=source, field=f"settings.{exc.field}") from None


def model_to_dict(model: TaskModel) -> dict[str, Any]:
    """The model as the JSON document of docs/formats.md (metres, degrees)."""
    return {
        "format": "demoplan/model-1",
        "states": [_state_to_dict(s) for s in model.states],
        "sequences": [list(s) for s in model.sequences],
        "constraints": [list(c) for c in model.constraints],
        "support": list(constraint_support(model.sequences, model.constraints)),
        "goals": [list(g) for g in model.goals],
        "teacher_constraints": [list(c) for c in model.teacher_constraints],
        "violations": [{"demonstration": d, "required": [x, y]} for d, x, y in model.violations],
        "settings": settings_to_dict(model.settings),
        **(
            {}
            if model.precision is None
            else {
                "precision": {
                    "position": model.precision[0],
                    "orientation": model.precision[1],
                    "estimated": model.precision_estimated,
                }
            }
        ),
        **(
            {
                "roles": [
                    {"name": r.name, "type": r.type, "instances": list(r.instances)}
                    for r in model.roles
                ]
            }
            if model.roles
            else {}
        ),
        "demonstrations": [demonstration_to_dict(d) for d in model.demonstrations],
    }


def _state_to_dict(state: State) -> dict[str, Any]:
    orientation = state.orientation
    return {
        "id": state.id,
        "object": state.object,
        "position": {
            "reference": state.position.reference,
            "value": list(state.position.value),
            "spread": state.position.spread,
            "frame": "reference" if state.position.in_reference_frame else "world",
            **({"anywhere": True} if state.position.anywhere else {}),
            **({"region": list(state.position.region)} if state.position.region else {}),
        },
        "orientation": {
            "reference": orientation.reference,
            "value": None if orientation.rpy is None else list(orientation.rpy),
            "quat": None if orientation.value is None else list(orientation.value),
            "spread": orientation.spread,
        },
        "members": [list(m) for m in state.members],
        "margins": dict(state.margins),
        **({"notes": list(state.notes)} if state.notes else {}),
    }


def model_from_dict(data: dict[str, Any], source: str) -> TaskModel:
    """Parse and check a model document; every id it uses must be a state."""
    check_format(data, {"model"}, source)
    try:
        parsed = _ModelSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None
    settings = settings_from_dict(parsed.settings, source)
    states = tuple(_state_from_schema(s) for s in parsed.states)
    ids = [s.id for s in states]
    if len(set(ids)) != len(ids):
        duplicate = next(i for i in ids if ids.count(i) > 1)
        raise InputError(
            f"state id {duplicate!r} appears twice; unique ids expected",
            source=source,
            field="states",
        )
    known = set(ids)

    def check(labels: list[str], field: str) -> tuple[str, ...]:
        for label in labels:
            if not _LABEL.match(label) or label.split("#")[0] not in known:
                raise InputError(
                    f"{label!r} is not a state of this model (states: {', '.join(ids)})",
                    source=source,
                    field=field,
                )
        return tuple(labels)

    def pairs(rows: list[list[str]], field: str) -> tuple[tuple[str, str], ...]:
        out = []
        for index, row in enumerate(rows):
            if len(row) != 2:
                raise InputError("expected a pair [X, Y]", source=source, field=f"{field}[{index}]")
            x, y = check(row, f"{field}[{index}]")
            out.append((x, y))
        return tuple(out)

    sequences = tuple(check(s, f"sequences[{i}]") for i, s in enumerate(parsed.sequences))
    if len(parsed.goals) != len(sequences):
        raise InputError(
            f"{plural(len(parsed.goals), 'goal')} for {plural(len(sequences), 'sequence')}; "
            "one goal per "
            "demonstration expected",
            source=source,
            field="goals",
        )
    demos = _model_demonstrations(parsed, states, len(sequences), source)
    for index, violation in enumerate(parsed.violations):
        if violation.demonstration >= len(sequences):
            raise InputError(
                f"demonstration {violation.demonstration} does not exist; an index below "
                f"{len(sequences)} expected",
                source=source,
                field=f"violations[{index}].demonstration",
            )
        check(list(violation.required), f"violations[{index}].required")
    return TaskModel(
        states=states,
        sequences=sequences,
        constraints=pairs(parsed.constraints, "constraints"),
        goals=tuple(
            tuple(sorted(check(g, f"goals[{i}]"), key=label_key))
            for i, g in enumerate(parsed.goals)
        ),
        demonstrations=tuple(demos),
        teacher_constraints=pairs(parsed.teacher_constraints, "teacher_constraints"),
        violations=tuple(
            (v.demonstration, v.required[0], v.required[1]) for v in parsed.violations
        ),
        settings=settings,
        precision=(
            None
            if parsed.precision is None
            else (parsed.precision.position, parsed.precision.orientation)
        ),
        precision_estimated=parsed.precision is None or parsed.precision.estimated,
        roles=_roles(parsed.roles, demos, source),
    )


def _model_demonstrations(
    parsed: _ModelSchema, states: tuple[State, ...], sequences: int, source: str
) -> list[Demonstration]:
    """The demonstrations a model keeps (none in an older model), one per
    sequence, every state's reference an object of theirs."""
    if not parsed.demonstrations:
        return []
    demos = demonstrations_from_document(
        {"format": "demoplan/demonstrations-1", "demonstrations": parsed.demonstrations},
        source,
    )
    if len(demos) != sequences:
        raise InputError(
            f"{plural(len(demos), 'demonstration')} for "
            f"{plural(sequences, 'sequence')}; one sequence per "
            "demonstration expected",
            source=source,
            field="demonstrations",
        )
    _check_references(states, demos, source)
    return demos


def _roles(roles: list[_RoleSchema], demos: list[Demonstration], source: str) -> tuple[Role, ...]:
    """The model's roles: each an object of its demonstrations, of its type,
    with one instance name (or null) per demonstration."""
    out = []
    for index, role in enumerate(roles):
        where = f"roles[{index}]"
        if demos and len(role.instances) != len(demos):
            raise InputError(
                f"{plural(len(role.instances), 'instance')} for "
                f"{plural(len(demos), 'demonstration')}; one per "
                "demonstration expected (null where it had none)",
                source=source,
                field=f"{where}.instances",
            )
        types = demonstrated_types(demos)
        if demos and types.get(role.name) != role.type:
            raise InputError(
                f"{role.name!r} is not an object of type {role.type!r} in the demonstrations",
                source=source,
                field=f"{where}.name",
            )
        out.append(Role(role.name, role.type, tuple(role.instances)))
    return tuple(out)


def _check_references(states: tuple[State, ...], demos: list[Demonstration], source: str) -> None:
    """Every reference must be something the demonstrations know: an object or landmark."""
    names = {s.object for s in states}
    for demo in demos:
        names |= {n for n, _ in demo.objects} | {n for n, _ in demo.landmarks}
        names |= {n for n, _ in demo.initial} | set(demo.moved_objects)
    for index, state in enumerate(states):
        for kind, reference in (
            ("position", state.position.reference),
            ("orientation", state.orientation.reference),
        ):
            if reference is not None and reference not in names:
                raise InputError(
                    f"unknown reference {reference!r}; null (absolute) or one of "
                    f"{sorted(names)} expected",
                    source=source,
                    field=f"states[{index}].{kind}.reference",
                )


def _state_from_schema(state: _StateSchema) -> State:
    x, y, *rest = state.position.value
    orientation = state.orientation
    quat = None
    if orientation.quat is not None:
        quat = canonical_quat(orientation.quat)
    elif orientation.value is not None:
        rpy = [0.0, 0.0, orientation.value[0]] if len(orientation.value) == 1 else orientation.value
        quat = quat_from_rpy(rpy)
    return State(
        id=state.id,
        object=state.object,
        position=StatePosition(
            state.position.reference,
            (x, y, rest[0] if rest else 0.0),
            state.position.spread,
            in_reference_frame=state.position.frame == "reference"
            and state.position.reference is not None,
            anywhere=state.position.anywhere and state.position.reference is None,
            region=_region(state.position.region) if state.position.reference else None,
        ),
        orientation=StateOrientation(
            orientation.reference if quat is not None else None, quat, orientation.spread
        ),
        members=tuple((m[0], m[1]) for m in state.members),
        margins=tuple(sorted(state.margins.items())),
        notes=tuple(state.notes),
    )


def _region(values: list[float] | None) -> Compartment | None:
    if values is None:
        return None
    x0, y0, z0, x1, y1, z1 = values
    return (x0, y0, z0, x1, y1, z1)


def save_model(model: TaskModel, path: str | Path) -> None:
    """Write ``model`` to ``path`` atomically."""
    write_atomic(Path(path), dump_json(model_to_dict(model)))


def load_model(path: str | Path) -> TaskModel:
    """Read a model file written by ``demoplan learn``."""
    return model_from_dict(read_document(Path(path)), str(path))
