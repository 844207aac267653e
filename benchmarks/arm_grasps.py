"""Benchmark: does the arm carry what its pre-check accepts, at the first attempt?

What it measures
----------------
Over cluttered household layouts (``tests/support/arm_layouts.py``: three objects —
boxes, cylinders, spheres 3–12 cm, 0.05–1 kg — at random 18–65 cm in front of
an arm at the origin, 5 cm apart, each with a random place to go and either of
the default grasps), for each object in turn: the check a run makes before
the arm moves (``why_not_graspable``, ``why_not_reachable`` at both places),
and where it accepts, one grasp and put-down in MuJoCo. Carried: put down
within 1 cm of its place. A layout stops at its first failure (what follows
no longer stands where it was drawn). Printed: the objects accepted and
carried, the rate with its 95 % Wilson lower bound, the refusals by reason,
the median and 90th percentile wall seconds per carry, and every failure.

Flat boxes and books (``--flat N``, default 20): the same check and first
attempt for one flat box at a time — 6–16 cm wide, 2–5 cm tall, 0.05–0.6 kg
log-uniform (a sandwich, a book, a tray; the heavier ones beyond what the
10 mm cup holds) — standing at random 30–55 cm in front of the arm, with a
random place to go, after the named ones: the lunch box's sandwich (10 × 10 ×
3 cm of wood, 0.18 kg) and a 15 × 10 × 3 cm book at 0.2, 0.3 and 0.4 kg.
Printed: each named one's outcome, and for the drawn ones the accepted and
carried by mass band, with the refusals' reasons.

Run: ``MUJOCO_GL=egl python benchmarks/arm_grasps.py --layouts 60`` (about
10 s a layout on a shared 2-core machine); ``--first K`` starts at layout
seed K; ``--layouts 0 --flat 40`` the flat boxes alone (about 5 s each).
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np
from tests.support.arm_layouts import GAP, Attempt, Item, attempt_all, layout

from demoplan.execution.arm import choose_tool
from demoplan.model import ObjectGeometry, Pose
from demoplan.rotations import quat_from_yaw

BOOK = (0.15, 0.10, 0.03)
NAMED = {
    "sandwich 10 × 10 × 3 cm, wood": ObjectGeometry("box", (0.10, 0.10, 0.03)),
    "book 15 × 10 × 3 cm, 0.2 kg": ObjectGeometry("box", BOOK, 0.2),
    "book 15 × 10 × 3 cm, 0.3 kg": ObjectGeometry("box", BOOK, 0.3),
    "book 15 × 10 × 3 cm, 0.4 kg": ObjectGeometry("box", BOOK, 0.4),
}
FLAT_SIZES = (0.06, 0.16)  # m across
FLAT_HEIGHTS = (0.02, 0.05)  # m
FLAT_MASSES = (0.05, 0.6)  # kg, log-uniform
MASS_BANDS = (0.2, 0.3, 0.35, 0.4, 0.45)  # kg: the rows of the flat boxes' table
OUTCOMES = ("refused", "carried", "not grasped", "not placed")


def wilson_lower(successes: int, total: int, z: float = 1.96) -> float:
    """The lower end of the Wilson score interval (95 % by default)."""
    if total == 0:
        return 0.0
    p = successes / total
    centre = p + z * z / (2 * total)
    spread = z * math.sqrt(p * (1 - p) / total + z * z / (4 * total * total))
    return (centre - spread) / (1 + z * z / total)


def _reason(attempt: Attempt) -> str:
    why = attempt.refused or ""
    if "reach" in why:
        return "out of reach"
    if "sphere" in why:
        return "a sphere too wide for the fingers"
    if "weighs" in why:
        return "too heavy for the cup, too wide or heavy for the fingers"
    return why[:60]


def flat_item(seed: int, shape: ObjectGeometry | None = None) -> Item:
    """One flat box (``shape``, or drawn from ``seed``) at a random spot 30–55 cm
    in front of the arm, ±60° of its front, with a random place to go at least
    :data:`~tests.support.arm_layouts.GAP` clear of it."""
    rng = np.random.default_rng(seed)
    if shape is None:
        x, y = (float(v) for v in rng.uniform(*FLAT_SIZES, 2))
        z = float(rng.uniform(*FLAT_HEIGHTS))
        mass = math.exp(rng.uniform(math.log(FLAT_MASSES[0]), math.log(FLAT_MASSES[1])))
        shape = ObjectGeometry("box", (x, y, z), mass)
    radius = math.hypot(shape.size[0], shape.size[1]) / 2

    def spot() -> Pose:
        distance = float(rng.uniform(0.3, 0.55))
        angle = math.radians(float(rng.uniform(-60.0, 60.0)))
        yaw = float(rng.uniform(-90.0, 90.0))
        return Pose(
            (distance * math.cos(angle), distance * math.sin(angle), 0.0), quat_from_yaw(yaw)
        )

    start = spot()
    place = spot()
    while math.dist(start.position, place.position) < 2 * radius + GAP:
        place = spot()
    return Item("box", shape, start, place, float(rng.choice([0.0, 90.0])))


def _band(kg: float) -> tuple[int, str]:
    """The row of the flat boxes' table ``kg`` falls in: (its order, its label)."""
    edges = (0.0, *MASS_BANDS, math.inf)
    index = next(k for k in range(len(edges) - 1) if kg <= edges[k + 1])
    low, high = edges[index], edges[index + 1]
    return index, f"> {low:g} kg" if math.isinf(high) else f"{low:g}–{high:g} kg"


