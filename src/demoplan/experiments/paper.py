"""The paper's results as data, and fresh data with its structure.

Tables II–V and the plans of §V.B, as the paper prints them — the one
transcription that ``demoplan experiments`` and the golden tests compare
with — and :func:`paper_experiment_1`: new demonstrations with the structure
of Experiment 1 (a new scene per draw, noise on every placement), for
measuring how often learning gives Table II on data nobody tuned.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.model import Demonstration, ObjectGeometry, Pose, Step

__all__ = [
    "CONSTRAINTS_EXPERIMENT_2",
    "PAPER_CONSTRAINTS_EXPERIMENT_1",
    "PAPER_ORDERS",
    "PAPER_PLAN_EXPERIMENT_2",
    "PAPER_PLAN_MOVES_EXPERIMENT_2",
    "PAPER_TABLE_II",
    "PAPER_TABLE_III",
    "PAPER_TABLE_IV",
    "PAPER_TABLE_V",
    "PaperDraw",
    "PaperState",
    "distinct_places",
    "paper_experiment_1",
    "spread_points",
    "table_places",
]


@dataclass(frozen=True, slots=True)
class PaperState:
    """One row of the paper's Table II or IV (positions in m, θ in degrees)."""

    id: str
    object: str
    position_reference: str | None
    position: tuple[float, ...]
    orientation_reference: str | None = None
    theta: float | None = None


PAPER_TABLE_II = (
    PaperState("A", "plate", None, (0.52, 0.44)),
    PaperState("B", "knife", "plate", (0.1, 0.0)),
    PaperState("C", "fork", "plate", (-0.07, 0.0)),
    PaperState("D", "spoon", "knife", (-0.08, 0.04)),
    PaperState("E", "glass", None, (0.52, 0.56)),
    PaperState("F", "food", None, (0.62, 0.56)),
    PaperState("G", "napkin", "plate", (-0.01, -0.02)),
    PaperState("H", "spoon", "plate", (0.02, 0.04)),
    PaperState("I", "knife", "spoon", (0.08, -0.04)),
    PaperState("J", "fork", "glass", (-0.07, -0.12)),
)
PAPER_TABLE_III = ("A-B-C-D-E-F-G", "A-E-H-I-J-F-G", "A-C-B-F-E-D-G")
PAPER_CONSTRAINTS_EXPERIMENT_1 = 32
PAPER_TABLE_IV = (
    PaperState("A", "wood", None, (0.34, 0.04, 0.00), None, 0),
    PaperState("B", "green", "wood", (0.06, 0.00, 0.0), "wood", 0),
    PaperState("C", "red", "wood", (0.03, 0.00, 0.04), "wood", 0),
    PaperState("D", "green", None, (0.40, 0.04, 0.00), None, 0),
)
PAPER_TABLE_V = ("A-B-C", "D-A-C")
# The paper's text says "four constraints"; the rule of §IV.B gives five (docs/learning.md).
CONSTRAINTS_EXPERIMENT_2 = 5


PAPER_ORDERS = (
    ("plate", "knife", "fork", "spoon", "glass", "food", "napkin"),
    ("plate", "glass", "spoon", "knife", "fork", "food", "napkin"),
    ("plate", "fork", "knife", "food", "glass", "spoon", "napkin"),
)
"""The objects of Table III's sequences, in the order each demonstration placed them."""


PAPER_PLAN_MOVES_EXPERIMENT_2 = (5, 4)
"""§V.B: "the plan for the first demonstration is five steps, while the plan for
second demonstration is only four steps"."""
PAPER_PLAN_EXPERIMENT_2 = ("red", "green", "wood", "red")
"""§V.B: "Move red away, move green to position, move wood to position and
finally move red on top of green and wood"."""


@dataclass(frozen=True)
class PaperDraw:
    """Three demonstrations drawn by :func:`paper_experiment_1`, and the scale
    of its deviations."""

    demos: list[Demonstration]
    scale: float


# How the teacher's placements deviate from the nominal layout in each of the
# three demonstrations (m): the plate, the glass, the knife-and-spoon pair
# against the plate, and the fork. Chosen (by a search over such patterns) so
# that Table II is the unambiguous answer: in every step, the reference of
# Table II has a lower spread than every other candidate available at that
# step by ≥ 4 mm RMS (absolute states: lowest or tied with absolute), the
# table's values are met exactly, and no object's absolute placements lie
# more than 4.5 cm apart (so that none is two clusters).
_PLATE = ((0.001, -0.009), (0.015, 0.018))
_GLASS = ((0.012, -0.004), (-0.003, 0.009))
_CUTLERY = (0.005, -0.012)
_FORK = (0.013, -0.001)


