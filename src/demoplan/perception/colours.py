"""Background, foreground and colour classes of a top-view image.

The table is the image's dominant colour (the median of its border); a pixel
belongs to the foreground when it differs from the table by more than
``max(min_contrast, 6 σ)``, σ the sensor noise measured on the border. Each
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

__all__ = ["PALETTE", "ColourRegion", "colour_regions", "name_colour"]

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
    core_pixels: int


def name_colour(rgb: np.ndarray) -> str:
    """The plain colour name nearest to ``rgb`` (dark or grey: ``black`` / ``grey``)."""
    names, chroma = _palette()
    top = float(np.max(rgb))
    if top < 60:
        return "black"
    normal = np.asarray(rgb, dtype=float) / top
    if normal.min() > 0.82:
        return "grey"
    return names[int(np.argmin(np.linalg.norm(chroma - normal, axis=1)))]


def _palette() -> tuple[list[str], np.ndarray]:
    return list(PALETTE), np.array(list(PALETTE.values()))


def _classify(pixels: np.ndarray) -> np.ndarray:
    """Palette index per pixel (N × 3 RGB); dark → -2, greyish → -3."""
    _, chroma = _palette()
    top = pixels.max(axis=1)
    normal = pixels / np.maximum(top, 1.0)[:, None]
    distance = np.linalg.norm(normal[:, None, :] - chroma[None, :, :], axis=2)
    labels: np.ndarray = np.argmin(distance, axis=1)
    labels[normal.min(axis=1) > 0.82] = -3
    labels[top < 60] = -2
    return labels


def colour_regions(
    image: np.ndarray, *, min_area: float, min_contrast: float = 30.0
) -> tuple[list[ColourRegion], np.ndarray]:
    """The colour regions of ``image`` (H × W × 3) with at least ``min_area`` core
    pixels, and the table colour."""
    rgb = image.astype(float)
    border = np.concatenate([rgb[0], rgb[-1], rgb[:, 0], rgb[:, -1]])
    table = np.median(border, axis=0)
    deviation = np.linalg.norm(border - table, axis=1)
    sigma = 1.4826 * float(np.median(deviation)) / np.sqrt(3)
    threshold = max(min_contrast, 6 * sigma)
    distance = np.linalg.norm(rgb - table, axis=2)
    foreground = distance > threshold / 2
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
                colour = names[label] if label >= 0 else ("black" if label == -2 else "grey")
                present.append((colour, crop[core][chosen].mean(axis=0)))
        if not present:
            continue
        centres = np.array([c for _, c in present])
        pixel_colours = crop.reshape(-1, 3)
        # nearest class centre, judged on the colour change from the table
        offsets = pixel_colours - table
        centre_offsets = centres - table
        scores = np.stack(
            [
                np.linalg.norm(offsets - (offsets @ c / max(c @ c, 1e-9))[:, None] * c, axis=1)
                - 0.25 * (offsets @ c) / np.sqrt(max(c @ c, 1e-9))
                for c in centre_offsets
            ],
            axis=1,
        )
        nearest = np.argmin(scores, axis=1).reshape(member.shape)
        for k, (colour, centre) in enumerate(present):
            c = centre - table
            projection = ((crop - table) @ c) / max(float(c @ c), 1e-9)
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
                    int((classes == _index(colour)).sum()) if _index(colour) is not None else 0,
                )
            )
    return regions, table


def _index(colour: str) -> int | None:
    names, _ = _palette()
    return names.index(colour) if colour in names else None
