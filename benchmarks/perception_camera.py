"""Block perception on the real photographs under another camera's exposure, white
balance, tone curve, noise, compression, resolution, focus and orientation.

Each labelled photograph of the development set (``tests/data/photos``, but the
one without cubes) is varied by each of
:data:`demoplan.perception.camera_variations.VARIATIONS` (the image and its label
together) and perceived as ``demoplan perceive IMAGE --px-per-m S --origin 0 0``
reads it — without ``--side``, and with the label's side where the label names
one size — and scored as the development set is (found within 0.6 side, false).
A run *meets* when it exits 0, finds at least 90 % of the needed tops and has at
most one false block. The tables: per photograph × variation, found/needed, false,
exit and CPU seconds; per variation, how many runs meet.

How to run, from the repository root::

    PYTHONPATH=src python benchmarks/perception_camera.py
    PYTHONPATH=src python benchmarks/perception_camera.py --only none,gain0.75 \
        --photos mrhan_touching
    PYTHONPATH=src python benchmarks/perception_camera.py --out rows.json

About 90 runs, a few minutes of CPU.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from demoplan.perception.camera_variations import VARIATIONS, varied_photo
from demoplan.perception.labelled import load_labelled, perceive_labelled

ROOT = Path(__file__).resolve().parents[1]
PHOTOS = ROOT / "tests" / "data" / "photos"
DEFAULT_PHOTOS = ("armlab_mrhan4", "mrhan_phone", "mrhan_stacks", "mrhan_touching")


def meets(row: dict[str, Any]) -> bool:
    """The issue's thresholds: exit 0, ≥ 90 % of the needed tops, ≤ 1 false."""
    return bool(row["exit"] == 0 and row["found"] >= 0.9 * row["needed"] and row["false"] <= 1)


def run(photos: Sequence[str], variations: Sequence[str], folder: Path) -> list[dict[str, Any]]:
    """Every photograph × variation (× --side given, where the label names one size)."""
    rows = []
    for name in photos:
        photo = load_labelled(PHOTOS / f"{name}.json")
        sides = [None] + ([photo.side_m[0]] if len(photo.side_m) == 1 else [])
        for key in variations:
            varied = varied_photo(photo, VARIATIONS[key], folder, f"{name}_{key}")
            for side in sides:
                cpu = time.process_time()
                result = perceive_labelled(varied, side=side)
                cpu = time.process_time() - cpu
                score = result.score
                row = dict(
                    photo=name, variation=key, side=side is not None, found=score.found,
                    needed=score.needed, false=score.false, exit=result.exit_code,
                    cpu=round(cpu, 3),
                )  # fmt: skip
                row["meets"] = meets(row)
                rows.append(row)
    return rows


def runs_table(rows: Sequence[dict[str, Any]]) -> Table:
    table = Table(title="Development photographs under camera variations")
    for column in ("photo", "variation", "--side", "found", "false", "exit", "CPU s", "meets"):
        table.add_column(column, justify="left" if column in ("photo", "variation") else "right")
    for row in rows:
        table.add_row(
            row["photo"], row["variation"], "yes" if row["side"] else "no",
            f"{row['found']}/{row['needed']}", str(row["false"]), str(row["exit"]),
            f"{row['cpu']:.2f}", "ok" if row["meets"] else "FAIL",
        )  # fmt: skip
    return table


def variations_table(rows: Sequence[dict[str, Any]]) -> Table:
    table = Table(title="Runs meeting the thresholds, per variation")
    for column in ("variation", "runs meeting", "photographs meeting", "found", "false"):
        table.add_column(column, justify="left" if column == "variation" else "right")
    keys = list(dict.fromkeys(row["variation"] for row in rows))
    for key in keys + ["all"]:
        chosen = [r for r in rows if key in ("all", r["variation"])]
        photos = sorted({r["photo"] for r in chosen})
        whole = sum(all(r["meets"] for r in chosen if r["photo"] == p) for p in photos)
        table.add_row(
            key, f"{sum(r['meets'] for r in chosen)}/{len(chosen)}", f"{whole}/{len(photos)}",
            f"{sum(r['found'] for r in chosen)}/{sum(r['needed'] for r in chosen)}",
            str(sum(r["false"] for r in chosen)),
        )  # fmt: skip
    return table


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", default="", help="variations, comma-separated (default all)")
    parser.add_argument("--photos", default="", help="photographs, comma-separated")
    parser.add_argument("--out", type=Path, help="also save the rows to this JSON file")
    parser.add_argument("--keep", type=Path, help="write the varied images here (kept)")
    args = parser.parse_args(argv)
    args.variations = args.only.split(",") if args.only else list(VARIATIONS)
    unknown = [key for key in args.variations if key not in VARIATIONS]
    if unknown:
        parser.error(f"unknown variations {unknown}; known: {', '.join(VARIATIONS)}")
    args.photo_names = args.photos.split(",") if args.photos else list(DEFAULT_PHOTOS)
    return args


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    console = Console()
    with tempfile.TemporaryDirectory() as scratch:
        folder = args.keep or Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        rows = run(args.photo_names, args.variations, folder)
    console.print(runs_table(rows))
    console.print(variations_table(rows))
    cpus = sorted(r["cpu"] for r in rows)
    console.print(f"median CPU per run {cpus[len(cpus) // 2]:.2f} s over {len(cpus)} runs")
    if args.out:
        args.out.write_text(json.dumps(rows, indent=0) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
