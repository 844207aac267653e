"""Benchmark: the heaviest object each of the arm's tools carries, by shape.

What it measures
----------------
For each shape below and each tool of ``--sim arm`` — the 10 mm suction cup
and the parallel-jaw fingers — the mass (kg) at which the arm stops carrying
it in MuJoCo: the object stands at the trial carry's pick place, the arm takes
it with that tool (the fingers across its narrowest side), carries it 28 cm
across its front and puts it down turned by 90°
(:func:`demoplan.execution.arm.carries`, as the pre-check does); carried means
put down within 1 cm. A bisection on a log scale, seven trials per shape and
tool: between 5 g and 0.5 kg for the cup, between 50 g and 5 kg for the
fingers, or up to the mass of the shape in osmium, the densest solid, if that
is lighter ("≥": carried even then). The carry
near the limit depends on the motion: the pre-check keeps a margin of 1.25
(docs/execution.md). "—": the tool cannot take the shape at all (too wide for
the fingers, too narrow for the pad).

Run: ``MUJOCO_GL=egl python benchmarks/arm_capacity.py`` (about 6 minutes).
"""

from __future__ import annotations

import math

from demoplan.documents.masses import MAX_DENSITY
from demoplan.execution.arm import TRIAL_PICK, TRIAL_PLACE, Tool, carries
from demoplan.model import ObjectGeometry
from demoplan.scenes.geometry import half_extent

SHAPES = {
    "4 cm block": ObjectGeometry("box", (0.04, 0.04, 0.04)),
    "mug 8 × 9.5 cm": ObjectGeometry("cylinder", (0.08, 0.08, 0.095)),
    "bowl 14 × 6 cm": ObjectGeometry("cylinder", (0.14, 0.14, 0.06)),
    "plate 24 × 2 cm": ObjectGeometry("cylinder", (0.24, 0.24, 0.02)),
    "knife 1.2 × 9 × 0.5 cm": ObjectGeometry("box", (0.012, 0.09, 0.005)),
}
RANGES: dict[Tool, tuple[float, float]] = {"suction": (0.005, 0.5), "fingers": (0.05, 5.0)}


def heaviest_carried(
    shape: ObjectGeometry, tool: Tool, axis: float, trials: int = 7
) -> tuple[float, float] | None:
    """(carried, not carried): the bracket round ``tool``'s limit for ``shape``
    (kg); None when it does not carry even the lightest."""
    low, high = RANGES[tool]
    high = min(high, MAX_DENSITY * shape.volume)

    def carried(mass: float) -> bool:
        loaded = ObjectGeometry(shape.shape, shape.size, mass)
        return carries(loaded, TRIAL_PICK, TRIAL_PLACE, tool, axis) == (True, True)

    if not carried(low):
        return None
    if carried(high):
        return high, math.inf
    for _ in range(trials):
        mass = math.sqrt(low * high)
        if carried(mass):
            low = mass
        else:
            high = mass
    return low, high


def _cell(bracket: tuple[float, float] | None) -> str:
    if bracket is None:
        return "— | —"
    low, high = bracket
    if math.isinf(high):
        return f"≥ {low:.3f} kg | —"
    return f"{low:.3f} kg | {high:.3f} kg"


def main() -> None:
    print("| object | cup carries | cup drops | fingers carry | fingers drop |")
    print("|---|---|---|---|---|")
    for name, shape in SHAPES.items():
        axis = min((0.0, 90.0), key=lambda a: half_extent(shape, a))  # the narrowest side
        cells = [_cell(heaviest_carried(shape, tool, axis)) for tool in ("suction", "fingers")]
        print(f"| {name} | {' | '.join(cells)} |", flush=True)


if __name__ == "__main__":
    main()
