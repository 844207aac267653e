"""Benchmark: the heaviest object the arm's suction cup carries, by shape.

What it measures
----------------
For each shape below, the mass (kg) at which the arm of ``--sim arm`` stops
carrying it in MuJoCo: the object stands at the trial carry's pick place, the
arm takes it, carries it 28 cm across its front and puts it down turned by 90°
(:func:`demoplan.execution.arm.carries`, as the pre-check does); carried means
put down within 1 cm. A bisection on a log scale between 5 g and 0.5 kg, seven
trials per shape (the carry near the limit depends on the motion: the
pre-check keeps a margin of 1.25, docs/execution.md).

Run: ``MUJOCO_GL=egl python benchmarks/arm_capacity.py`` (a few minutes).
"""

from __future__ import annotations

import math

from demoplan.execution.arm import TRIAL_PICK, TRIAL_PLACE, carries
from demoplan.model import ObjectGeometry

SHAPES = {
    "4 cm block": ObjectGeometry("box", (0.04, 0.04, 0.04)),
    "bowl 15 × 7 cm": ObjectGeometry("cylinder", (0.15, 0.15, 0.07)),
    "mug 8 × 10 cm": ObjectGeometry("cylinder", (0.08, 0.08, 0.1)),
    "plate 25 × 2 cm": ObjectGeometry("cylinder", (0.25, 0.25, 0.02)),
    "knife 1.2 × 9 × 0.5 cm": ObjectGeometry("box", (0.012, 0.09, 0.005)),
}


def heaviest_carried(shape: ObjectGeometry, trials: int = 7) -> tuple[float, float]:
    """(carried, not carried): the bracket round the cup's limit for ``shape`` (kg)."""
    low, high = 0.005, 0.5
    for _ in range(trials):
        mass = math.sqrt(low * high)
        shape = ObjectGeometry(shape.shape, shape.size, mass)
        if carries(shape, TRIAL_PICK, TRIAL_PLACE) == (True, True):
            low = mass
        else:
            high = mass
    return low, high


def main() -> None:
    print("| object | carried at | not carried at |")
    print("|---|---|---|")
    for name, shape in SHAPES.items():
        low, high = heaviest_carried(shape)
        print(f"| {name} | {low:.3f} kg | {high:.3f} kg |", flush=True)


if __name__ == "__main__":
    main()
