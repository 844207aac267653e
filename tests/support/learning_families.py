"""Generated families of demonstrations with a known intended task model.

Each generator takes a NumPy generator (the tests draw its seed with
hypothesis) and returns the demonstrations together with what was meant:
per object, the reference its placement was made against (``None``:
absolute) and the offset in that reference's frame. Every object is placed
once per demonstration, so the intended model has one state per object,
except in :func:`paper_experiment_1`, which regenerates the paper's Table II.

Layouts are chosen so that the intended answer is the unambiguous one under
docs/learning.md: a relative object's reference is also its nearest object (by a
margin), so that the tie rule ("else the nearest reference") agrees with
the lowest spread; references move between demonstrations far more than the
placement noise, so that relative vs absolute is decidable.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from demoplan.experiments.paper import PAPER_ORDERS, PaperDraw, paper_experiment_1, spread_points
from demoplan.experiments.paper import PAPER_TABLE_III as LIBRARY_TABLE_III
from demoplan.experiments.paper import distinct_places as distinct_places
from demoplan.experiments.paper import table_places as table_places
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.rotations import quat_from_yaw
from tests.support.helpers import TABLE_II

__all__ = [
    "PAPER_ORDERS",
    "PAPER_TABLE_II",
    "PAPER_TABLE_III",
    "SYMMETRIC_SHAPES",
    "Family",
    "PaperDraw",
    "constraints_from_sequences",
    "paper_experiment_1",
    "precision_family",
    "rotate",
    "shifted_scene_family",
    "slots_family",
    "symmetric_family",
    "topological_order",
    "tray_family",
    "unambiguous",
]


@dataclass(frozen=True)
class Family:
    """Demonstrations and the task they were generated from.

    ``references[o]`` is the intended position reference of object ``o``
    (``None``: absolute); ``offsets[o]`` its intended value (x, y, z) in the
    reference's frame (world axes for a reference without orientation; the
    world position for absolute objects, ``None`` where it is not fixed);
    ``orders[d]`` is demonstration d's order of objects.
    """

    kind: str
    demos: list[Demonstration]
    references: dict[str, str | None]
    offsets: dict[str, tuple[float, float, float] | None]
    orders: list[list[str]]
    sigma: float
    extra: dict[str, object] = field(default_factory=dict)

    def _repr_pretty_(self, printer: Any, cycle: bool) -> None:  # hypothesis' reports
        printer.text(repr(self))

    def __repr__(self) -> str:  # short, for hypothesis' falsifying examples
        def pose(p: Pose) -> str:
            xy = ", ".join(f"{v:.4f}" for v in p.position[:2])
            return f"({xy})" if p.orientation is None else f"({xy}, {p.rpy[2]:.1f}°)"  # type: ignore[index]

        demos = "; ".join(
            " ".join(f"{s.object}{pose(s.pose)}" for s in d.steps)
            + "".join(f" [{n}{pose(q)}]" for n, q in d.landmarks)
            for d in self.demos
        )
        return f"Family({self.kind}, σ={self.sigma:.4f}, references={self.references}, {demos})"


def rotate(yaw_deg: float, xy: np.ndarray) -> np.ndarray:
    """``xy`` (2,) turned by ``yaw_deg`` about z."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return np.array([c * xy[0] - s * xy[1], s * xy[0] + c * xy[1]])


def topological_order(
    rng: np.random.Generator, references: list[int | None], first: int | None = None
) -> list[int]:
    """A random order of the objects with every reference before the objects
    placed against it (and ``first``, if given, first)."""
    remaining = [i for i in range(len(references)) if i != first]
    order: list[int] = [] if first is None else [first]
    while remaining:
        ready = [i for i in remaining if references[i] is None or references[i] in order]
        pick = ready[int(rng.integers(len(ready)))]
        order.append(pick)
        remaining.remove(pick)
    return order


