"""Synthetic top-view images of blocks, for tests and benchmarks.

Squares are rendered by supersampling (``supersample``² samples per pixel, so
edges are anti-aliased as a camera's are; only the pixels a block's edge
crosses are sampled, the others are wholly in or out), then lit by a smooth brightness
gradient across the table (``shading``), each block a little brighter or
darker than the next, and Gaussian sensor noise (``noise``, grey levels) is
added. The ground truth is exact: the blocks as given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.perception.camera import Camera

__all__ = ["COLOURS", "SyntheticBlock", "random_blocks", "render_blocks", "touching_pair"]

COLOURS: dict[str, tuple[int, int, int]] = {
    "red": (200, 40, 40),
    "green": (50, 150, 60),
    "blue": (40, 80, 190),
    "yellow": (225, 190, 40),
    "wood": (180, 135, 90),
}
TABLE = (226, 222, 208)


@dataclass(frozen=True, slots=True)
class SyntheticBlock:
    """A square block seen from above: centre (m), yaw (deg), side (m), colour name."""

    colour: str
    x: float
    y: float
    yaw: float
    side: float


def render_blocks(
    blocks: Sequence[SyntheticBlock],
    camera: Camera,
    width: int = 500,
    height: int = 400,
    *,
    noise: float = 3.0,
    shading: float = 0.15,
    supersample: int = 4,
    rng: np.random.Generator | int | None = 0,
    background: tuple[int, int, int] = TABLE,
) -> np.ndarray:
    """An RGB ``uint8`` image (height × width × 3) of ``blocks`` on the table."""
    generator = np.random.default_rng(rng)
    image = np.empty((height, width, 3), dtype=float)
    image[:] = background
    n = supersample
    offsets = (np.arange(n) + 0.5) / n
    for block in blocks:
        u, v = camera.to_pixels(block.x, block.y)
        half = block.side * camera.px_per_m / 2
        reach = half * math.sqrt(2) + 2
        c0, c1 = max(0, int(u - reach)), min(width, int(u + reach) + 1)
        v0, v1 = max(0, int(v - reach)), min(height, int(v + reach) + 1)
        if c0 >= c1 or v0 >= v1:
            continue
        coverage = block_coverage(u, v, half, math.radians(block.yaw), (c0, c1, v0, v1), offsets)
        rows = slice(height - v1, height - v0)  # image rows run down
        coverage = coverage[::-1]
        tint = np.asarray(COLOURS[block.colour], dtype=float) * generator.uniform(0.9, 1.1)
        patch = image[rows, c0:c1]
        image[rows, c0:c1] = patch * (1 - coverage[..., None]) + tint * coverage[..., None]
    if shading:
        ramp = 1.0 - shading * (
            np.linspace(0, 1, width)[None, :] * 0.6 + np.linspace(0, 1, height)[:, None] * 0.4
        )
        image *= ramp[..., None]
    if noise:
        image += generator.normal(0.0, noise, image.shape)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


_PIXEL_REACH = 0.75
"""How far (px) a sample of a pixel may lie from its centre along either of a
block's axes: under half the pixel's diagonal (√2/2 ≈ 0.707), with room for
rounding."""


def block_coverage(
    u: float,
    v: float,
    half: float,
    yaw: float,
    box: tuple[int, int, int, int],
    offsets: np.ndarray,
) -> np.ndarray:
    """The fraction of each pixel of ``box`` (columns c0–c1, rows v0–v1, v up)
    inside the square of half side ``half`` (px) centred at (``u``, ``v``) and
    turned by ``yaw`` (rad): the share of its ``len(offsets)``² samples inside.
    A pixel whose centre lies deeper inside (or farther outside) than any of its
    samples can reach is wholly in (or out); only the pixels along the edges
    are sampled, with the very numbers sampling every pixel would give."""
    c0, c1, v0, v1 = box
    cos, sin = math.cos(yaw), math.sin(yaw)
    cu, cv = np.meshgrid(np.arange(c0, c1) + 0.5, np.arange(v0, v1) + 0.5)
    along = np.abs(cos * (cu - u) + sin * (cv - v))
    across = np.abs(-sin * (cu - u) + cos * (cv - v))
    inside = (along <= half - _PIXEL_REACH) & (across <= half - _PIXEL_REACH)
    outside = (along > half + _PIXEL_REACH) | (across > half + _PIXEL_REACH)
    coverage: np.ndarray = inside.astype(float)
    edge_rows, edge_columns = np.nonzero(~inside & ~outside)
    # each edge pixel's samples (v up): rows of the pixel's n × n grid
    su = (c0 + edge_columns)[:, None, None] + offsets[None, None, :]
    sv = (v0 + edge_rows)[:, None, None] + offsets[None, :, None]
    du, dv = su - u, sv - v
    qu = cos * du + sin * dv
    qv = -sin * du + cos * dv
    sampled = (np.abs(qu) <= half) & (np.abs(qv) <= half)
    coverage[edge_rows, edge_columns] = sampled.mean(axis=(1, 2))
    return coverage


def random_blocks(
    count: int,
    camera: Camera,
    width: int,
    height: int,
    rng: np.random.Generator,
    *,
    sides: tuple[float, float] = (0.03, 0.05),
    gap: float = 0.01,
    colours: Sequence[str] = tuple(COLOURS),
) -> list[SyntheticBlock]:
    """``count`` blocks of distinct colours at random poses, apart by ``gap`` (m)."""
    placed: list[SyntheticBlock] = []
    names = list(rng.permutation(list(colours)))[:count]
    margin = sides[1]
    x0, y0 = camera.to_world(0, 0)
    x1, y1 = camera.to_world(width, height)
    for colour in names:
        for _ in range(1000):
            side = float(rng.uniform(*sides))
            x = float(rng.uniform(x0 + margin, x1 - margin))
            y = float(rng.uniform(y0 + margin, y1 - margin))
            radius = side / math.sqrt(2)
            if all(
                math.dist((x, y), (b.x, b.y)) > radius + b.side / math.sqrt(2) + gap for b in placed
            ):
                placed.append(SyntheticBlock(str(colour), x, y, float(rng.uniform(-45, 45)), side))
                break
    return placed


def touching_pair(
    camera: Camera, width: int, height: int, rng: np.random.Generator, colours: tuple[str, str]
) -> list[SyntheticBlock]:
    """Two blocks side by side, faces touching (the paper's failure case)."""
    side = float(rng.uniform(0.035, 0.045))
    yaw = float(rng.uniform(-45, 45))
    x0, y0 = camera.to_world(width / 2, height / 2)
    x = x0 + float(rng.uniform(-0.05, 0.05))
    y = y0 + float(rng.uniform(-0.05, 0.05))
    along = (math.cos(math.radians(yaw)) * side / 2, math.sin(math.radians(yaw)) * side / 2)
    slide = float(rng.uniform(-0.3, 0.3)) * side  # offset along the shared face
    across = (-math.sin(math.radians(yaw)) * slide, math.cos(math.radians(yaw)) * slide)
    return [
        SyntheticBlock(colours[0], x - along[0], y - along[1], yaw, side),
        SyntheticBlock(colours[1], x + along[0] + across[0], y + along[1] + across[1], yaw, side),
    ]
