"""A user's own objects: the objects file (``demoplan/objects-1``,
docs/formats.md "Objects file") — the things of a task, each with its shape,
size, colour, mass and type, and the landmarks, standing where the task starts.

An objects file is a scene (``demoplan/scene-1``) whose objects and landmarks
may also name their ``colour``: it is read by the scene parser, so that a name,
a size, a mass or a pose means in it what it means in a scene, and its start is
the scene that ``plan`` and ``run`` read (:func:`scene_document`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from demoplan.errors import InputError
from demoplan.fileio import check_format
from demoplan.scenes.scene import Scene, scene_from_document

__all__ = ["COLOUR", "ObjectsFile", "objects_from_document", "scene_document"]

COLOUR = re.compile(r"^#[0-9a-fA-F]{6}$")
"""A colour: ``#rrggbb``."""


@dataclass(frozen=True, slots=True)
class ObjectsFile:
    """What an objects file holds: its start as a scene, and the colours it names."""

    scene: Scene
    colours: tuple[tuple[str, str], ...]
    """(name, ``#rrggbb``) for each object or landmark that names its colour."""
    masses: tuple[tuple[str, str, float], ...]
    """(name, ``mass`` or ``density``, value) as the file gives them (kg, kg/m³)."""


def objects_from_document(document: dict[str, Any], source: str) -> ObjectsFile:
    """Read a ``demoplan/objects-1`` document (one error line naming ``source``
    and the field otherwise)."""
    check_format(document, {"objects"}, source)
    colours: list[tuple[str, str]] = []
    masses: list[tuple[str, str, float]] = []
    stripped: dict[str, Any] = {}
    for group in ("objects", "landmarks"):
        entries = document.get(group)
        if entries is None:
            continue
        if not isinstance(entries, dict):
            raise InputError("an object of named entries expected", source=source, field=group)
        stripped[group] = {}
        for name, entry in entries.items():
            if not isinstance(entry, dict):
                raise InputError("an object expected", source=source, field=f"{group}.{name}")
            colour = entry.get("colour")
            if colour is not None:
                if not isinstance(colour, str) or not COLOUR.match(colour):
                    raise InputError(
                        f"{colour!r} is not a colour; #rrggbb expected",
                        source=source,
                        field=f"{group}.{name}.colour",
                    )
                colours.append((name, colour.lower()))
            for key in ("mass", "density"):
                value = entry.get(key)
                if isinstance(value, int | float) and not isinstance(value, bool):
                    masses.append((name, key, float(value)))
            stripped[group][name] = {k: v for k, v in entry.items() if k != "colour"}
    scene = scene_from_document({**document, **stripped, "format": "demoplan/scene-1"}, source)
    for name, entry in stripped.get("objects", {}).items():
        if entry.get("size") is None:
            raise InputError(
                "has no size; an objects file gives every object's size [x, y, z]",
                source=source,
                field=f"objects.{name}.size",
            )
    return ObjectsFile(scene, tuple(colours), tuple(masses))


def scene_document(document: dict[str, Any], source: str) -> dict[str, Any]:
    """The scene an objects file starts from, as ``plan`` and ``run`` read it:
    the document without its colours (checked first, :func:`objects_from_document`)."""
    objects_from_document(document, source)
    out = {k: v for k, v in document.items() if k not in {"objects", "landmarks"}}
    out["format"] = "demoplan/scene-1"
    for group in ("objects", "landmarks"):
        if group in document:
            out[group] = {
                name: {k: v for k, v in entry.items() if k != "colour"}
                for name, entry in document[group].items()
            }
    return out