def constraints_from_sequences(sequences: list[list[str]]) -> set[tuple[str, str]]:
    """Paper §IV.B (docs/learning.md): (X, Y) seen with X before Y somewhere, minus
    pairs seen both ways."""
    seen: set[tuple[str, str]] = set()
    for sequence in sequences:
        for i, x in enumerate(sequence):
            for y in sequence[i + 1 :]:
                if x != y:
                    seen.add((x, y))
    return {(x, y) for x, y in seen if (y, x) not in seen}


def unambiguous(family: Family) -> bool:
    """Whether the drawn placements support the intended references: at no step
    does a candidate available there (absolute, objects placed earlier in that
    demonstration) have a spread (RMS, trace of the sample covariance of the
    relative positions) below the intended reference's by more than σ/2.
    With 2–6 demonstrations a sibling can come out tighter than the true
    reference by chance; such draws are left out."""
    positions = [
        {s.object: np.array(s.pose.position[:2]) for s in demo.steps} for demo in family.demos
    ]

    def spread(obj: str, ref: str | None) -> float:
        rows = np.array([p[obj] - (0.0 if ref is None else p[ref]) for p in positions])
        return float(np.sqrt(np.trace(np.atleast_2d(np.cov(rows.T)))))

    for obj, intended in family.references.items():
        own = spread(obj, intended)
        for order in family.orders:
            for ref in [None, *order[: order.index(obj)]]:
                if spread(obj, ref) < own - family.sigma / 2:
                    return False
    return True


def _nearest_references(
    points: np.ndarray, movable: list[int], margin: float
) -> list[int | None] | None:
    """Each movable object after the first is placed against its nearest earlier
    movable object, which must be its nearest object of all by ``margin``."""
    references: list[int | None] = [None] * len(points)
    for k, i in enumerate(movable):
        if k == 0:
            continue
        earlier = movable[:k]
        ref = min(earlier, key=lambda j: float(np.linalg.norm(points[i] - points[j])))
        d_ref = float(np.linalg.norm(points[i] - points[ref]))
        for j in range(len(points)):
            if j not in (i, ref) and float(np.linalg.norm(points[i] - points[j])) < d_ref + margin:
                return None
        references[i] = ref
    return references


def _names(n: int) -> list[str]:
    return [f"o{i}" for i in range(n)]


def shifted_scene_family(rng: np.random.Generator, n_objects: int, n_demos: int) -> Family:
    """Family 1: the first object anywhere, each later one against an earlier one
    (placements ≥ 8 cm apart), the whole scene translated by 1–5 m per
    demonstration (no two scenes within 1 m: two that happened to coincide
    would make absolute as good an answer as the intended reference),
    σ = 1 cm per axis."""
    sigma = 0.01
    while True:
        points = spread_points(rng, n_objects, 0.5, 0.08)
        if points is None:
            continue
        refs = _nearest_references(points, list(range(n_objects)), 0.02)
        if refs is not None:
            break
    names = _names(n_objects)
    demos, orders = [], []
    shifts: list[np.ndarray] = []
    while len(shifts) < n_demos:  # scenes metres apart: no two within 1 m of each other
        angle = rng.uniform(0, 2 * math.pi)
        shift = rng.uniform(1.0, 5.0) * np.array([math.cos(angle), math.sin(angle)])
        if all(np.linalg.norm(shift - other) >= 1.0 for other in shifts):
            shifts.append(shift)
    for d in range(n_demos):
        shift = shifts[d]
        order = topological_order(rng, refs)
        placed: dict[int, np.ndarray] = {}
        steps = []
        for i in order:
            ref = refs[i]
            base = shift + points[i] if ref is None else placed[ref] + points[i] - points[ref]
            placed[i] = base + rng.normal(0, sigma, 2)
            steps.append(Step(names[i], Pose((float(placed[i][0]), float(placed[i][1]), 0.0))))
        demos.append(Demonstration(f"shifted-{d + 1}", tuple(steps)))
        orders.append([names[i] for i in order])
    references: dict[str, str | None] = {
        names[i]: None if r is None else names[r] for i, r in enumerate(refs)
    }
    offsets: dict[str, tuple[float, float, float] | None] = {
        names[i]: None if r is None else (*(points[i] - points[r]).tolist(), 0.0)
        for i, r in enumerate(refs)
    }
    return Family("shifted", demos, references, offsets, orders, sigma)


