"""Generated tasks with identical objects (issue: two plates, three red blocks,
a tray of identical cups), with what was meant.

Each generator takes a NumPy generator and the instance names' order per
demonstration, so that tests can shuffle the names and check that nothing
learned or planned depends on them. Instance names are ``<type>-<letter>``;
the generator's truth is per *seat* (or slot, or level), independent of names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.scene import Scene, SceneObject

__all__ = [
    "CUP",
    "SEATS",
    "TABLE_SHAPES",
    "TABLE_TYPES",
    "Taught",
    "cups_into_tray",
    "cups_scene",
    "table_for_two",
    "table_scene",
    "tower_scene",
    "tower_with_two_reds",
]

SEATS = ((0.40, 0.30), (0.40, -0.30))
"""Where the two plates go (m): a seat each."""
TABLE_TYPES = ("plate", "fork", "knife", "glass")
TABLE_SHAPES = {
    "plate": ObjectGeometry("cylinder", (0.20, 0.20, 0.02)),
    "fork": ObjectGeometry("box", (0.03, 0.18, 0.01)),
    "knife": ObjectGeometry("box", (0.02, 0.20, 0.01)),
    "glass": ObjectGeometry("cylinder", (0.07, 0.07, 0.12)),
}
# Offsets from the plate of the seat (m): fork left, knife right, glass behind the knife.
_LAID = {"fork": (-0.14, 0.0), "knife": (0.14, 0.0), "glass": (0.14, 0.16)}
CUP = ObjectGeometry("cylinder", (0.06, 0.06, 0.09))
TRAY = ObjectGeometry("box", (0.30, 0.12, 0.02))
_SLOTS = (-0.09, 0.0, 0.09)  # m along the tray's x axis
BLOCK = ObjectGeometry("box", (0.04, 0.04, 0.04))


@dataclass(frozen=True)
class Taught:
    """Demonstrations and, per demonstration, which instance went to which
    seat/slot/level (``truth[d][name] = place number``, from 0)."""

    demonstrations: tuple[Demonstration, ...]
    truth: tuple[dict[str, int], ...]


def _names(kind: str, count: int, order: Sequence[int]) -> list[str]:
    """Instance names of ``kind`` in ``order``: ``order[i]`` names the i-th placed."""
    letters = "abcdefgh"
    return [f"{kind}-{letters[order[i]]}" for i in range(count)]


def table_for_two(
    rng: np.random.Generator,
    orders: Sequence[dict[str, Sequence[int]]],
    *,
    seat_noise: float = 0.01,
    noise: float = 0.001,
) -> Taught:
    """A table laid for two, once per entry of ``orders`` (per type, the
    instance letters in seat order). Plates go to their seat (absolute, within
    ``seat_noise``); fork, knife and glass relative to the plate of their seat
    (within ``noise``). Seats are laid in a random order, the plate first."""
    demos, truth = [], []
    for index, order in enumerate(orders):
        names = {kind: _names(kind, 2, order[kind]) for kind in TABLE_TYPES}
        steps: list[Step] = []
        seen: dict[str, int] = {}
        for seat in rng.permutation(2):
            sx, sy = SEATS[seat]
            px, py = sx + rng.normal(0, seat_noise), sy + rng.normal(0, seat_noise)
            plate = names["plate"][seat]
            steps.append(Step(plate, Pose((px, py, 0.0), quat_from_yaw(0.0))))
            seen[plate] = int(seat)
            for kind in rng.permutation(["fork", "knife", "glass"]):
                dx, dy = _LAID[str(kind)]
                name = names[str(kind)][seat]
                x, y = px + dx + rng.normal(0, noise), py + dy + rng.normal(0, noise)
                steps.append(Step(name, Pose((x, y, 0.0), quat_from_yaw(0.0))))
                seen[name] = int(seat)
        objects = tuple(
            (name, TABLE_SHAPES[kind]) for kind in TABLE_TYPES for name in sorted(names[kind])
        )
        types = tuple((name, kind) for kind in TABLE_TYPES for name in sorted(names[kind]))
        demos.append(Demonstration(f"table-{index + 1}", tuple(steps), objects, types=types))
        truth.append(seen)
    return Taught(tuple(demos), tuple(truth))


def table_scene(rng: np.random.Generator, order: dict[str, Sequence[int]]) -> Scene:
    """Every piece of the table for two standing apart at the table's edge, in
    ``order`` (per type, the instance letters from left to right)."""
    objects = []
    x0 = 0.05
    for row, kind in enumerate(TABLE_TYPES):
        for column, name in enumerate(_names(kind, 2, order[kind])):
            x = x0 + 0.25 * column + rng.uniform(-0.005, 0.005)
            y = -0.75 + 0.25 * row
            objects.append(
                SceneObject(
                    name, Pose((x + 0.6, y, 0.0), quat_from_yaw(0.0)), TABLE_SHAPES[kind], type=kind
                )
            )
    return Scene(objects=tuple(objects), source="table-for-two scene")


def tower_with_two_reds(reds_swapped: Sequence[bool], *, noise: float = 0.0005) -> Taught:
    """A tower blue < red < red < green at (0.4, 0.1), taught once per entry;
    where ``reds_swapped``, the other red goes first. Truth: level 1 or 2."""
    rng = np.random.default_rng(7)
    demos, truth = [], []
    for index, swapped in enumerate(reds_swapped):
        reds = ["red-b", "red-a"] if swapped else ["red-a", "red-b"]
        order = ["blue", reds[0], reds[1], "green"]
        steps = []
        for level, name in enumerate(order):
            x, y = 0.4 + rng.normal(0, noise), 0.1 + rng.normal(0, noise)
            steps.append(Step(name, Pose((x, y, 0.04 * level), quat_from_yaw(0.0))))
        objects = tuple((n, BLOCK) for n in ("blue", "red-a", "red-b", "green"))
        initial = (
            ("blue", Pose((0.2, -0.2, 0.0), quat_from_yaw(0.0))),
            ("red-a", Pose((0.3, -0.2, 0.0), quat_from_yaw(0.0))),
            ("red-b", Pose((0.4, -0.2, 0.0), quat_from_yaw(0.0))),
            ("green", Pose((0.5, -0.2, 0.0), quat_from_yaw(0.0))),
        )
        demos.append(
            Demonstration(
                f"tower-{index + 1}",
                tuple(steps),
                objects,
                initial=initial,
                types=(("red-a", "red"), ("red-b", "red")),
            )
        )
        truth.append({reds[0]: 0, reds[1]: 1})
    return Taught(tuple(demos), tuple(truth))


def tower_scene(rng: np.random.Generator) -> Scene:
    """The four blocks scattered on the table, apart: a scrambled start."""
    spots = [(0.15, -0.25), (0.30, -0.35), (0.55, -0.25), (0.65, 0.30), (0.20, 0.30)]
    chosen = rng.permutation(len(spots))[:4]
    names = ["blue", "red-x", "red-y", "green"]
    objects = []
    for name, spot in zip(names, chosen, strict=True):
        x, y = spots[spot]
        objects.append(
            SceneObject(
                name,
                Pose((x, y, 0.0), quat_from_yaw(float(rng.uniform(-40, 40)))),
                BLOCK,
                type="red" if name.startswith("red") else None,
            )
        )
    return Scene(objects=tuple(objects), source="tower scene")


def cups_into_tray(
    rng: np.random.Generator, orders: Sequence[Sequence[int]], *, noise: float = 0.001
) -> Taught:
    """Three identical cups into a tray's three slots, once per entry of
    ``orders`` (the cups' letters in slot order); the tray (a landmark) stands
    elsewhere and turned in every demonstration; slots filled in a random order."""
    demos, truth = [], []
    for index, order in enumerate(orders):
        names = _names("cup", 3, order)
        tx, ty = rng.uniform(0.3, 0.5), rng.uniform(-0.2, 0.2)
        yaw = float(rng.uniform(-90, 90))
        c, s = np.cos(np.radians(yaw)), np.sin(np.radians(yaw))
        steps = []
        for slot in rng.permutation(3):
            dx = _SLOTS[slot] + rng.normal(0, noise)
            dy = rng.normal(0, noise)
            x, y = tx + c * dx - s * dy, ty + s * dx + c * dy
            steps.append(Step(names[slot], Pose((x, y, TRAY.size[2]), quat_from_yaw(yaw))))
        objects = (*((n, CUP) for n in sorted(names)), ("tray", TRAY))
        demos.append(
            Demonstration(
                f"cups-{index + 1}",
                tuple(steps),
                objects,
                landmarks=(("tray", Pose((tx, ty, 0.0), quat_from_yaw(yaw))),),
                types=tuple((n, "cup") for n in names),
            )
        )
        truth.append({names[slot]: slot for slot in range(3)})
    return Taught(tuple(demos), tuple(truth))


def cups_scene(
    tray: tuple[float, float, float], names: Sequence[str] = ("cup-x", "cup-y", "cup-z")
) -> Scene:
    """Three cups apart on the table and the tray at ``(x, y, yaw)``."""
    x, y, yaw = tray
    objects = tuple(
        SceneObject(name, Pose((0.15 + 0.12 * i, -0.35, 0.0)), CUP, type="cup")
        for i, name in enumerate(names)
    )
    return Scene(
        objects=objects,
        landmarks=(("tray", Pose((x, y, 0.0), quat_from_yaw(yaw))),),
        landmark_geometry=(("tray", TRAY),),
        source="cups scene",
    )
