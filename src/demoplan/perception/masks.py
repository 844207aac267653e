"""Binary masks shaped with OpenCV: eroded and dilated by the 4-neighbour cross,
their small parts, their holes filled (what :mod:`demoplan.perception.colours`
cuts its regions with); the distances it classifies colours by; and the reach of
a second table (:class:`TableReach`). SciPy's
equivalents are not imported: ``demoplan perceive``'s start-up is part of its
time, and SciPy's would be a third of it."""

from __future__ import annotations

import numpy as np

from demoplan.perception.opencv import cv2

__all__ = [
    "CROSS",
    "TableReach",
    "close",
    "dilate",
    "distances",
    "erode",
    "fill_holes",
    "labelled_parts",
    "small_parts",
]

CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
"""The 4-neighbour cross (3 × 3) the masks are eroded and dilated by."""


def erode(mask: np.ndarray, steps: int) -> np.ndarray:
    """``mask`` eroded ``steps`` times by the 4-neighbour cross (outside is empty),
    as ``scipy.ndimage.binary_erosion(mask, iterations=steps)``, with OpenCV."""
    eroded = cv2.erode(
        mask.astype(np.uint8),
        CROSS,
        iterations=steps,
        borderType=cv2.BORDER_CONSTANT,
        borderValue=0,
    )
    return np.asarray(eroded, dtype=bool)


def dilate(mask: np.ndarray, steps: int) -> np.ndarray:
    """``mask`` dilated ``steps`` times by the 4-neighbour cross, with OpenCV."""
    return np.asarray(cv2.dilate(mask.astype(np.uint8), CROSS, iterations=steps), dtype=bool)


def close(mask: np.ndarray, radius: int) -> np.ndarray:
    """``mask`` closed by a disc ``radius`` pixels out from its centre, the crop's
    outside empty: OpenCV's closing erodes with the outside full, so a mask
    dilated up to the crop's border kept all it had grown there (a black cube's
    crop, 10 px around it, closed by a disc of radius 10, grew 19 % of its area
    in bands along the crop's edges — then taken for a marker's white cells)."""
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
    padded = cv2.copyMakeBorder(
        mask.astype(np.uint8), radius, radius, radius, radius, cv2.BORDER_CONSTANT, value=0
    )
    closed = cv2.morphologyEx(padded, cv2.MORPH_CLOSE, disc)
    height, width = mask.shape
    return np.asarray(closed[radius : radius + height, radius : radius + width], dtype=bool)


class TableReach:
    """Where a second table (:mod:`demoplan.perception.colours`: a hand and forearm
    reaching in from the border may be one) left foreground beside it — its shading
    and rim off its median colour, its shadow on the table — that the nearest-class
    rule gives to the class of a cube beside it: within the largest block's
    ``side`` (px) of the table's body (``tables``, its pixels of its colour, eroded
    by a sixth of the side first, so the specks of its colour elsewhere — a grey
    board's pixels near a blue table's chroma — reach nowhere)."""

    def __init__(self, tables: np.ndarray, side: float) -> None:
        steps = max(1, round(side))
        body = erode(tables, max(1, steps // 6))
        # the distance from the body (one pass, ~10 ms on 1280 × 720), not a dilation
        # by a disc the side across (60-280 ms for sides of 50-110 px)
        away = cv2.distanceTransform((~body).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        self.mask: np.ndarray = away <= steps
        self.rim = max(1, round(side / 6))

    def strays(self, rows: slice, cols: slice, named: np.ndarray) -> np.ndarray | None:
        """Of the crop ``rows`` × ``cols``, the pixels within reach farther than a
        rim (a sixth of the side) from a class's pixels ``named`` its colour, or
        ``None`` (none): they stay in its soft mask — a piece of the table cut down
        to a class's core would look a block (``langtable_real``'s pale arm) — but
        do not count in its size (``ColourRegion.counted``)."""
        strays = self.mask[rows, cols] & ~dilate(named, self.rim)
        return strays if strays.any() else None


SHORT_LABELS = 2**16 - 1
"""A mask whose rows hold fewer runs of set pixels than this is labelled in 16 bits."""


def labelled_parts(mask: np.ndarray, connectivity: int = 8) -> tuple[int, np.ndarray, np.ndarray]:
    """OpenCV's connected parts of ``mask`` (bool or 0/1 ``uint8``): their count (the
    background's included), the label of each pixel and the parts' stats (box, area).
    The labels are ``uint16`` when the mask's rows hold fewer than :data:`SHORT_LABELS`
    runs of set pixels, else ``int32``: OpenCV's labelling gives a new label only to
    a pixel, or a 2 × 2 block, with a run's first pixel in it, so every label fits,
    and in 16 bits it labels on one thread, the same labels and stats at a third to
    a half of the CPU of its 32-bit labelling split between threads (the holes in a
    top, a photograph's white parts and its foreground alike)."""
    pixels = np.ascontiguousarray(mask.view(np.uint8) if mask.dtype == np.bool_ else mask, np.uint8)
    runs = np.count_nonzero(pixels[:, 1:] > pixels[:, :-1]) + np.count_nonzero(pixels[:, 0])
    count, labels, stats, _ = cv2.connectedComponentsWithStats(
        pixels, connectivity=connectivity, ltype=cv2.CV_16U if runs < SHORT_LABELS else cv2.CV_32S
    )
    return int(count), labels, stats


def small_parts(mask: np.ndarray, min_area: float) -> np.ndarray:
    """The connected parts of ``mask`` smaller than ``min_area`` pixels (all of it,
    unlabelled, when it is smaller than that altogether: a top's holes mostly are)."""
    if np.count_nonzero(mask) < min_area:
        return np.asarray(mask, dtype=bool)
    _, labels, stats = labelled_parts(mask)
    small = stats[:, cv2.CC_STAT_AREA] < min_area
    small[0] = False
    parts: np.ndarray = small[labels]
    return parts


def fill_holes(mask: np.ndarray) -> np.ndarray:
    """``mask`` with its holes filled: the parts of its outside that do not reach the
    crop's border (4-connected, as ``scipy.ndimage.binary_fill_holes``). One flood
    fill of the outside from a frame of outside pixels put round the crop: a fifth of
    the CPU of labelling the outside's parts and looking up which touch the border."""
    height, width = mask.shape
    framed = np.zeros((height + 2, width + 2), dtype=np.uint8)
    framed[1:-1, 1:-1] = mask
    cv2.floodFill(framed, None, (0, 0), 2, flags=4)  # the outside (0) reached: 2
    filled: np.ndarray = framed[1:-1, 1:-1] != 2
    return filled


def distances(points: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Euclidean distance of every point (N × D) to every centre (K × D), N × K, as
    ``scipy.spatial.distance.cdist`` gives it (the squares summed in order)."""
    squares = np.zeros((len(points), len(centres)))
    for k, centre in enumerate(centres):
        for d in range(points.shape[1]):
            squares[:, k] += np.square(points[:, d] - centre[d])
    root: np.ndarray = np.sqrt(squares)
    return root