def paper_experiment_1(rng: np.random.Generator, sigma: float = 0.0005) -> PaperDraw:
    """Three demonstrations with the structure of the paper's Experiment 1: the
    plate, glass and food absolute; the knife and spoon a pair placed against
    the plate (each against the other once one is down); the fork against the
    plate in x and the glass in y (so that it is nearest to the glass where the
    glass is down, J, else to the plate, C); the napkin on the plate; orders of
    Table III. A new scene per draw: initial poses, the deviations scaled by
    0.95–1.05, and σ noise on every placement."""
    scale = float(rng.uniform(0.95, 1.05))
    p1, p2 = (np.array(v) * scale for v in _PLATE)
    g1, g2 = (np.array(v) * scale for v in _GLASS)
    j = np.array(_CUTLERY) * scale
    f1 = np.array(_FORK) * scale
    plate_dev = [p1, p2, -p1 - p2]
    glass_dev = [g1, g2, -g1 - g2]
    cutlery = [j, np.zeros(2), -j]
    fork_dev = [f1, g2, plate_dev[2] - f1 + p1]
    geometry = (
        ("plate", ObjectGeometry("cylinder", (0.07, 0.07, 0.015))),
        ("knife", ObjectGeometry("box", (0.012, 0.09, 0.005))),
        ("fork", ObjectGeometry("box", (0.012, 0.07, 0.005))),
        ("spoon", ObjectGeometry("box", (0.05, 0.012, 0.008))),
        ("glass", ObjectGeometry("cylinder", (0.05, 0.05, 0.1))),
        ("food", ObjectGeometry("cylinder", (0.08, 0.08, 0.04))),
        ("napkin", ObjectGeometry("box", (0.05, 0.05, 0.003))),
    )
    demos = []
    for d, order in enumerate(PAPER_ORDERS):
        placed: dict[str, np.ndarray] = {}

        def noise() -> np.ndarray:
            return rng.normal(0, sigma, 2)

        for name in order:
            if name == "plate":
                xy = np.array([0.52, 0.44]) + plate_dev[d]
            elif name == "glass":
                xy = np.array([0.52, 0.56]) + glass_dev[d]
            elif name == "food":
                xy = np.array([0.62, 0.56])
            elif name == "napkin":
                xy = placed["plate"] + (-0.01, -0.02)
            elif name == "knife" and "spoon" in placed:
                xy = placed["spoon"] + (0.08, -0.04)
            elif name == "knife":
                xy = placed["plate"] + (0.1, 0.0) + cutlery[d]
            elif name == "spoon" and "knife" in placed:
                xy = placed["knife"] + (-0.08, 0.04)
            elif name == "spoon":
                xy = placed["plate"] + (0.02, 0.04) + cutlery[d]
            else:  # fork: x with the plate, y with the glass (nominal placements)
                xy = np.array([0.45, 0.44]) + fork_dev[d]
            placed[name] = xy + noise()
        initial = spread_points(rng, len(order), 0.35, 0.09)
        assert initial is not None
        steps = tuple(
            Step(
                name,
                Pose(
                    (
                        float(placed[name][0]),
                        float(placed[name][1]),
                        0.015 if name == "napkin" else 0.0,
                    )
                ),
            )
            for name in order
        )
        demos.append(
            Demonstration(
                f"set-table-{d + 1}",
                steps,
                objects=geometry,
                initial=tuple(
                    (name, Pose((float(initial[k][0]) + 0.05, float(initial[k][1]) + 0.15, 0.0)))
                    for k, name in enumerate(sorted(placed))
                ),
            )
        )
    return PaperDraw(demos, scale)


def spread_points(
    rng: np.random.Generator, n: int, side: float, separation: float
) -> np.ndarray | None:
    """``n`` points in a ``side`` square, each at least ``separation`` from the
    others (None when 2000 tries do not find them)."""
    points: list[np.ndarray] = []
    for _ in range(2000):
        p = rng.uniform(0.0, side, 2)
        if all(np.linalg.norm(p - q) >= separation for q in points):
            points.append(p)
            if len(points) == n:
                return np.array(points)
    return None


def table_places(
    rows: Sequence[PaperState], sequences: Sequence[Sequence[str]]
) -> dict[str, tuple[str, tuple[float, ...]]]:
    """Each of a table's states as (object, absolute place): its relative value
    added to its reference's place — the state the reference object takes in
    the same demonstration (Table III / V), itself resolved the same way."""
    row = {r.id: (r.object, r.position_reference, r.position) for r in rows}
    places: dict[str, tuple[str, tuple[float, ...]]] = {}

    def place(state: str, sequence: Sequence[str]) -> tuple[float, ...]:
        _, reference, value = row[state]
        if reference is None:
            return value
        (base,) = (s for s in sequence if row[s][0] == reference)
        return tuple(a + b for a, b in zip(place(base, sequence), value, strict=True))

    for sequence in sequences:
        for state in sequence:
            places.setdefault(state, (row[state][0], place(state, sequence)))
    return places


def distinct_places(
    places: dict[str, tuple[str, tuple[float, ...]]], within: float = 0.011
) -> dict[str, str]:
    """State → the first state with the same object at the same place (the tables
    round to 1 cm, and a sum of two rounded values is within 1 cm)."""
    first: dict[str, str] = {}
    for state, (obj, xy) in places.items():
        first[state] = next(
            (
                seen
                for seen in first.values()
                if places[seen][0] == obj and math.dist(places[seen][1], xy) <= within
            ),
            state,
        )
    return first
