"""Where block perception's square search spends its time: every search of a region.

:func:`demoplan.perception.blocks.detect_blocks` searches each colour region for a
square again and again (``_next_square``): a Hough vote, then fits from its
strongest starts until one is a block. This script runs it on

- the five development photographs (``tests/data/photos``, their label's
  ``px_per_m``, the default sizes),
- ``--seeds`` draws of every generated family
  (:mod:`demoplan.perception.photo_families`), each with and without ``--side``,

and logs every search (the region's first, or one of what is left after a block was
cut out; its area in smallest-block areas; the vote's CPU) and every fit (the start's
rank, why it is no block or ``block``, its CPU), the functions timed by wrapping
them in this process (the results are the detector's own). It prints, for the
photographs and the families apart: the CPU of the searches that find a block and
of those that find none (first searches and later ones), the rank of the start that
was a block, and what capping the starts tried per search would save and lose
(counted on the log: a search whose block came later than the cap loses it).

How to run, from the repository root::

    PYTHONPATH=src python benchmarks/perception_searches.py [--seeds 2] [--out log.json]
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from demoplan.perception import blocks
from demoplan.perception.camera import Camera
from demoplan.perception.labelled import load_labelled
from demoplan.perception.photo_families import FAMILIES, family_case
from demoplan.perception.sizes import SIDE_TOLERANCE

ROOT = Path(__file__).resolve().parents[1]
PHOTOS = ROOT / "tests" / "data" / "photos"


class SearchLog:
    """The searches of one image, filled by the wrapped functions."""

    def __init__(self) -> None:
        self.searches: list[dict[str, Any]] = []
        self._seen: Counter[int] = Counter()
        self._fit_start: float | None = None

    def wrap(self) -> None:
        """Wrap ``blocks``' search functions to log into this (for the whole process)."""
        next_square, hough_starts = blocks._next_square, blocks._hough_starts
        fit_from, why_no_block = blocks._fit_from, blocks._why_no_block

        def logged_next_square(search: Any, region: Any, alpha: np.ndarray, where: str) -> Any:
            attempt = self._seen[id(region)]
            self._seen[id(region)] += 1
            area = float(np.count_nonzero(alpha > 0.5)) / search.side_px[0] ** 2
            self.searches.append({"attempt": attempt, "area": area, "vote": 0.0, "fits": []})
            return next_square(search, region, alpha, where)

        def logged_hough_starts(*args: Any) -> Any:
            start = time.process_time()
            found = hough_starts(*args)
            self.searches[-1]["vote"] += time.process_time() - start
            return found

        def logged_fit_from(*args: Any) -> Any:
            self._fit_start = time.process_time()
            return fit_from(*args)

        def logged_why(*args: Any) -> Any:
            why = why_no_block(*args)
            if self._fit_start is None:  # the tops behind an occluder judged: no search's
                return why
            fits = self.searches[-1]["fits"]
            spent = time.process_time() - self._fit_start
            self._fit_start = None
            outcome = "block" if why is None else why[0]
            fits.append({"rank": len(fits), "why": outcome, "cpu": spent})
            return why

        wrapped = {
            "_next_square": logged_next_square,
            "_hough_starts": logged_hough_starts,
            "_fit_from": logged_fit_from,
            "_why_no_block": logged_why,
        }
        for name, function in wrapped.items():
            setattr(blocks, name, function)

    def run(self, image: np.ndarray, camera: Camera, settings: blocks.PerceptionSettings) -> float:
        """The CPU of one ``detect_blocks`` call, its searches logged afresh."""
        self.searches, self._seen = [], Counter()
        start = time.process_time()
        blocks.detect_blocks(image, camera, settings, rejected=[])
        return time.process_time() - start


def _cases(seeds: int) -> Iterator[tuple[str, np.ndarray, Camera, blocks.PerceptionSettings]]:
    for label in sorted(PHOTOS.glob("*.json")):
        photo = load_labelled(label)
        with Image.open(photo.image) as opened:
            image = np.asarray(opened.convert("RGB"))
        camera = Camera(photo.px_per_m, (0.0, 0.0))
        yield f"photo:{photo.name}", image, camera, blocks.PerceptionSettings()
    for family in sorted(FAMILIES):
        for seed in range(seeds):
            case = family_case(family, seed)
            side = case.label.side_m[0]
            camera = Camera(case.label.px_per_m, (0.0, 0.0))
            for given in (False, True):
                settings = blocks.PerceptionSettings()
                if given:
                    low, high = (1 - SIDE_TOLERANCE) * side, (1 + SIDE_TOLERANCE) * side
                    settings = replace(settings, min_side=low, max_side=high)
                name = f"family:{case.name}{' --side' if given else ''}"
                yield name, case.image, camera, settings


def _summary(title: str, runs: list[dict[str, Any]]) -> None:
    cpu = sum(run["cpu"] for run in runs)
    searches = [search for run in runs for search in run["searches"]]
    print(f"{title}: {len(runs)} images, {cpu:.2f} s CPU in detect_blocks")
    for first in (True, False):
        for with_block in (True, False):
            group = [
                s
                for s in searches
                if (s["attempt"] == 0) == first
                and bool(s["fits"] and s["fits"][-1]["why"] == "block") == with_block
            ]
            spent = sum(s["vote"] + sum(f["cpu"] for f in s["fits"]) for s in group)
            votes = sum(s["vote"] for s in group)
            which = "first searches of a region" if first else "searches of what is left"
            print(
                f"  {which}, {'a block found' if with_block else 'no block':>13}: {len(group):4} "
                f"searches, {spent:6.2f} s ({spent / cpu:4.0%}; the votes {votes:.2f} s), "
                f"{sum(len(s['fits']) for s in group)} fits"
            )
    found = [
        s["fits"][-1]["rank"] for s in searches if s["fits"] and s["fits"][-1]["why"] == "block"
    ]
    ranks = Counter(found)
    print(f"  rank of the start that was a block: {dict(sorted(ranks.items()))}")
    reasons: Counter[str] = Counter()
    reason_cpu: Counter[str] = Counter()
    for search in searches:
        for fit in search["fits"]:
            reasons[fit["why"]] += 1
            reason_cpu[fit["why"]] += fit["cpu"]
    outcomes = (f"{why} {n} ({reason_cpu[why]:.2f} s)" for why, n in reasons.most_common())
    print("  fits by outcome: " + ", ".join(outcomes))
    for cap in (2, 3, 4, 6):
        saved = sum(f["cpu"] for s in searches for f in s["fits"][cap:])
        lost = sum(1 for rank in found if rank >= cap)
        print(
            f"  at most {cap} starts a search: {saved:.2f} s of fits saved ({saved / cpu:.0%}), "
            f"{lost} searches lose their block"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=2, help="draws of every family (seeds from 0)")
    parser.add_argument("--out", type=Path, help="also write the log to this JSON file")
    arguments = parser.parse_args()
    log = SearchLog()
    log.wrap()
    runs: dict[str, dict[str, Any]] = {}
    for name, image, camera, settings in _cases(arguments.seeds):
        cpu = log.run(image, camera, settings)
        runs[name] = {"cpu": cpu, "searches": log.searches}
    if arguments.out is not None:
        arguments.out.write_text(json.dumps(runs, indent=0))
    _summary("photographs", [run for name, run in runs.items() if name.startswith("photo:")])
    families = [run for name, run in runs.items() if name.startswith("family:")]
    if families:
        _summary(f"families, seeds 0-{arguments.seeds - 1}, with and without --side", families)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
