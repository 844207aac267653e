"""Calibration from markers: block position error and time per photograph over
oblique views (benchmarks/README.md, ``calibration.py``).

    python benchmarks/calibration.py [--views 40] [--seed 0]

Renders (demoplan.perception.pinhole) of a table with four 4 cm DICT_4X4_50
markers 30 × 20 cm apart and three 4 cm cubes at random poses, seen from 0.5–0.7 m,
0–30° from vertical, any heading, 640 × 480 px, focal length 560 px; each view
perceived as ``perceive --markers`` does (calibrate, rectify, detect), with the
intrinsics given and without them (focal length estimated; tilts ≥ 10°), with
``--side`` and without. Prints per setting: cubes found, the centre error (mm,
median / p95 / max) and the time per photograph (median / p95, calibration
included).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from demoplan.errors import InputError
from demoplan.perception.calibrated import perceive_calibrated
from demoplan.perception.calibration import Intrinsics, MarkerLayout, calibrate
from demoplan.perception.camera import load_image, save_image
from demoplan.perception.pinhole import PinholeCamera, render_table
from demoplan.perception.synthetic import SyntheticBlock

MARKERS = {0: (0.0, 0.0), 1: (0.3, 0.0), 2: (0.3, 0.2), 3: (0.0, 0.2)}
LAYOUT = MarkerLayout("DICT_4X4_50", 0.04, {k: (x, y, 0.0) for k, (x, y) in MARKERS.items()})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--views", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    settings = {
        (True, True): "intrinsics, --side",
        (True, False): "intrinsics, no --side",
        (False, True): "estimated f, --side",
        (False, False): "estimated f, no --side",
    }
    errors: dict[str, list[float]] = {name: [] for name in settings.values()}
    times: dict[str, list[float]] = {name: [] for name in settings.values()}
    missed = dict.fromkeys(settings.values(), 0)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "view.png"
        for _ in range(args.views):
            tilt, heading = float(rng.uniform(0, 30)), float(rng.uniform(-180, 180))
            distance = float(rng.uniform(0.5, 0.7))
            blocks = [
                SyntheticBlock(
                    colour,
                    0.06 + 0.09 * i + float(rng.uniform(-0.01, 0.01)),
                    float(rng.uniform(0.06, 0.14)),
                    float(rng.uniform(-45, 45)),
                    0.04,
                )
                for i, colour in enumerate(("red", "blue", "green"))
            ]
            view = PinholeCamera.looking_at(
                (0.15, 0.1), tilt=tilt, heading=heading, distance=distance, focal=560.0
            )
            save_image(render_table(view, blocks, MARKERS, marker_side=0.04, rng=rng), path)
            for (given, side), name in settings.items():
                if not given and tilt < 10:
                    continue
                start = time.perf_counter()
                calibration = calibrate(
                    load_image(path), LAYOUT, intrinsics=Intrinsics(view.matrix) if given else None
                )
                try:
                    found = perceive_calibrated(path, calibration, side=0.04 if side else None)
                except InputError:
                    found = {}
                times[name].append(time.perf_counter() - start)
                for block in blocks:
                    seen = found.get(block.colour)
                    if seen is None:
                        missed[name] += 1
                    else:
                        errors[name].append(1000 * math.dist((seen.x, seen.y), (block.x, block.y)))
    print(
        "| setting | cubes found | error mm (median / p95 / max) | time per photo (median / p95) |"
    )
    print("|---|---|---|---|")
    for name in settings.values():
        e, t = np.array(errors[name]), np.array(times[name])
        print(
            f"| {name} | {len(e)}/{len(e) + missed[name]} | "
            f"{np.median(e):.2f} / {np.percentile(e, 95):.2f} / {e.max():.2f} | "
            f"{1000 * np.median(t):.0f} / {1000 * np.percentile(t, 95):.0f} ms |"
        )


if __name__ == "__main__":
    main()
