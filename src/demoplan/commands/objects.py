"""A user's own objects: the objects file (``demoplan/objects-1``,
docs/formats.md "Objects file") — the things of a task, each with its shape,
size, colour, mass and type, and the landmarks, standing where the task starts.

An objects file is a scene (``demoplan/scene-1``) in which every object gives
its size: it is read by the scene parser, so that a name, a size, a mass, a
colour or a pose means in it what it means in a scene, and ``plan`` and ``run``
read it as the scene it starts from (:func:`demoplan.scenes.scene.load_scene`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from demoplan.errors import InputError
from demoplan.scenes.scene import Scene, scene_from_document, scene_of_objects_file

__all__ = ["ObjectsFile", "objects_from_document", "scene_document"]

@dataclass(frozen=True, slots=True)
class ObjectsFile:
    """What an objects file holds: its start as a scene (with the colours it
    names), and the masses as it gives them."""

    scene: Scene
    masses: tuple[tuple[str, str, float], ...]
    """(name, ``mass`` or ``density``, value) as the file gives them (kg, kg/m³)."""


def objects_from_document(document: dict[str, Any], source: str) -> ObjectsFile:
    """Read a ``demoplan/objects-1`` document (one error line naming ``source``
    and the field otherwise)."""
    scene = scene_from_document(scene_of_objects_file(document, source), source)
    masses: list[tuple[str, str, float]] = []
    for group in ("objects", "landmarks"):
        for name, entry in (document.get(group) or {}).items():
            for key in ("mass", "density"):
                value = entry.get(key)
                if isinstance(value, int | float) and not isinstance(value, bool):
                    masses.append((name, key, float(value)))
    for name, entry in (document.get("objects") or {}).items():
        if entry.get("size") is None:
            raise InputError(
                "has no size; an objects file gives every object's size [x, y, z]",
                source=source,
                field=f"objects.{name}.size",
            )
    return ObjectsFile(scene, tuple(masses))


def scene_document(document: dict[str, Any], source: str) -> dict[str, Any]:
    """The scene an objects file starts from, as ``plan`` and ``run`` read it
    (checked first, :func:`objects_from_document`)."""
    objects_from_document(document, source)
    return scene_of_objects_file(document, source)
