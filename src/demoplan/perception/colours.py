"""Background, foreground and colour classes of a top-view image.

The table's colour under each pixel is a plane per channel fitted to the
image border (so a smooth brightness gradient is table, not object); a pixel
belongs to the foreground when it differs from the table by more than
``max(min_contrast, 6 σ)``, σ the sensor noise measured between neighbouring
border pixels (so a smooth brightness gradient is not taken for noise). Each
connected foreground region is split by colour: its confidently coloured
("core") pixels are named by the nearest plain colour in brightness-free
chromaticity (RGB divided by its largest channel, so shading does not change
it), each colour with enough core pixels becomes a class, and every pixel of
the region goes to the nearest class. For each class, a *soft mask* α ∈ [0, 1]
says how much of a pixel the object covers, from where the pixel's colour lies
between the table's and the class's (an edge pixel half covered is a half-mix):
that is what the sub-pixel fit works on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from demoplan.budget import check_time

__all__ = ["PALETTE", "ColourRegion", "colour_regions", "name_colour"]

MAX_CHROMA_DISTANCE = 0.3
"""A colour farther than this (in RGB / max RGB) from every plain colour has no name."""
_SPECIAL = {-2: "black", -3: "grey", -4: "block"}

PALETTE: dict[str, tuple[float, float, float]] = {
    # brightness-free chromaticity: RGB / max(RGB)
    "red": (1.0, 0.2, 0.2),
    "orange": (1.0, 0.55, 0.12),
    "wood": (1.0, 0.75, 0.5),
    "yellow": (1.0, 0.85, 0.18),
    "green": (0.3, 1.0, 0.35),
    "blue": (0.2, 0.42, 1.0),
    "purple": (0.7, 0.35, 1.0),
}


@dataclass(frozen=True, slots=True)
class ColourRegion:
    """One colour class within one connected foreground region.

    ``alpha`` is the soft mask on the crop ``rows × cols`` of the image
    (``offset`` = its top-left pixel); ``rgb`` the class's mean colour.
    """

    colour: str
    rgb: tuple[float, float, float]
    offset: tuple[int, int]
    alpha: np.ndarray


def name_colour(rgb: np.ndarray) -> str:
    """The plain colour name nearest to ``rgb`` (dark or grey: ``black`` / ``grey``;
    ``block`` when no plain colour is near: docs/formats.md then names blocks block1, block2…)."""
    label = int(_classify(np.asarray(rgb, dtype=float).reshape(1, 3))[0])
    return _palette()[0][label] if label >= 0 else _SPECIAL[label]


def _palette() -> tuple[list[str], np.ndarray]:
    return list(PALETTE), np.array(list(PALETTE.values()))


def _classify(pixels: np.ndarray) -> np.ndarray:
    """Palette index per pixel (N × 3 RGB); dark → -2, greyish → -3."""
    _, chroma = _palette()
    top = pixels.max(axis=1)
    normal = pixels / np.maximum(top, 1.0)[:, None]
    distance = np.linalg.norm(normal[:, None, :] - chroma[None, :, :], axis=2)
    labels: np.ndarray = np.argmin(distance, axis=1)
    labels[distance.min(axis=1) > MAX_CHROMA_DISTANCE] = -4  # no plain colour
    labels[normal.min(axis=1) > 0.82] = -3
    labels[top < 60] = -2
    return labels


def colour_regions(
    image: np.ndarray, *, min_area: float, min_contrast: float = 30.0
) -> tuple[list[ColourRegion], np.ndarray]:
    """The colour regions of ``image`` (H × W × 3) with at least ``min_area`` core
    pixels, and the table colour."""
    where = f" modelling the table under {image.shape[1]} × {image.shape[0]} pixels"
    rgb = image.astype(float)
    edges = [rgb[0], rgb[-1], rgb[:, 0], rgb[:, -1]]
    table = np.median(np.concatenate(edges), axis=0)
    check_time(where)  # a budget set by the caller (demoplan.budget), if any
    background = _table_model(rgb)
    check_time(where)
    # sensor noise from neighbouring border pixels (a smooth shading does not count)
    steps = np.abs(np.concatenate([np.diff(edge, axis=0) for edge in edges]))
    sigma = 1.4826 * float(np.median(steps)) / np.sqrt(2)
    threshold = max(min_contrast, 6 * sigma)
    distance = np.linalg.norm(rgb - background, axis=2)
    foreground = distance > threshold / 2
    check_time(where)
    labels, _ = ndimage.label(foreground, structure=np.ones((3, 3)))
    regions: list[ColourRegion] = []
    names, _ = _palette()
    for index, box in enumerate(ndimage.find_objects(labels), start=1):
        if box is None:
            continue
        rows = slice(max(0, box[0].start - 3), min(labels.shape[0], box[0].stop + 3))
        cols = slice(max(0, box[1].start - 3), min(labels.shape[1], box[1].stop + 3))
        member = labels[rows, cols] == index
        crop = rgb[rows, cols]
        ground = background[rows, cols]
        far = distance[rows, cols]
        # core: clearly foreground and two pixels in from the region's rim, where
        # anti-aliased pixels mix the table's colour into the object's
        core = ndimage.binary_erosion(member, iterations=2) & (far > threshold)
        if core.sum() < min_area:
            continue
        classes = _classify(crop[core])
        present = []
        for label in np.unique(classes):
            chosen = classes == label
            if chosen.sum() >= min_area:
                colour = names[label] if label >= 0 else _SPECIAL[int(label)]
                change = (crop[core][chosen] - ground[core][chosen]).mean(axis=0)
                present.append((colour, crop[core][chosen].mean(axis=0), change))
        if not present:
            continue
        # nearest class, judged on the colour change from the table under each pixel
        offsets = (crop - ground).reshape(-1, 3)
        centre_offsets = np.array([change for _, _, change in present])
        scores = np.stack(
            [
                np.linalg.norm(offsets - (offsets @ c / max(c @ c, 1e-9))[:, None] * c, axis=1)
                - 0.25 * (offsets @ c) / np.sqrt(max(c @ c, 1e-9))
                for c in centre_offsets
            ],
            axis=1,
        )
        nearest = np.argmin(scores, axis=1).reshape(member.shape)
        for k, (colour, centre, c) in enumerate(present):
            projection = ((crop - ground) @ c) / max(float(c @ c), 1e-9)
            alpha = (
                np.clip(projection, 0.0, 1.0)
                * (nearest == k)
                * ndimage.binary_dilation(member, iterations=1)
            )
            regions.append(
                ColourRegion(
                    colour,
                    (float(centre[0]), float(centre[1]), float(centre[2])),
                    (rows.start, cols.start),
                    alpha,
                )
            )
    return regions, table


def _table_model(rgb: np.ndarray) -> np.ndarray:
    """The table's colour under every pixel: a plane per channel fitted (least
    squares) to the image border, so a smooth brightness gradient is table too."""
    height, width, _ = rgb.shape
    rows = np.concatenate(
        [np.zeros(width), np.full(width, height - 1), np.arange(height), np.arange(height)]
    )
    cols = np.concatenate(
        [np.arange(width), np.arange(width), np.zeros(height), np.full(height, width - 1)]
    )
    values = rgb[rows.astype(int), cols.astype(int)]
    design = np.stack([np.ones_like(rows), rows / height, cols / width], axis=1)
    coefficients, *_ = np.linalg.lstsq(design, values, rcond=None)
    # refit without the border pixels a block touches (far from the first fit)
    residual = np.linalg.norm(values - design @ coefficients, axis=1)
    keep = residual <= 3 * max(float(np.median(residual)), 1.0)
    coefficients, *_ = np.linalg.lstsq(design[keep], values[keep], rcond=None)
    rr, cc = np.meshgrid(np.arange(height) / height, np.arange(width) / width, indexing="ij")
    model: np.ndarray = (
        coefficients[0] + rr[..., None] * coefficients[1] + cc[..., None] * coefficients[2]
    )
    return model
