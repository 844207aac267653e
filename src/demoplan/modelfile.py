"""Task model files (SPEC §3 ``demoplan/model-1``), written by ``demoplan learn``.

Besides the fields the SPEC requires (``states``, ``sequences``,
``constraints``, ``goals``), a model records each state's statistics (spread,
members), the teacher's constraints and any demonstration that contradicts
them, the learning settings, and the demonstrations themselves, so that
``demoplan learn --update`` can add one more and relearn.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from demoplan.constraints import label_key
from demoplan.demonstrations import demonstration_to_dict, demonstrations_from_document
from demoplan.errors import InputError
from demoplan.fileio import (
    check_format,
    describe_validation_error,
    dump_json,
    read_document,
    write_atomic,
)
from demoplan.model import State, StateOrientation, StatePosition, TaskModel
from demoplan.rotations import canonical_quat, quat_from_rpy

__all__ = ["load_model", "model_from_dict", "model_to_dict", "save_model"]


class _Schema(BaseModel):
    model_config = ConfigDict(extra="allow", allow_inf_nan=False, frozen=True)


class _PositionSchema(_Schema):
    reference: str | None
    value: list[float] = Field(min_length=2, max_length=3)
    spread: float = 0.0


class _OrientationSchema(_Schema):
    reference: str | None = None
    value: list[float] | None = Field(default=None, min_length=1, max_length=3)
    quat: list[float] | None = Field(default=None, min_length=4, max_length=4)
    spread: float = 0.0


class _StateSchema(_Schema):
    id: str = Field(pattern=r"^[A-Z]+$")
    object: str = Field(min_length=1)
    position: _PositionSchema
    orientation: _OrientationSchema = _OrientationSchema()
    members: list[list[int]] = []


class _ModelSchema(_Schema):
    format: str
    states: list[_StateSchema]
    sequences: list[list[str]]
    constraints: list[list[str]]
    goals: list[list[str]]
    teacher_constraints: list[list[str]] = []
    settings: dict[str, float | int | str] = {}
    demonstrations: list[dict[str, Any]] = []


def model_to_dict(model: TaskModel) -> dict[str, Any]:
    """The model as the SPEC's JSON document (metres, degrees)."""
    return {
        "format": "demoplan/model-1",
        "states": [_state_to_dict(s) for s in model.states],
        "sequences": [list(s) for s in model.sequences],
        "constraints": [list(c) for c in model.constraints],
        "goals": [list(g) for g in model.goals],
        "teacher_constraints": [list(c) for c in model.teacher_constraints],
        "violations": [
            {"demonstration": d, "required": [x, y]} for d, x, y in model.violations
        ],
        "settings": dict(model.settings),
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
        },
        "orientation": {
            "reference": orientation.reference,
            "value": None if orientation.rpy is None else list(orientation.rpy),
            "quat": None if orientation.value is None else list(orientation.value),
            "spread": orientation.spread,
        },
        "members": [list(m) for m in state.members],
    }


def model_from_dict(data: dict[str, Any], source: str) -> TaskModel:
    """Parse and check a model document; every id it uses must be a state."""
    check_format(data, {"model"}, source)
    try:
        parsed = _ModelSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None
    states = tuple(_state_from_schema(s) for s in parsed.states)
    ids = [s.id for s in states]
    if len(set(ids)) != len(ids):
        raise InputError("state ids must be unique", source=source, field="states")
    known = set(ids)

    def check(labels: list[str], field: str) -> tuple[str, ...]:
        for label in labels:
            if label.split("#")[0] not in known:
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

    demos = []
    if parsed.demonstrations:
        demos = demonstrations_from_document(
            {"format": "demoplan/demonstrations-1", "demonstrations": parsed.demonstrations},
            source,
        )
    return TaskModel(
        states=states,
        sequences=tuple(check(s, f"sequences[{i}]") for i, s in enumerate(parsed.sequences)),
        constraints=pairs(parsed.constraints, "constraints"),
        goals=tuple(
            tuple(sorted(check(g, f"goals[{i}]"), key=label_key))
            for i, g in enumerate(parsed.goals)
        ),
        demonstrations=tuple(demos),
        teacher_constraints=pairs(parsed.teacher_constraints, "teacher_constraints"),
        violations=tuple(
            (int(v["demonstration"]), str(v["required"][0]), str(v["required"][1]))
            for v in data.get("violations", [])
            if isinstance(v, dict)
        ),
        settings=tuple(parsed.settings.items()),
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
            state.position.reference, (x, y, rest[0] if rest else 0.0), state.position.spread
        ),
        orientation=StateOrientation(
            orientation.reference if quat is not None else None, quat, orientation.spread
        ),
        members=tuple((m[0], m[1]) for m in state.members if len(m) == 2),
    )


def save_model(model: TaskModel, path: str | Path) -> None:
    """Write ``model`` to ``path`` atomically."""
    write_atomic(Path(path), dump_json(model_to_dict(model)))


def load_model(path: str | Path) -> TaskModel:
    """Read a model file written by ``demoplan learn``."""
    return model_from_dict(read_document(Path(path)), str(path))
