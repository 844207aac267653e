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

It also writes ``family-achromatic-regions.png``: the ``achromatic`` family's
photograph (seed 1) as ``demoplan.perception.achromatic`` sees it — left the
table's local lightness it is compared with, right the black, white and grey
candidate regions (cyan outlines), the parts rejected (magenta: markers;
orange: not compact, elongated, at the border, beside a coloured block) and the
blocks found (green squares).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from demoplan.perception.achromatic import local_table_lightness
from demoplan.perception.blocks import PerceptionSettings, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.colours import RejectedPart, colour_regions
from demoplan.perception.opencv import cv2
from demoplan.perception.photo_families import FAMILIES, family_case
from demoplan.perception.seams import image_lightness

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


def achromatic_figure() -> np.ndarray:
    """The achromatic family's seed 1: the local table's lightness beside the black,
    white and grey candidate regions, the parts rejected and the blocks found."""
    case = family_case("achromatic", SEED)
    settings = PerceptionSettings()
    px_per_m = case.label.px_per_m
    side_px = settings.min_side * px_per_m
    table = local_table_lightness(image_lightness(case.image), side_px)
    left = cv2.cvtColor(np.clip(table * 2.55, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2RGB)
    right = np.ascontiguousarray(case.image)
    rejected: list[RejectedPart] = []
    regions, _ = colour_regions(case.image, min_area=0.3 * side_px**2, rejected=rejected)
    for region in regions:
        if region.colour in ("black", "white", "grey"):
            row, col = region.offset
            mask = (region.alpha > 0.5).astype(np.uint8)
            contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
            cv2.drawContours(right, contours, -1, (0, 220, 255), 3, offset=(col, row))
    achromatic_reasons = {"marker", "not compact", "elongated", "cut by the border"}
    for part in rejected:
        if part.reason in achromatic_reasons or part.detail.startswith("beside a coloured"):
            colour = (230, 0, 230) if part.reason == "marker" else (255, 140, 0)
            outlines = [np.round(o).astype(np.int32) for o in part.outlines]
            cv2.polylines(right, outlines, True, colour, 3)
    height = case.image.shape[0]
    for block in detect_blocks(case.image, Camera(px_per_m, (0.0, 0.0)), settings):
        u, v = block.x * px_per_m - 0.5, height - block.y * px_per_m - 0.5
        half = block.side * px_per_m / 2
        corners = cv2.boxPoints(((u, v), (2 * half, 2 * half), -block.yaw))
        cv2.polylines(right, [np.round(corners).astype(np.int32)], True, (0, 230, 0), 3)
    panels = [
        cv2.resize(panel, (480, 270), interpolation=cv2.INTER_AREA) for panel in (left, right)
    ]
    return np.concatenate(panels, axis=1)


def main() -> None:
    name = HERE / "family-achromatic-regions.png"
    palette = Image.fromarray(achromatic_figure()).quantize(128, method=Image.Quantize.FASTOCTREE)
    palette.save(name, optimize=True)
    print(f"wrote {name.relative_to(HERE.parent.parent)} ({name.stat().st_size // 1024} KB)")
    for family in FAMILIES:
        name = HERE / f"family-{family.replace('_', '-')}.png"
        palette = Image.fromarray(figure(family)).quantize(128, method=Image.Quantize.FASTOCTREE)
        palette.save(name, optimize=True)
        print(f"wrote {name.relative_to(HERE.parent.parent)} ({name.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
