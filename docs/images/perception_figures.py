"""Render the figures of "Method" in docs/perception.md: one per stage of the
block detector, on a photograph-like render.

From the repository root::

    python docs/images/perception_figures.py

renders four cubes (``demoplan.perception.photos.render_photo``: a gridded
board, markers, shadows, side faces, a highlight, blur, noise, JPEG) with two
things painted on that are no block — a small red patch and a green disc —
and writes next to this file ``perception-1-input.png`` (the photograph),
``perception-2-foreground.png`` (chroma distance from the table and the
foreground), ``perception-3-regions.png`` (the colour regions' soft masks),
``perception-4-hough.png`` (one region's edge pixels and its Hough
accumulator over the centre, best θ at the best side, with the peaks),
``perception-5-fit.png`` (the Hough start and the fitted square on that soft
mask) and ``perception-6-overlay.png`` (what ``perceive --plot`` draws). The
PNGs are stored with 256 colours (small files).
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Polygon
from PIL import Image

from demoplan.perception.blocks import (
    HOUGH_SIDE_PX,
    PerceptionSettings,
    Rejection,
    detect_blocks,
)
from demoplan.perception.colours import _distinctness, colour_regions
from demoplan.perception.hough import (
    S_BIN,
    SIDE_STEP,
    THETA_BIN,
    XY_BIN,
    edge_pixels,
    hough_squares,
)
from demoplan.perception.opencv import cv2
from demoplan.perception.overlay import Drawn, draw_overlay, top_view_to_image
from demoplan.perception.photos import PhotoRig, render_photo, top_camera
from demoplan.perception.synthetic import COLOURS, SyntheticBlock

HERE = Path(__file__).resolve().parent
SIDE = 0.04
RIG = PhotoRig(width=640, height_px=400, focal=1000.0, nadir=(0.3, 0.2), nadir_px=(312.5, 625 / 3))
"""The camera 1 m above (0.3, 0.2); the plane of the tops (4 cm up) at 1000 / 0.96 px/m
with the image's bottom-left corner at (0, 0): ``--px-per-m 1041.667 --origin 0 0``."""
SETTINGS = PerceptionSettings(min_side=0.85 * SIDE, max_side=1.15 * SIDE)  # as --side 0.04


def photograph() -> np.ndarray:
    """The render, with a red patch and a green disc painted on (no blocks)."""
    cubes = [
        SyntheticBlock("red", 0.09, 0.09, 15.0, SIDE),
        SyntheticBlock("blue", 0.22, 0.24, -30.0, SIDE),
        SyntheticBlock("yellow", 0.42, 0.27, 5.0, SIDE),
        SyntheticBlock("green", 0.37, 0.07, 35.0, SIDE),
    ]
    image = render_photo(cubes, RIG, rng=4)
    cv2.circle(image, (300, 330), 5, COLOURS["red"], -1, cv2.LINE_AA)
    cv2.circle(image, (160, 110), 22, COLOURS["green"], -1, cv2.LINE_AA)
    return image


def save_photo(image: np.ndarray, name: str) -> None:
    """``image`` as a PNG of 256 colours (an octree palette, dithered)."""
    palette = Image.fromarray(image).quantize(256, method=Image.Quantize.FASTOCTREE)
    palette.save(HERE / name, optimize=True)


def save_figure(figure: plt.Figure, name: str) -> None:
    figure.savefig(HERE / name, dpi=90, bbox_inches="tight")
    plt.close(figure)
    with Image.open(HERE / name) as drawn:
        save_photo(np.asarray(drawn.convert("RGB")), name)


