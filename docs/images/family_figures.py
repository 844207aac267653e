"""Render the figures of "Generated families" in docs/perception.md: one
photograph of each family of ``demoplan.perception.photo_families``, with its
truth drawn on.

From the repository root::

    python docs/images/family_figures.py

writes next to this file ``family-NAME.png`` for every family (seed 1; for
``distractors`` seed 2, whose photograph has cubes beside the shapes): the
1280 × 720 render shrunk to 480 × 270, a green circle of 0.6 side around each
labelled top face that must be found (the reach of a detection that finds it),
a magenta one around each partial face (a cube on it, a hand over it, the
border through it: it need not be found). The PNGs are stored with 128
colours (small files).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from demoplan.perception.opencv import cv2
from demoplan.perception.photo_families import FAMILIES, family_case

HERE = Path(__file__).resolve().parent
SEED = 1
SEEDS = {"distractors": 2}  # seed 1 has shapes only
SHRINK = 480 / 1280


def figure(family: str) -> np.ndarray:
    """The family's photograph (``SEED``, or its own), shrunk, with its labels drawn on."""
    case = family_case(family, SEEDS.get(family, SEED))
    shrunk = cv2.resize(case.image, (480, 270), interpolation=cv2.INTER_AREA)
    drawn: np.ndarray = np.ascontiguousarray(shrunk)
    for block in case.label.blocks:
        colour = (230, 0, 230) if block.partial else (0, 230, 0)
        centre = (round((block.u + 0.5) * SHRINK - 0.5), round((block.v + 0.5) * SHRINK - 0.5))
        radius = max(2, round(0.6 * block.side_px * SHRINK))
        cv2.circle(drawn, centre, radius, colour, 1, cv2.LINE_AA)
    return drawn


def main() -> None:
    for family in FAMILIES:
        name = HERE / f"family-{family.replace('_', '-')}.png"
        palette = Image.fromarray(figure(family)).quantize(128, method=Image.Quantize.FASTOCTREE)
        palette.save(name, optimize=True)
        print(f"wrote {name.relative_to(HERE.parent.parent)} ({name.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
