"""A breakfast-tray task of our own, as a user would teach it: a tray (a
landmark with a size) put down at a different place and yaw for every
demonstration; the plate on the tray, the bowl on the plate, the cup and the
spoon beside them on the tray. Only "plate before bowl" is a real constraint:
the orders are drawn so that every other pair is shown both ways.

Everything is written as the files a user writes (``demoplan/demonstration-1``
and ``demoplan/scene-1`` documents), so tests read them through the same
parsers as ``demoplan learn`` and ``demoplan plan``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

TRAY = (0.40, 0.30, 0.02)  # m: a landmark with a size; things stand on its top
OBJECTS: dict[str, tuple[str, tuple[float, float, float]]] = {
    "plate": ("cylinder", (0.16, 0.16, 0.015)),
    "bowl": ("cylinder", (0.12, 0.12, 0.06)),
    "cup": ("cylinder", (0.07, 0.07, 0.09)),
    "spoon": ("box", (0.15, 0.03, 0.01)),
}
# Where each item goes in the tray's frame: (x, y, yaw relative to the tray),
# and what it stands on (z is that thing's top).
LAYOUT: dict[str, tuple[float, float, float, str]] = {
    "plate": (-0.07, 0.0, 0.0, "tray"),
    "bowl": (-0.07, 0.0, 0.0, "plate"),
    "cup": (0.12, 0.08, 0.0, "tray"),
    "spoon": (0.12, -0.07, 90.0, "tray"),
}
RESTING = {  # where the items wait on the table before they are laid out
    "plate": (0.15, -0.45),
    "bowl": (0.35, -0.45),
    "cup": (0.55, -0.45),
    "spoon": (0.75, -0.45),
}


def height_of(name: str) -> float:
    """The top of ``name`` laid out (m): what stands on it stands there."""
    if name == "tray":
        return TRAY[2]
    support = LAYOUT[name][3]
    return height_of(support) + OBJECTS[name][1][2]


def laid_out(tray: tuple[float, float, float]) -> dict[str, tuple[float, float, float, float]]:
    """Each item's place (x, y, z, yaw°) when the tray stands at (x, y, yaw°)."""
    x0, y0, yaw = tray
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    places = {}
    for name, (dx, dy, dyaw, support) in LAYOUT.items():
        z = height_of(support)
        places[name] = (x0 + c * dx - s * dy, y0 + s * dx + c * dy, z, yaw + dyaw)
    return places


@dataclass(frozen=True)
class Family:
    """One breakfast task: the tray's pose per demonstration, the orders, the scatter."""

    trays: tuple[tuple[float, float, float], ...]
    orders: tuple[tuple[str, ...], ...]
    scatter: float  # m: each placement lies within scatter / 2 of its place


def draw_family(seed: int, demonstrations: int, scatter: float) -> Family:
    """``demonstrations`` (3–5) tray poses anywhere on the table (x 0.3–0.7 m,
    y -0.1–0.3 m, any yaw) and orders in which only the plate precedes the bowl
    always: the first two show every other pair both ways. The tray's yaw
    is its front's direction (a landmark's frame is the one given, whatever
    its shape's symmetry): the breakfast turns with it."""
    rng = np.random.default_rng(seed)
    trays = tuple(
        (float(rng.uniform(0.3, 0.7)), float(rng.uniform(-0.1, 0.3)), float(rng.uniform(-180, 180)))
        for _ in range(demonstrations)
    )
    orders = [("plate", "bowl", "cup", "spoon"), ("spoon", "cup", "plate", "bowl")]
    while len(orders) < demonstrations:
        rest = [str(n) for n in rng.permutation(["cup", "spoon", "plate"])]
        at = int(rng.integers(rest.index("plate") + 1, len(rest) + 1))
        orders.append((*rest[:at], "bowl", *rest[at:]))
    return Family(trays, tuple(orders), scatter)


def demonstration_documents(family: Family, seed: int) -> list[dict[str, Any]]:
    """The family's demonstrations as ``demoplan/demonstration-1`` documents."""
    rng = np.random.default_rng(seed + 1)
    documents = []
    for index, (tray, order) in enumerate(zip(family.trays, family.orders, strict=True)):
        places = laid_out(tray)
        steps = []
        for name in order:
            x, y, z, yaw = places[name]
            radius = family.scatter / 2 * math.sqrt(rng.uniform())
            angle = rng.uniform(0, 2 * math.pi)
            step: dict[str, Any] = {
                "object": name,
                "position": [x + radius * math.cos(angle), y + radius * math.sin(angle), z],
            }
            if OBJECTS[name][0] == "box":
                step["yaw"] = yaw + float(rng.normal(0, 1.0))
            steps.append(step)
        documents.append(
            {
                "format": "demoplan/demonstration-1",
                "name": f"breakfast-{index + 1}",
                "objects": {
                    n: {"shape": s, "size": list(size)} for n, (s, size) in OBJECTS.items()
                },
                "landmarks": {
                    "tray": {
                        "position": [tray[0], tray[1], 0.0],
                        "yaw": tray[2],
                        "shape": "box",
                        "size": list(TRAY),
                    }
                },
                "initial": {n: {"position": [x, y, 0.0]} for n, (x, y) in RESTING.items()},
                "steps": steps,
            }
        )
    return documents


def scene_document(tray: tuple[float, float, float] | None, **landmark: Any) -> dict[str, Any]:
    """A run-time scene: the items waiting on the table and the tray at
    ``tray`` (x, y, yaw°) — or, with ``tray`` None, no tray (``landmark``
    gives other landmark entries, such as a misspelt one)."""
    landmarks: dict[str, Any] = dict(landmark)
    if tray is not None:
        landmarks["tray"] = {
            "position": [tray[0], tray[1], 0.0],
            "yaw": tray[2],
            "shape": "box",
            "size": list(TRAY),
        }
    return {
        "format": "demoplan/scene-1",
        "objects": {n: {"position": [x, y, 0.0]} for n, (x, y) in RESTING.items()},
        "landmarks": landmarks,
    }


def carried_tray_documents(family: Family, seed: int) -> list[dict[str, Any]]:
    """The family with the tray an object the person puts down first, at a
    different place and yaw each time (a kit tray), then fills."""
    documents = demonstration_documents(family, seed)
    for document, tray in zip(documents, family.trays, strict=True):
        entry = document["landmarks"].pop("tray")
        document["objects"]["tray"] = {"shape": entry["shape"], "size": entry["size"]}
        document["initial"]["tray"] = {"position": [0.9, 0.45, 0.0]}
        document["steps"].insert(
            0, {"object": "tray", "position": [tray[0], tray[1], 0.0], "yaw": tray[2]}
        )
    return documents


def carried_tray_scene(tray: tuple[float, float, float]) -> dict[str, Any]:
    """A scene where the kit tray already stands, at ``tray`` (x, y, yaw°)."""
    document = scene_document(None)
    document["objects"]["tray"] = {
        "position": [tray[0], tray[1], 0.0],
        "yaw": tray[2],
        "shape": "box",
        "size": list(TRAY),
    }
    return document