def foreground_figure(image: np.ndarray) -> None:
    distinct, _, threshold, _ = _distinctness(image)
    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 3.4))
    shown = left.imshow(distinct, cmap="magma", vmin=0, vmax=4 * threshold)
    figure.colorbar(shown, ax=left, fraction=0.03, label="a*b* distance from the table")
    left.set_title("chroma: distance from the table's a*b*", fontsize=9)
    right.imshow(distinct > threshold / 2, cmap="gray")
    title = f"foreground: distance > {threshold / 2:.0f} (half of max(12, 6σ))"
    right.set_title(title, fontsize=9)
    for axes in (left, right):
        axes.set_axis_off()
    save_figure(figure, "perception-2-foreground.png")


def regions_figure(image: np.ndarray, camera_px: float) -> None:
    min_area = 0.3 * (SETTINGS.min_side * camera_px) ** 2
    regions, _ = colour_regions(image, min_area=min_area)
    canvas = np.full(image.shape, 255.0)
    for region in regions:
        row, col = region.offset
        rows, cols = region.alpha.shape
        patch = canvas[row : row + rows, col : col + cols]
        alpha = region.alpha[..., None]
        patch[:] = patch * (1 - alpha) + np.array(region.rgb) * alpha
    figure, axes = plt.subplots(figsize=(6.4, 4.0))
    axes.imshow(canvas.astype(np.uint8))
    for region in regions:
        row, col = region.offset
        axes.annotate(region.colour, (col, row), fontsize=7, va="bottom")
    title = "colour regions: soft masks α (top faces), each in its class colour"
    axes.set_title(title, fontsize=9)
    axes.set_axis_off()
    save_figure(figure, "perception-3-regions.png")


