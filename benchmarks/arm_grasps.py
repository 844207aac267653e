"""Benchmark: does the arm carry what its pre-check accepts, at the first attempt?

What it measures
----------------
Over cluttered household layouts (``tests/arm_layouts.py``: three objects —
boxes, cylinders, spheres 3–12 cm, 0.05–1 kg — at random 18–65 cm in front of
an arm at the origin, 5 cm apart, each with a random place to go and either of
the default grasps), for each object in turn: the check a run makes before
the arm moves (``why_not_graspable``, ``why_not_reachable`` at both places),
and where it accepts, one grasp and put-down in MuJoCo. Carried: put down
within 1 cm of its place. A layout stops at its first failure (what follows
no longer stands where it was drawn). Printed: the objects accepted and
carried, the rate with its 95 % Wilson lower bound, the refusals by reason,
the median and 90th percentile wall seconds per carry, and every failure.

Run: ``MUJOCO_GL=egl python benchmarks/arm_grasps.py --layouts 60`` (about
10 s a layout on a shared 2-core machine); ``--first K`` starts at layout
seed K.
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

from tests.arm_layouts import Attempt, attempt_all, layout


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--layouts", type=int, default=60)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--objects", type=int, default=3)
    options = parser.parse_args()
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
