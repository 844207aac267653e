"""Render the figures of "Method" in docs/perception.md: one per stage of the
block detector, on a photograph-like render and on a real photograph of the
development set.

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
mask) and ``perception-6-overlay.png`` (what ``perceive --plot`` draws); then
the same stages as ``perception-real-1-input.png`` … ``perception-real-6-overlay.png``
on ``tests/data/photos/mrhan_phone.png`` (a phone's photograph, 30–35° from
straight down: six cubes showing large side faces, a pen, markers, a robot; MIT,
Copyright (c) 2023 Ziqi Han — tests/data/photos/NOTICE.md), read as
``demoplan perceive mrhan_phone.png --px-per-m 2100 --origin 0 0 --side 0.038``
reads it. The PNGs are stored with 256 colours (small files).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
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
    _shrink,
    detect_blocks,
)
from demoplan.perception.camera import Camera, load_image
from demoplan.perception.colours import ColourRegion, _distinctness, colour_regions
from demoplan.perception.hough import (
    S_BIN,
    SIDE_STEP,
    THETA_BIN,
    XY_BIN,
    edge_pixels,
    hough_squares,
)
from demoplan.perception.image_measures import ImageMeasures
from demoplan.perception.opencv import cv2
from demoplan.perception.overlay import Drawn, draw_overlay, top_view_to_image
from demoplan.perception.photos import PhotoRig, render_photo, top_camera
from demoplan.perception.sizes import SIDE_TOLERANCE
from demoplan.perception.synthetic import COLOURS, SyntheticBlock

HERE = Path(__file__).resolve().parent
SIDE = 0.04
RIG = PhotoRig(width=640, height_px=400, focal=1000.0, nadir=(0.3, 0.2), nadir_px=(312.5, 625 / 3))
"""The camera 1 m above (0.3, 0.2); the plane of the tops (4 cm up) at 1000 / 0.96 px/m
with the image's bottom-left corner at (0, 0): ``--px-per-m 1041.667 --origin 0 0``."""
REAL_PHOTO = HERE.parent.parent / "tests" / "data" / "photos" / "mrhan_phone.png"
REAL_SIDE = 0.038
"""mrhan_phone's cubes (its label: 38 mm, about 2100 px/m near them)."""


@dataclass(frozen=True)
class Subject:
    """A photograph the stages are shown on: the figures' file prefix, the camera and
    the settings ``demoplan perceive`` reads it with, the colour of the region the
    Hough and fit figures show, and the part of the photograph they show (rows,
    columns; the whole when None)."""

    prefix: str
    image: np.ndarray
    camera: Camera
    settings: PerceptionSettings
    focus: str
    crop: tuple[slice, slice] | None = None
    photo_scale: float = 1.0
    """The input and the overlay are stored at this scale (smaller files)."""

    @property
    def min_area(self) -> float:
        return 0.3 * (self.settings.min_side * self.camera.px_per_m) ** 2

    def shown(self, picture: np.ndarray) -> np.ndarray:
        return picture if self.crop is None else picture[self.crop]

    def figsize(self, width: float) -> tuple[float, float]:
        rows, cols = self.shown(self.image).shape[:2]
        return width, width * rows / cols


def settings_for(side: float) -> PerceptionSettings:
    """As ``--side``: the sizes within the tolerance of the side given."""
    return PerceptionSettings(
        min_side=(1 - SIDE_TOLERANCE) * side, max_side=(1 + SIDE_TOLERANCE) * side
    )


def rendered() -> Subject:
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
    return Subject("perception", image, top_camera(RIG, SIDE), settings_for(SIDE), "blue")


def photographed() -> Subject:
    """mrhan_phone of the development set: the figures of the whole photograph show
    its right two thirds, where the cubes are."""
    return Subject(
        "perception-real",
        load_image(REAL_PHOTO),
        Camera(2100.0, (0.0, 0.0)),
        settings_for(REAL_SIDE),
        "blue",
        crop=(slice(200, 1500), slice(420, 1200)),
        photo_scale=0.6,
    )


def save_photo(image: np.ndarray, name: str, scale: float = 1.0) -> None:
    """``image`` as a PNG of 256 colours (an octree palette, dithered), resized by
    ``scale``."""
    picture = Image.fromarray(image)
    if scale != 1.0:
        size = (round(picture.width * scale), round(picture.height * scale))
        picture = picture.resize(size, Image.Resampling.LANCZOS)
    palette = picture.quantize(256, method=Image.Quantize.FASTOCTREE)
    palette.save(HERE / name, optimize=True)


def save_figure(figure: plt.Figure, name: str) -> None:
    figure.savefig(HERE / name, dpi=90, bbox_inches="tight")
    plt.close(figure)
    with Image.open(HERE / name) as drawn:
        save_photo(np.asarray(drawn.convert("RGB")), name)


def foreground_figure(subject: Subject) -> None:
    distinct, _, threshold, _ = _distinctness(subject.image)
    width, height = subject.figsize(5.0)
    figure, (left, right) = plt.subplots(1, 2, figsize=(2 * width, height))
    shown = left.imshow(subject.shown(distinct), cmap="magma", vmin=0, vmax=4 * threshold)
    figure.colorbar(shown, ax=left, fraction=0.03, label="a*b* distance from the table")
    left.set_title("chroma: distance from the table's a*b*", fontsize=9)
    right.imshow(subject.shown(distinct > threshold / 2), cmap="gray")
    title = f"foreground: distance > {threshold / 2:.0f} (half of max(12, 6σ))"
    right.set_title(title, fontsize=9)
    for axes in (left, right):
        axes.set_axis_off()
    save_figure(figure, f"{subject.prefix}-2-foreground.png")


