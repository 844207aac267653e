"""Binary masks shaped with OpenCV: eroded and dilated by the 4-neighbour cross,
their small parts, their holes filled (what :mod:`demoplan.perception.colours`
cuts its regions with); and the distances it classifies colours by. SciPy's
equivalents are not imported: ``demoplan perceive``'s start-up is part of its
time, and SciPy's would be a third of it."""

from __future__ import annotations

import numpy as np

from demoplan.perception.opencv import cv2

__all__ = ["CROSS", "close", "dilate", "distances", "erode", "fill_holes", "small_parts"]

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


def small_parts(mask: np.ndarray, min_area: float) -> np.ndarray:
    """The connected parts of ``mask`` smaller than ``min_area`` pixels."""
    _, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    small = stats[:, cv2.CC_STAT_AREA] < min_area
    small[0] = False
    parts: np.ndarray = small[labels]
    return parts


def fill_holes(mask: np.ndarray) -> np.ndarray:
    """``mask`` with its holes filled: the parts of its outside that do not reach the
    crop's border (4-connected, as ``scipy.ndimage.binary_fill_holes``)."""
    count, labels = cv2.connectedComponents((~mask).astype(np.uint8), connectivity=4)
    border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    enclosed = np.ones(count, dtype=bool)
    enclosed[border] = False
    enclosed[0] = False  # the mask itself
    filled: np.ndarray = mask | enclosed[labels]
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