TRAY = ObjectGeometry("box", (0.40, 0.30, 0.02))
ITEM = ObjectGeometry("box", (0.03, 0.03, 0.05))


def tray_family(
    rng: np.random.Generator,
    n_items: int,
    n_demos: int,
    *,
    oriented: bool,
    landmark: bool = False,
) -> Family:
    """Family 2: a tray put down at a random place and yaw in [−30°, 30°]; items
    at fixed offsets (5–15 cm) in the tray's frame, standing on it, 1–3 mm
    noise; items without orientation or with a yaw rigid with the tray.
    ``landmark``: the tray is not moved but given as a landmark."""
    sigma = float(rng.uniform(0.001, 0.003))
    while True:
        radii = rng.uniform(0.05, 0.15, n_items)
        angles = rng.uniform(-math.pi, math.pi, n_items)
        offsets = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
        if all(
            np.linalg.norm(offsets[i] - offsets[j]) >= max(radii[i], radii[j]) + 0.02
            for i, j in itertools.combinations(range(n_items), 2)
        ):
            break
    while True:
        trays = rng.uniform((0.3, 0.2), (0.9, 0.6), (n_demos, 2))
        if all(np.linalg.norm(a - b) >= 0.1 for a, b in itertools.combinations(trays, 2)):
            break
    item_yaws = rng.uniform(-180, 180, n_items)
    names = [f"item{i}" for i in range(n_items)]
    top = TRAY.size[2]
    demos, orders = [], []
    for d in range(n_demos):
        yaw = float(rng.uniform(-30.0, 30.0))
        tray_pose = Pose((float(trays[d][0]), float(trays[d][1]), 0.0), quat_from_yaw(yaw))
        steps = [] if landmark else [Step("tray", tray_pose)]
        order = [int(i) for i in rng.permutation(n_items)]
        for i in order:
            xy = trays[d] + rotate(yaw, offsets[i]) + rng.normal(0, sigma, 2)
            item_yaw = float(yaw + item_yaws[i] + rng.normal(0, 0.3)) if oriented else None
            steps.append(
                Step(
                    names[i],
                    Pose(
                        (float(xy[0]), float(xy[1]), top),
                        None if item_yaw is None else quat_from_yaw(item_yaw),
                    ),
                )
            )
        demos.append(
            Demonstration(
                f"tray-{d + 1}",
                tuple(steps),
                objects=(("tray", TRAY), *((n, ITEM) for n in names)),
                landmarks=(("tray", tray_pose),) if landmark else (),
            )
        )
        orders.append(([] if landmark else ["tray"]) + [names[i] for i in order])
    references: dict[str, str | None] = {n: "tray" for n in names}
    values: dict[str, tuple[float, float, float] | None] = {
        n: (float(offsets[i][0]), float(offsets[i][1]), top) for i, n in enumerate(names)
    }
    if not landmark:
        references["tray"] = None
        values["tray"] = None
    return Family("tray", demos, references, values, orders, sigma, {"item_yaws": item_yaws})


SYMMETRIC_SHAPES = {
    "can": (ObjectGeometry("cylinder", (0.066, 0.066, 0.12)), 0.0),
    "square": (ObjectGeometry("box", (0.05, 0.05, 0.05)), 90.0),
    "rectangle": (ObjectGeometry("box", (0.08, 0.04, 0.03)), 180.0),
}


