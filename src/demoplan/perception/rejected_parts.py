"""The parts of a top-view image that colour_regions drops on its way, each with
why (:class:`RejectedPart`), and the recorder that keeps them when a caller asks
for them (``demoplan perceive --plot`` draws them)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from demoplan.perception.masks import dilate
from demoplan.perception.opencv import cv2

__all__ = ["REPORTED_SHARE", "PartRecorder", "RejectedPart", "outlines"]


@dataclass(frozen=True, slots=True)
class RejectedPart:
    """A foreground part that is no block, and why: ``reason`` a short phrase
    (``too small``, ``thin or faint``, ``no block colour``, ``side face``, ``table``),
    ``detail`` the measure behind it, ``outlines`` the outlines of its pieces in
    image pixels (x right, y down, pixel centres at whole numbers), each N × 2."""

    reason: str
    detail: str
    colour: str
    outlines: tuple[np.ndarray, ...]


REPORTED_SHARE = 0.1
"""Parts smaller than this share of the smallest block's area (sensor noise,
specks) are dropped without a record."""


def outlines(mask: np.ndarray, min_area: float) -> list[np.ndarray]:
    """The outer outlines (N × 2 pixel points, x right, y down) of ``mask``'s parts
    of at least ``min_area`` pixels (OpenCV's contours)."""
    contours, _ = cv2.findContours(
        mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE
    )
    return [
        c.reshape(-1, 2).astype(float)
        for c in contours
        if len(c) >= 3 and cv2.contourArea(c) + len(c) / 2 >= min_area
    ]


class PartRecorder:
    """Appends the parts :func:`demoplan.perception.colours.colour_regions` drops
    to a list, when there is one (nothing is computed otherwise)."""

    def __init__(self, rejected: list[RejectedPart] | None, min_area: float):
        self.rejected = rejected
        self.min_area = min_area

    def __call__(
        self, mask: np.ndarray, rows: slice, cols: slice, reason: str, detail: str, colour: str = ""
    ) -> None:
        """``mask`` (on the crop ``rows`` × ``cols``), dropped for ``reason``: one
        record, of the pieces that are not mere specks."""
        if self.rejected is None:
            return
        shift = np.array([cols.start or 0, rows.start or 0])
        pieces = tuple(o + shift for o in outlines(mask, REPORTED_SHARE * self.min_area))
        if pieces:
            self.rejected.append(RejectedPart(reason, detail, colour, pieces))

    def speck(self, labels: np.ndarray, index: int, box: tuple[int, ...]) -> None:
        """A connected foreground part smaller than a block (not mere noise)."""
        x, y, w, h, area = box
        if self.rejected is not None and area >= REPORTED_SHARE * self.min_area:
            mask = labels[y : y + h, x : x + w] == index
            self(mask, slice(y, y + h), slice(x, x + w), "too small", f"{area} px")

    def shade(
        self, classes: np.ndarray, core: np.ndarray, lightness: np.ndarray, rows: slice, cols: slice
    ) -> None:
        """Core pixels of a coloured region too dark or grey to be named, and darker
        than most of it (a side face in shadow, a shadow): no class takes them."""
        if self.rejected is None:
            return
        shade = np.zeros_like(core)
        dim = lightness[core] < np.median(lightness[core])
        shade[core] = ((classes == -2) | (classes == -3)) & dim
        why = "dark or grey in a coloured region"
        self(dilate(shade, 3), rows, cols, "side face or shadow", why)

    def side_faces(
        self,
        core: np.ndarray,
        darker: np.ndarray,
        where: tuple[slice, slice],
        why: str,
        colour: str,
    ) -> None:
        """A class's darker lightness mode (``darker``, over its ``core`` pixels)."""
        if self.rejected is None:
            return
        mask = np.zeros_like(core)
        mask[core] = darker
        self(dilate(mask, 3), *where, "side face", why, colour)