def regions(subject: Subject) -> list[ColourRegion]:
    found, _ = colour_regions(subject.image, min_area=subject.min_area)
    return found


def regions_figure(subject: Subject) -> None:
    canvas = np.full(subject.image.shape, 255.0)
    named = regions(subject)
    for region in named:
        row, col = region.offset
        rows, cols = region.alpha.shape
        patch = canvas[row : row + rows, col : col + cols]
        alpha = region.alpha[..., None]
        patch[:] = patch * (1 - alpha) + np.array(region.rgb) * alpha
    figure, axes = plt.subplots(figsize=subject.figsize(6.4))
    axes.imshow(subject.shown(canvas.astype(np.uint8)))
    top, left = (0, 0) if subject.crop is None else (subject.crop[0].start, subject.crop[1].start)
    bottom, right = subject.shown(canvas).shape[:2]
    for region in named:
        row, col = region.offset
        if 0 <= row - top < bottom and 0 <= col - left < right:
            axes.annotate(region.colour, (col - left, row - top), fontsize=7, va="bottom")
    title = "colour regions: soft masks α, each in its class colour"
    axes.set_title(title, fontsize=9)
    axes.set_axis_off()
    save_figure(figure, f"{subject.prefix}-3-regions.png")


def focus_region(subject: Subject) -> ColourRegion:
    """The largest region of the subject's focus colour."""
    return max(
        (r for r in regions(subject) if r.colour == subject.focus),
        key=lambda r: float(r.alpha.sum()),
    )


def hough_factor(subject: Subject) -> int:
    """The whole factor the masks are shrunk by for the vote (blocks.HOUGH_SIDE_PX)."""
    return max(1, int(subject.settings.min_side * subject.camera.px_per_m // HOUGH_SIDE_PX))


def hough_figure(subject: Subject) -> None:
    """The focus region: edge pixels, and the accumulator at the side the strongest
    peak has (the vote of demoplan.perception.hough, redone here for one side to
    show it), best θ per centre bin, on the mask shrunk as the detector shrinks it."""
    factor = hough_factor(subject)
    alpha = _shrink(focus_region(subject).alpha, factor)
    px = subject.camera.px_per_m / factor
    peaks = hough_squares(alpha, (subject.settings.min_side * px, subject.settings.max_side * px))
    u, v, nu, nv, g = edge_pixels(alpha)
    s = peaks[0].side
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
    shrunk = f", shrunk {factor}×" if factor > 1 else ""
    left.set_title(
        f"the {subject.focus} region's soft mask{shrunk},\nedge pixels and normals (colour: θ)",
        fontsize=9,
    )
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
    save_figure(figure, f"{subject.prefix}-4-hough.png")


def square(cu: float, cv: float, theta: float, side: float) -> np.ndarray:
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    h = side / 2
    return np.array(
        [(cu + c * a - s * b, cv + s * a + c * b) for a, b in ((-h, -h), (h, -h), (h, h), (-h, h))]
    )


def fit_figure(subject: Subject) -> None:
    """The Hough start (thick, orange, scaled back from the shrunk mask) and the
    fitted square (thin, blue) on the focus region's soft mask."""
    region = focus_region(subject)
    alpha = region.alpha
    height, width = alpha.shape
    factor = hough_factor(subject)
    px = subject.camera.px_per_m / factor
    sides = (subject.settings.min_side * px, subject.settings.max_side * px)
    start = hough_squares(_shrink(alpha, factor), sides)[0]
    camera = subject.camera
    row0, col0 = region.offset
    image_rows = subject.image.shape[0]

    def in_crop(block_x: float, block_y: float) -> tuple[float, float]:
        u, v = camera.to_pixels(block_x, block_y)
        return u - col0, v - (image_rows - row0 - height)

    found = next(
        b
        for b in detect_blocks(subject.image, camera, subject.settings)
        if b.colour == subject.focus
        and 0 <= in_crop(b.x, b.y)[0] < width
        and 0 <= in_crop(b.x, b.y)[1] < height
    )
    u, v = in_crop(found.x, found.y)
    figure, axes = plt.subplots(figsize=(4.5, 4.2))
    axes.imshow(alpha, cmap="gray", extent=(0, width, 0, height))
    axes.add_patch(
        Polygon(
            square(start.u * factor, start.v * factor, start.theta, start.side * factor),
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
    save_figure(figure, f"{subject.prefix}-5-fit.png")


def overlay_figure(subject: Subject) -> list[Rejection]:
    rejected: list[Rejection] = []
    measures = ImageMeasures(subject.image)
    found = detect_blocks(subject.image, subject.camera, subject.settings, rejected, measures)
    drawn = [Drawn(b.name, b.x, b.y, b.yaw, b.side) for b in found]
    to_image = top_view_to_image(subject.camera, subject.image.shape[0])
    overlay = draw_overlay(subject.image, drawn, [(r, 0.0) for r in rejected], to_image)
    save_photo(subject.shown(overlay), f"{subject.prefix}-6-overlay.png", subject.photo_scale)
    return rejected


def figures(subject: Subject) -> None:
    save_photo(subject.shown(subject.image), f"{subject.prefix}-1-input.png", subject.photo_scale)
    foreground_figure(subject)
    regions_figure(subject)
    hough_figure(subject)
    fit_figure(subject)
    rejected = overlay_figure(subject)
    print(f"{subject.prefix} rejected:", ", ".join(f"{r.reason} ({r.detail})" for r in rejected))


def main() -> None:
    for subject in (rendered(), photographed()):
        figures(subject)
    for name in sorted(HERE.glob("perception-*.png")):
        print(f"wrote {name.relative_to(HERE.parent.parent)} ({name.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