def symmetric_family(
    rng: np.random.Generator, kinds: list[str], n_demos: int, *, relative: bool
) -> Family:
    """Family 3: cans, square and rectangular boxes released at any yaw for their
    symmetric part (a can at any yaw, a square box at base + 90°·k, a
    rectangular one at base + 180°·k, 0.5° noise); positions absolute, or
    (``relative``) against the first object in a scene shifted by 20–50 cm,
    2 mm noise."""
    sigma = 0.002
    points = None
    while points is None:
        points = spread_points(rng, len(kinds), 0.6, 0.15)
    names = [f"{kind}{i}" for i, kind in enumerate(kinds)]
    bases = rng.uniform(-180, 180, len(kinds))
    refs: list[int | None] = [None] + [0 if relative else None] * (len(kinds) - 1)
    demos, orders = [], []
    for d in range(n_demos):
        angle = rng.uniform(0, 2 * math.pi)
        shift = (
            rng.uniform(0.2, 0.5) * np.array([math.cos(angle), math.sin(angle)])
            if relative
            else np.zeros(2)
        )
        order = topological_order(rng, refs)
        placed: dict[int, np.ndarray] = {}
        steps = []
        for i in order:
            ref = refs[i]
            base = shift + points[i] if ref is None else placed[ref] + points[i] - points[ref]
            placed[i] = base + rng.normal(0, sigma, 2)
            _, period = SYMMETRIC_SHAPES[kinds[i]]
            if period == 0.0:
                yaw = float(rng.uniform(-180, 180))
            else:
                turns = int(rng.integers(0, round(360 / period)))
                yaw = float(bases[i] + period * turns + rng.normal(0, 0.5))
            steps.append(
                Step(
                    names[i],
                    Pose((float(placed[i][0]), float(placed[i][1]), 0.0), quat_from_yaw(yaw)),
                )
            )
        demos.append(
            Demonstration(
                f"symmetric-{d + 1}",
                tuple(steps),
                objects=tuple(
                    (n, SYMMETRIC_SHAPES[k][0]) for n, k in zip(names, kinds, strict=True)
                ),
            )
        )
        orders.append([names[i] for i in order])
    references: dict[str, str | None] = {
        names[i]: None if r is None else names[r] for i, r in enumerate(refs)
    }
    return Family("symmetric", demos, references, dict.fromkeys(names), orders, sigma)


def precision_family(
    rng: np.random.Generator, sigma: float, n_objects: int, n_demos: int
) -> Family:
    """Family 4: the same structure at placement noise ``sigma``. Object o0 is put
    first, anywhere (it moves by ≥ 10σ between demonstrations); every other object is
    either absolute at a fixed spot or placed against its nearest earlier
    object of o0's group (which moves with o0). Placements are ≥ max(12 cm,
    6σ + 5 cm) apart."""
    separation = max(0.12, 6 * sigma + 0.05)
    side = separation * 3.0
    while True:
        fixed = [i for i in range(1, n_objects) if rng.random() < 0.35]
        points = spread_points(rng, n_objects, side, separation)
        if points is None:
            continue
        movable = [i for i in range(n_objects) if i not in fixed]
        refs = _nearest_references(points, movable, max(0.02, 2 * sigma))
        if refs is not None:
            break
    gap = max(10 * sigma, 0.03) * 1.2
    ranks = rng.permutation(n_demos)
    moves = [
        np.array([rng.uniform(0, 0.3 * gap), ranks[d] * gap + rng.uniform(0, 0.3 * gap)])
        for d in range(n_demos)
    ]
    far = np.array([2 * side + separation + n_demos * gap, 0.0])  # o0's group, away from the fixed
    names = _names(n_objects)
    demos, orders = [], []
    for d in range(n_demos):
        order = topological_order(rng, refs, first=0)  # nothing to place o0 against
        placed: dict[int, np.ndarray] = {}
        steps = []
        for i in order:
            ref = refs[i]
            if ref is not None:
                base = placed[ref] + points[i] - points[ref]
            elif i in fixed:
                base = points[i]
            else:
                base = far + moves[d] + points[i]
            placed[i] = base + rng.normal(0, sigma, 2)
            steps.append(Step(names[i], Pose((float(placed[i][0]), float(placed[i][1]), 0.0))))
        demos.append(Demonstration(f"precision-{d + 1}", tuple(steps)))
        orders.append([names[i] for i in order])
    references: dict[str, str | None] = {
        names[i]: None if r is None else names[r] for i, r in enumerate(refs)
    }
    offsets: dict[str, tuple[float, float, float] | None] = {}
    for i, r in enumerate(refs):
        if r is not None:
            offsets[names[i]] = (*(points[i] - points[r]).tolist(), 0.0)
        else:
            offsets[names[i]] = (*points[i].tolist(), 0.0) if i in fixed else None
    return Family("precision", demos, references, offsets, orders, sigma)


