"""Benchmark: demonstrations perceived from camera frames (``perceive --sequence``).

What it measures
----------------
1. **Experiment 2** — the two pyramid demonstrations of
   ``examples/blocks/demonstrations.json`` filmed by
   :func:`demoplan.perception.filmed.render_demonstration` (500 × 400 px,
   1 px = 1 mm, 48 frames each) and perceived by
   :func:`demoplan.perception.sequence.demonstration_from_frames` with the
   blocks' side given: seconds per demonstration (the frames in memory; the
   rendering not counted) and each step's error against the file.
2. **Generated demonstrations** — ``--demos`` of
   :func:`demoplan.perception.filmed.random_demonstration` (demonstration
   ``i``: seed ``i``, 2–5 blocks and 1–4 moves drawn from ``default_rng(i +
   1000)``; half the moves stack a block on another), filmed at 420 × 320 px
   with 3 frames per stretch of a move: the share of demonstrations whose
   steps come back with the right objects in the right order on the right
   level (z within 2 mm), and the position (mm) and yaw (°, mod 90)
   errors of their steps: median, 95th percentile, worst.

    python benchmarks/sequence.py            # 60 generated demonstrations
    python benchmarks/sequence.py --demos 10
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.model import Demonstration
from demoplan.perception.camera import Camera
from demoplan.perception.filmed import FilmSettings, random_demonstration, render_demonstration
from demoplan.perception.sequence import Frame, demonstration_from_frames, top_view_detector

ROOT = Path(__file__).resolve().parent.parent
SIDE = 0.04


def _perceive(frames: list[np.ndarray], camera: Camera, name: str) -> tuple[Demonstration, float]:
    started = time.perf_counter()
    demo = demonstration_from_frames(
        (Frame(str(i), f) for i, f in enumerate(frames)),
        top_view_detector(camera, SIDE),
        name=name,
        side=SIDE,
    )
    return demo, time.perf_counter() - started


def _errors(truth: Demonstration, seen: Demonstration) -> tuple[list[float], list[float]]:
    positions, yaws = [], []
    for a, b in zip(truth.steps, seen.steps, strict=True):
        positions.append(1000 * math.dist(a.pose.position[:2], b.pose.position[:2]))
        ra, rb = a.pose.rpy, b.pose.rpy
        assert ra is not None and rb is not None
        yaws.append(abs((ra[2] - rb[2] + 45.0) % 90.0 - 45.0))
    return positions, yaws


def _stats(values: list[float], digits: int) -> str:
    if not values:
        return "—"
    median, p95 = np.median(values), np.percentile(values, 95)
    return f"{median:.{digits}f} / {p95:.{digits}f} / {max(values):.{digits}f}"


def experiment_2() -> None:
    camera = Camera(1000.0, (0.0, -0.15))
    for k, truth in enumerate(load_demonstrations([ROOT / "examples/blocks/demonstrations.json"])):
        frames = render_demonstration(truth, camera, rng=k)
        seen, seconds = _perceive(frames, camera, truth.name)
        positions, yaws = _errors(truth, seen)
        print(
            f"{truth.name}: {len(frames)} frames in {seconds:.2f} s "
            f"({1000 * seconds / len(frames):.0f} ms a frame); step errors "
            f"{', '.join(f'{p:.2f} mm {y:.2f}°' for p, y in zip(positions, yaws, strict=True))}"
        )


def generated(count: int) -> None:
    camera = Camera(1000.0, (0.0, 0.0))
    film = FilmSettings(width=420, height=320, move_frames=3)
    right, positions, yaws, seconds, frames_seen = 0, [], [], 0.0, 0
    for seed in range(count):
        draw = np.random.default_rng(seed + 1000)
        truth = random_demonstration(seed, int(draw.integers(2, 6)), int(draw.integers(1, 5)))
        frames = render_demonstration(truth, camera, film, rng=seed)
        seen, took = _perceive(frames, camera, truth.name)
        seconds, frames_seen = seconds + took, frames_seen + len(frames)
        same = [s.object for s in seen.steps] == [s.object for s in truth.steps] and all(
            abs(a.pose.position[2] - b.pose.position[2]) < 0.002
            for a, b in zip(truth.steps, seen.steps, strict=True)
        )
        if same:
            right += 1
            p, y = _errors(truth, seen)
            positions += p
            yaws += y
        else:
            print(f"demonstration {seed}: steps differ")
    print(
        "| demonstrations | steps right | position mm (median / p95 / max) "
        "| yaw ° (median / p95 / max) | ms a frame |"
    )
    print("|---|---|---|---|---|")
    print(
        f"| {count} | {right}/{count} | {_stats(positions, 2)} | {_stats(yaws, 2)} "
        f"| {1000 * seconds / max(frames_seen, 1):.0f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--demos", type=int, default=60)
    args = parser.parse_args()
    experiment_2()
    generated(args.demos)


if __name__ == "__main__":
    main()
