"""Identity check for speed-ups of block perception: the same detections and rejections.

A speed-up of :func:`demoplan.perception.blocks.detect_blocks` must not change any
result. ``dump`` runs it on

- the five development photographs (``tests/data/photos``, their label's
  ``px_per_m``, origin 0 0, the default sizes),
- the first ``--renders`` images of each of the perception benchmark's sets a, b
  and c (``benchmarks/perception.py``, the same seeds),
- ``--per-family`` draws of every generated family
  (:func:`demoplan.perception.photo_families.family_cases`, seeds from 0),

and writes every block (name, colour, x, y, yaw, side, RGB, coverage, misfit) and
every rejection (reason, detail, colour, outlines) to a JSON file; ``compare`` tells
whether two such files agree: strings exactly, numbers to ``--tolerance`` (1e-9:
metres, degrees, shares).

How to run, from the repository root (the code before a change in ``OLD/src``)::

    PYTHONPATH=OLD/src python benchmarks/perception_identity.py dump before.json
    PYTHONPATH=src python benchmarks/perception_identity.py dump after.json
    python benchmarks/perception_identity.py compare before.json after.json

Defaults: 15 renders per set and 5 draws per family (100 images, about half a
minute of CPU).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from demoplan.perception.blocks import Rejection, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.labelled import load_labelled

ROOT = Path(__file__).resolve().parents[1]
PHOTOS = ROOT / "tests" / "data" / "photos"
DIFFERENCES_SHOWN = 40


def _cases(renders: int, per_family: int) -> Iterator[tuple[str, np.ndarray, Camera]]:
    """(name, RGB image, camera) of every image checked."""
    for label in sorted(PHOTOS.glob("*.json")):
        photo = load_labelled(label)
        with Image.open(photo.image) as opened:
            image = np.asarray(opened.convert("RGB"))
        yield f"photo:{photo.name}", image, Camera(photo.px_per_m, (0.0, 0.0))
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import perception as benchmark  # benchmarks/perception.py: its sets' images

    for key in "abc":
        for index in range(renders):
            scene = benchmark.make_scene(key, benchmark.SEED_BASE[key] + index)
            yield f"set:{key}:{index}", scene.image, benchmark.CAMERA
    from demoplan.perception.photo_families import family_cases

    for case in family_cases(per_family=per_family):
        yield f"family:{case.name}", case.image, Camera(case.label.px_per_m, (0.0, 0.0))


def _rejection(rejection: Rejection) -> list[Any]:
    outlines = [[list(point) for point in outline] for outline in rejection.outlines]
    return [rejection.reason, rejection.detail, rejection.colour, outlines]


def dump(out: Path, renders: int, per_family: int) -> None:
    """Every image's blocks and rejections, as JSON, into ``out``."""
    results: dict[str, Any] = {}
    for name, image, camera in _cases(renders, per_family):
        rejected: list[Rejection] = []
        blocks = detect_blocks(image, camera, rejected=rejected)
        results[name] = {
            "blocks": [
                [b.name, b.colour, b.x, b.y, b.yaw, b.side, list(b.rgb), b.coverage, b.residual]
                for b in blocks
            ],
            "rejected": [_rejection(r) for r in rejected],
        }
        print(f"{name}: {len(blocks)} blocks, {len(rejected)} rejections", flush=True)
    out.write_text(json.dumps(results), encoding="utf-8")


def differences(a: Any, b: Any, where: str, tolerance: float) -> list[str]:
    """Where ``a`` and ``b`` (JSON values) differ: numbers by more than ``tolerance``."""
    if isinstance(a, bool) or isinstance(b, bool) or not isinstance(a, int | float):
        if isinstance(a, list) and isinstance(b, list):
            if len(a) != len(b):
                return [f"{where}: {len(a)} entries, then {len(b)}"]
            return [
                found
                for index, (x, y) in enumerate(zip(a, b, strict=True))
                for found in differences(x, y, f"{where}[{index}]", tolerance)
            ]
        if isinstance(a, dict) and isinstance(b, dict):
            return [
                found
                for key in sorted(set(a) | set(b))
                for found in differences(a.get(key), b.get(key), f"{where}.{key}", tolerance)
            ]
        return [] if a == b else [f"{where}: {a!r}, then {b!r}"]
    if not isinstance(b, int | float) or not math.isclose(a, b, rel_tol=0, abs_tol=tolerance):
        return [f"{where}: {a!r}, then {b!r}"]
    return []


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    dumping = commands.add_parser("dump", help="detect and write every result")
    dumping.add_argument("out", type=Path)
    dumping.add_argument("--renders", type=int, default=15, help="images per set a, b, c")
    dumping.add_argument("--per-family", type=int, default=5, help="draws per family")
    comparing = commands.add_parser("compare", help="compare two dumps")
    comparing.add_argument("before", type=Path)
    comparing.add_argument("after", type=Path)
    comparing.add_argument("--tolerance", type=float, default=1e-9)
    args = parser.parse_args()
    if args.command == "dump":
        dump(args.out, args.renders, args.per_family)
        return 0
    before, after = (json.loads(p.read_text(encoding="utf-8")) for p in (args.before, args.after))
    found = differences(before, after, "", args.tolerance)
    for line in found[:DIFFERENCES_SHOWN]:
        print(line)
    print(f"{len(before)} images: " + ("identical" if not found else f"{len(found)} differences"))
    return 0 if not found else 1


if __name__ == "__main__":
    raise SystemExit(main())