def hough_figure(image: np.ndarray, camera_px: float) -> None:
    """The blue cube's region: edge pixels, and the accumulator at the side the
    strongest peak has (the vote of demoplan.perception.hough, redone here for one
    side to show it), best θ per centre bin."""
    min_area = 0.3 * (SETTINGS.min_side * camera_px) ** 2
    regions, _ = colour_regions(image, min_area=min_area)
    region = next(r for r in regions if r.colour == "blue")
    factor = max(1, int(SETTINGS.min_side * camera_px // HOUGH_SIDE_PX))
    alpha = region.alpha
    sides = (SETTINGS.min_side * camera_px / factor, SETTINGS.max_side * camera_px / factor)
    peaks = hough_squares(alpha, sides)
    u, v, nu, nv, g = edge_pixels(alpha)
    best = peaks[0]
    s = best.side
    theta_bin = np.floor((np.degrees(np.arctan2(nv, nu)) % 90.0) / THETA_BIN + 0.5).astype(int) % 30
    height, width = alpha.shape
    n_x, n_y = math.ceil(width / XY_BIN), math.ceil(height / XY_BIN)
    steps = np.arange(-s / 2 + XY_BIN / 2, s / 2, XY_BIN)
    cu = (u[:, None] - s / 2 * nu[:, None] - steps[None, :] * nv[:, None]).ravel()
    cv = (v[:, None] - s / 2 * nv[:, None] + steps[None, :] * nu[:, None]).ravel()
    inside = (cu >= 0) & (cu < n_x * XY_BIN) & (cv >= 0) & (cv < n_y * XY_BIN)
    index = (np.repeat(theta_bin, len(steps)) * n_y + (cv / XY_BIN).astype(int)) * n_x
    index += (cu / XY_BIN).astype(int)
    votes = np.bincount(
        index[inside], weights=np.repeat(g, len(steps))[inside], minlength=30 * n_y * n_x
    ).reshape(30, n_y, n_x)
    figure, (left, right) = plt.subplots(1, 2, figsize=(9, 4))
    left.imshow(alpha, cmap="gray", extent=(0, width, 0, height))
    left.quiver(
        u, v, nu, nv, np.degrees(np.arctan2(nv, nu)) % 90, cmap="hsv", scale=40, width=0.004
    )
    left.set_title("the blue region's soft mask,\nedge pixels and normals (colour: θ)", fontsize=9)
    right.imshow(
        votes.max(axis=0)[::-1],
        cmap="viridis",
        extent=(0, n_x * XY_BIN, 0, n_y * XY_BIN),
        origin="lower",
    )
    for rank, peak in enumerate(peaks):
        right.plot(peak.u, peak.v, "r+" if rank else "w+", markersize=12, mew=2)
    right.set_title(
        f"votes at s = {s:.0f} px, best θ per centre bin\n(bins {THETA_BIN:.0f}° × "
        f"{XY_BIN:.0f} px, sides {S_BIN:.0f} px or {SIDE_STEP:.0%} apart; +: the peaks, "
        "white the strongest)",
        fontsize=9,
    )
    for axes in (left, right):
        axes.set_xlim(0, width)
        axes.set_ylim(0, height)
        axes.set_aspect("equal")
    save_figure(figure, "perception-4-hough.png")


def fit_figure(image: np.ndarray, camera_px: float) -> None:
    """The Hough start (thick, orange) and the fitted square (thin, blue) on the
    blue soft mask."""
    min_area = 0.3 * (SETTINGS.min_side * camera_px) ** 2
    regions, _ = colour_regions(image, min_area=min_area)
    region = next(r for r in regions if r.colour == "blue")
    alpha = region.alpha
    height, width = alpha.shape
    sides = (SETTINGS.min_side * camera_px, SETTINGS.max_side * camera_px)
    start = hough_squares(alpha, sides)[0]
    camera = top_camera(RIG, SIDE)
    (found,) = [b for b in detect_blocks(image, camera, SETTINGS) if b.colour == "blue"]
    row0, col0 = region.offset
    u, v = camera.to_pixels(found.x, found.y)
    u, v = u - col0, v - (image.shape[0] - row0 - height)

    def square(cu: float, cv: float, theta: float, side: float) -> np.ndarray:
        c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
        h = side / 2
        return np.array(
            [
                (cu + c * a - s * b, cv + s * a + c * b)
                for a, b in ((-h, -h), (h, -h), (h, h), (-h, h))
            ]
        )

    figure, axes = plt.subplots(figsize=(4.5, 4.2))
    axes.imshow(alpha, cmap="gray", extent=(0, width, 0, height))
    axes.add_patch(
        Polygon(
            square(start.u, start.v, start.theta, start.side),
            fill=False,
            ec="orange",
            ls="--",
            lw=1.5,
            label="Hough peak",
        )
    )
    side_px = found.side * camera.px_per_m
    axes.add_patch(
        Polygon(square(u, v, found.yaw, side_px), fill=False, ec="blue", lw=1.2, label="fitted")
    )
    axes.legend(loc="lower right", fontsize=7)
    axes.set_title(
        f"sub-pixel fit: θ {found.yaw:.1f}°, side {found.side * 1000:.1f} mm\n"
        f"coverage {found.coverage:.0%}, misfit {found.residual:.2f}",
        fontsize=9,
    )
    axes.set_xlim(0, width)
    axes.set_ylim(0, height)
    save_figure(figure, "perception-5-fit.png")


def main() -> None:
    image = photograph()
    camera = top_camera(RIG, SIDE)
    save_photo(image, "perception-1-input.png")
    foreground_figure(image)
    regions_figure(image, camera.px_per_m)
    hough_figure(image, camera.px_per_m)
    fit_figure(image, camera.px_per_m)
    rejected: list[Rejection] = []
    found = detect_blocks(image, camera, SETTINGS, rejected)
    drawn = [Drawn(b.name, b.x, b.y, b.yaw, b.side) for b in found]
    overlay = draw_overlay(
        image, drawn, [(r, 0.0) for r in rejected], top_view_to_image(camera, image.shape[0])
    )
    save_photo(overlay, "perception-6-overlay.png")
    for name in sorted(HERE.glob("perception-*.png")):
        print(f"wrote {name.relative_to(HERE.parent.parent)} ({name.stat().st_size // 1024} KB)")
    print("rejected:", ", ".join(f"{r.reason} ({r.detail})" for r in rejected))


if __name__ == "__main__":
    main()