def slots_family(
    rng: np.random.Generator,
    sigma: float,
    n_slotted: int,
    n_fixed: int,
    n_relative: int,
    n_demos: int,
) -> Family:
    """Family 5: a kit with alternative slots and mixed precision. ``n_slotted``
    objects each go into one of two slots (each slot used in at least three
    demonstrations) and ``n_fixed`` onto one spot, all put down by hand to
    ``sigma``; ``n_relative`` objects are placed against a fixed one ten times
    more precisely (a jig). Spots lie ≥ max(12 cm, 6σ + 6 cm) apart.
    ``extra["slots"]``: each slotted object's two spots."""
    n_absolute = n_slotted + n_fixed
    separation = max(0.12, 6 * sigma + 0.06)
    while True:
        points = spread_points(rng, n_absolute + n_slotted, separation * 4, separation)
        if points is not None:
            break
    names = _names(n_absolute + n_relative)
    slotted = names[:n_slotted]
    slots = {name: (points[k], points[n_absolute + k]) for k, name in enumerate(slotted)}
    fixed = {names[n_slotted + k]: points[n_slotted + k] for k in range(n_fixed)}
    jigged = {
        names[n_absolute + k]: (
            names[n_slotted + int(rng.integers(n_fixed))],
            np.array(_planar_offset(rng)),
        )
        for k in range(n_relative)
    }
    choices = {
        name: rng.permutation([d % 2 for d in range(n_demos)]) for name in slotted
    }  # n_demos ≥ 6: each slot at least three times
    demos, orders = [], []
    for d in range(n_demos):
        order = [*rng.permutation(slotted + list(fixed)).tolist()]
        for name in jigged:  # after its reference, anywhere
            order.insert(order.index(jigged[name][0]) + 1, name)
        placed: dict[str, np.ndarray] = {}
        steps = []
        for name in order:
            if name in slots:
                placed[name] = slots[name][int(choices[name][d])] + rng.normal(0, sigma, 2)
            elif name in fixed:
                placed[name] = fixed[name] + rng.normal(0, sigma, 2)
            else:
                reference, offset = jigged[name]
                placed[name] = placed[reference] + offset + rng.normal(0, sigma / 10, 2)
            xy = placed[name]
            steps.append(Step(name, Pose((float(xy[0]), float(xy[1]), 0.0))))
        demos.append(Demonstration(f"slots-{d + 1}", tuple(steps)))
        orders.append(order)
    references: dict[str, str | None] = {name: None for name in [*slotted, *fixed]}
    references |= {name: reference for name, (reference, _) in jigged.items()}
    offsets: dict[str, tuple[float, float, float] | None] = {name: None for name in slotted}
    offsets |= {name: (*xy.tolist(), 0.0) for name, xy in fixed.items()}
    offsets |= {name: (*offset.tolist(), 0.0) for name, (_, offset) in jigged.items()}
    return Family("slots", demos, references, offsets, orders, sigma, extra={"slots": slots})


def _planar_offset(rng: np.random.Generator) -> tuple[float, float]:
    """A jig's offset from its reference: 6–10 cm in any direction."""
    angle = rng.uniform(0, 2 * math.pi)
    length = rng.uniform(0.06, 0.10)
    return (length * math.cos(angle), length * math.sin(angle))


# The paper's Experiment 1 (§V.A; Tables II and III): the library's draws.
PAPER_TABLE_II = TABLE_II
PAPER_TABLE_III = [sequence.replace("-", "") for sequence in LIBRARY_TABLE_III]
