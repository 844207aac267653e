"""Object names: one rule for every file that names objects (docs/formats.md).

A name appears in plans (``GRASP cup loc3 grasp5``), tables and error lines,
one word each: a demonstration's, a scene's, an objects file's and a task
model's objects and landmarks are refused where they are read if a name is
empty, holds a space (a newline, a tab) or a control character (an escape
sequence, a bidirectional override), or is one of the names demoplan gives
locations and grasps. A pose stream's objects (CSV, TF frames, topics) and a
recording's bodies become such names, and are held to the same rule.
"""

from __future__ import annotations

import re
from typing import Annotated

from pydantic import AfterValidator, WithJsonSchema

from demoplan.errors import InputError

__all__ = ["ObjectName", "check_object_name", "object_name_problem"]

MAX_NAME_LENGTH = 200
"""Characters of an object name (a name is a word of a plan, not a document)."""

_RESERVED = re.compile(r"^(loc|freespace|grasp)\d+$")


def object_name_problem(name: str) -> str | None:
    """What is wrong with ``name`` as an object's or a landmark's name, or None."""
    if not name.strip():
        what = "an empty name" if not name else "a name of spaces only"
    elif any(c.isspace() for c in name):
        what = f"{name!r} holds a space, a tab or a line break"
    elif any(not c.isprintable() for c in name):
        what = f"{name!r} holds a control character"
    elif len(name) > MAX_NAME_LENGTH:
        what = f"a name of {len(name):,} characters"
    elif _RESERVED.match(name):
        return (
            f"{name!r} is a name demoplan gives locations and grasps (loc…, freespace…, "
            "grasp…); another name expected"
        )
    else:
        return None
    return (
        f"{what}; an object name of 1 to {MAX_NAME_LENGTH} printable characters without "
        "spaces expected (it appears in plans)"
    )


def check_object_name(name: str, source: str | None, field: str) -> None:
    """Raise the one-line :class:`~demoplan.errors.InputError` for a bad name."""
    if (problem := object_name_problem(name)) is not None:
        raise InputError(problem, source=source, field=field)


def _valid(name: str) -> str:
    if (problem := object_name_problem(name)) is not None:
        raise ValueError(problem)
    return name


ObjectName = Annotated[
    str, AfterValidator(_valid), WithJsonSchema({"type": "string", "format": "object-name"})
]
"""A schema's object or landmark name (a field, or a mapping's key)."""