def flat_boxes(count: int) -> None:
    """The named flat boxes and books, then ``count`` drawn ones (module docstring)."""
    for seed, (name, shape) in enumerate(NAMED.items()):
        (attempt,) = attempt_all((flat_item(seed, shape),))
        print(f"{name}: {attempt.outcome}" + (f" ({attempt.refused})" if attempt.refused else ""))
    bands: dict[tuple[int, str], Counter[str]] = {}
    started = time.perf_counter()
    for seed in range(count):
        (attempt,) = attempt_all((flat_item(1000 + seed),))
        counts = bands.setdefault(_band(attempt.item.geometry.kg), Counter())
        counts[attempt.outcome] += 1
        if attempt.refused is None:  # the check's answer, cached: no new trial
            counts[f"by the {choose_tool(attempt.item.geometry).tool}"] += 1
        if attempt.outcome not in ("carried", "refused"):
            item = attempt.item
            print(
                f"flat box {seed}: {[round(v, 3) for v in item.geometry.size]} "
                f"{item.geometry.kg:.3f} kg: {attempt.outcome}",
                flush=True,
            )
        elif attempt.refused is not None:
            print(f"flat box {seed}: {attempt.item.geometry.kg:.3f} kg refused: {_reason(attempt)}")
    print(
        f"{count} flat boxes 6–16 cm, 2–5 cm tall, checked in {time.perf_counter() - started:.0f} s"
    )
    print("| mass | boxes | accepted (by the cup) | carried at the first attempt |")
    print("|---|---|---|---|")
    for band in sorted(bands):
        counts = bands[band]
        tried = sum(counts[outcome] for outcome in OUTCOMES)
        accepted = tried - counts["refused"]
        print(
            f"| {band[1]} | {tried} | {accepted} ({counts['by the suction']}) "
            f"| {counts['carried']} |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--layouts", type=int, default=60)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--objects", type=int, default=3)
    parser.add_argument("--flat", type=int, default=20, help="flat boxes and books to try")
    options = parser.parse_args()
    if options.flat:
        flat_boxes(options.flat)
    if not options.layouts:
        return
    started = time.perf_counter()
    attempts: list[Attempt] = []
    for seed in range(options.first, options.first + options.layouts):
        done = attempt_all(layout(seed, options.objects))
        attempts += done
        for attempt in done:
            if attempt.outcome not in ("carried", "refused"):
                item = attempt.item
                print(
                    f"layout {seed}: {item.name} {[round(v, 3) for v in item.geometry.size]} "
                    f"{item.geometry.kg:.3f} kg from {[round(v, 3) for v in item.start.position]}"
                    f" to {[round(v, 3) for v in item.place.position]}: {attempt.outcome}",
                    flush=True,
                )
    accepted = [a for a in attempts if a.outcome != "refused"]
    carried = sum(a.outcome == "carried" for a in accepted)
    seconds = sorted(a.seconds for a in accepted)
    print(
        f"{options.layouts} layouts (seeds {options.first}–{options.first + options.layouts - 1}),"
        f" {len(attempts)} objects checked in {time.perf_counter() - started:.0f} s"
    )
    if accepted:
        print(
            f"accepted {len(accepted)}, carried at the first attempt {carried} "
            f"({100 * carried / len(accepted):.1f} %; 95 % lower bound "
            f"{100 * wilson_lower(carried, len(accepted)):.1f} %)"
        )
        print(
            f"seconds per carry: median {statistics.median(seconds):.1f}, "
            f"90th percentile {seconds[int(0.9 * (len(seconds) - 1))]:.1f}"
        )
    print("refused:", dict(Counter(_reason(a) for a in attempts if a.outcome == "refused")))
    moved = [a for a in attempts if a.moved_while_checking]
    print(f"checks during which the arm moved: {len(moved)}")


if __name__ == "__main__":
    main()
