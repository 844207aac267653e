"""A table for two laid with identical objects (issue 29): two plates, forks,
knives and glasses, one of each per seat, whose instance names the generator
hands out to the seats at random in every demonstration, so that it knows
which instance filled which role: the truth the roles table and the figures
must show (tests/plotting/test_roles_display.py, tests/studio/test_studio_browser.py)."""

from __future__ import annotations

import random

from demoplan.model import Demonstration, Pose, Step
from demoplan.rotations import quat_from_yaw
from tests.support.identical_families import SEATS, TABLE_SHAPES, TABLE_TYPES

TYPES = TABLE_TYPES
SHAPES = TABLE_SHAPES
BESIDE = {"plate": (0.0, 0.0), "fork": (0.0, 0.14), "knife": (0.0, -0.14), "glass": (0.15, -0.14)}
"""Where each piece goes relative to its seat's plate."""

Seating = dict[str, tuple[str, str]]
"""Per type, the instance at seat 1 and the one at seat 2."""


def table_for_two(name: str, seating: Seating, seed: int) -> Demonstration:
    """One demonstration: seat 1 laid (plate, fork, knife, glass), then seat 2,
    each with the instances ``seating`` gives it; the plates placed within a
    few cm of their seat, the rest within a mm of their place by the plate."""
    rng = random.Random(seed)
    steps = []
    for seat, (sx, sy) in enumerate(SEATS):
        px, py = sx + rng.gauss(0, 0.02), sy + rng.gauss(0, 0.02)
        for kind in TYPES:
            dx, dy = BESIDE[kind]
            noise = (0.0, 0.0) if kind == "plate" else (rng.gauss(0, 0.001), rng.gauss(0, 0.001))
            position = (px + dx + noise[0], py + dy + noise[1], 0.0)
            steps.append(Step(seating[kind][seat], Pose(position, quat_from_yaw(0.0))))
    objects = tuple((f"{kind}-{c}", SHAPES[kind]) for kind in TYPES for c in "ab")
    types = tuple((f"{kind}-{c}", kind) for kind in TYPES for c in "ab")
    return Demonstration(name, tuple(steps), objects, types=types)


def seating_from(swaps: list[dict[str, bool]]) -> list[Seating]:
    """Per demonstration, per type: ``(a, b)`` or, swapped, ``(b, a)`` at seats 1 and 2."""
    return [
        {
            kind: (f"{kind}-b", f"{kind}-a") if swapped[kind] else (f"{kind}-a", f"{kind}-b")
            for kind in TYPES
        }
        for swapped in swaps
    ]


def expected_rows(seatings: list[Seating]) -> list[tuple[str, ...]]:
    """The roles table the truth gives: seat 1's pieces are the #1 roles (seat 1
    is laid first), each role filled in every demonstration by the instance
    the generator put at that seat."""
    return [
        (f"{kind}#{seat + 1}", kind, *(seating[kind][seat] for seating in seatings))
        for kind in TYPES
        for seat in (0, 1)
    ]


SWAPS = [
    {"plate": False, "fork": True, "knife": False, "glass": True},
    {"plate": True, "fork": False, "knife": True, "glass": False},
    {"plate": True, "fork": True, "knife": False, "glass": False},
]
