"""The issue's task for tests: pack a lunch box (a landmark of 26 × 18 × 2 cm
moved and turned in each of three demonstrations) with a sandwich, an apple, a
juice box, a carrot and a cookie on the sandwich."""

from __future__ import annotations

import math
from typing import Any

from demoplan.documents.demonstrations import demonstrations_from_document
from demoplan.scenes.scene import Scene, scene_from_document, scene_to_dict

BLUE = "#1f5fbf"  # a user's blue sandwich; the palette gives it a pink red
GREEN = "#27ae60"  # a user's green lunch box (a landmark)
LUNCH_BOX = (0.26, 0.18, 0.02)
LUNCH = {  # name: shape, size, place in the box's frame (x, y, z above its top, yaw)
    "sandwich": ("box", (0.10, 0.10, 0.03), (-0.06, 0.02, 0.0, 0.0)),
    "apple": ("sphere", (0.07, 0.07, 0.07), (0.075, 0.04, 0.0, 0.0)),
    "juice": ("box", (0.04, 0.06, 0.10), (0.08, -0.045, 0.0, 90.0)),
    "carrot": ("box", (0.15, 0.025, 0.025), (-0.03, -0.06, 0.0, 0.0)),
    "cookie": ("cylinder", (0.05, 0.05, 0.01), (-0.06, 0.02, 0.03, 0.0)),
}


def lunch_demonstrations() -> list[Any]:
    """The issue's task: pack a lunch box (moved and turned in each of three
    demonstrations), the cookie on the sandwich."""
    demos = []
    for index, (bx, by, turn) in enumerate(
        [(0.45, 0.15, 0.0), (0.5, 0.2, 25.0), (0.4, 0.1, -20.0)]
    ):
        c, s = math.cos(math.radians(turn)), math.sin(math.radians(turn))
        steps = [
            {
                "object": name,
                "position": [bx + c * dx - s * dy, by + s * dx + c * dy, LUNCH_BOX[2] + dz],
                "yaw": turn + yaw,
            }
            for name, (_, _, (dx, dy, dz, yaw)) in LUNCH.items()
        ]
        document = {
            "format": "demoplan/demonstration-1",
            "name": f"lunch-{index + 1}",
            "objects": {
                name: {"shape": sh, "size": list(size)} for name, (sh, size, _) in LUNCH.items()
            },
            "landmarks": {
                "lunchbox": {
                    "position": [bx, by, 0],
                    "yaw": turn,
                    "shape": "box",
                    "size": list(LUNCH_BOX),
                }
            },
            "initial": {name: {"position": [0.1 + 0.15 * k, -0.3]} for k, name in enumerate(LUNCH)},
            "steps": steps,
        }
        demos += demonstrations_from_document(document, f"lunch-{index + 1}.json")
    return demos


def lunch_scene() -> Scene:
    """The lunch box moved and turned 30°, the food where it stood in the demonstrations."""
    return scene_from_document(
        {
            "format": "demoplan/scene-1",
            "objects": {name: {"position": [0.1 + 0.15 * k, -0.3]} for k, name in enumerate(LUNCH)},
            "landmarks": {
                "lunchbox": {
                    "position": [0.35, 0.25, 0],
                    "yaw": 30,
                    "shape": "box",
                    "size": list(LUNCH_BOX),
                }
            },
        },
        "lunch.json",
    )


def coloured_document(**colours: Any) -> dict[str, Any]:
    """The lunch box's start as a scene file, every thing with its size, the
    things named in ``colours`` with that ``colour``."""
    document = scene_to_dict(lunch_scene())
    for name, entry in document["objects"].items():
        shape, size, _ = LUNCH[name]
        entry.update(shape=shape, size=list(size))
    for group in ("objects", "landmarks"):
        for name, entry in document[group].items():
            if name in colours:
                entry["colour"] = colours[name]
    return document
