"""What perception found and what it rejected, drawn on the input image
(``demoplan perceive --plot``, docs/perception.md "Overlays").

Found blocks: their outline (the top face) in cyan with their name and yaw;
rejected regions: their outline in magenta with the reason. Outlines are
given in world (x, y) on a plane of the table's and mapped into the image by
the caller's ``to_image`` — a top view's scale and origin, or a calibrated
photograph's homography (:func:`~demoplan.perception.calibration.table_to_photo`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.errors import InputError
from demoplan.perception.blocks import Rejection
from demoplan.perception.camera import Camera

__all__ = [
    "FOUND_COLOUR",
    "REJECTED_COLOUR",
    "SPECK_SHARE",
    "Drawn",
    "NoBlocksError",
    "draw_overlay",
    "is_speck",
    "speck_side",
    "specks_line",
    "square_corners",
    "top_view_to_image",
]

FOUND_COLOUR = (0, 255, 255)
"""Cyan: no block colour of the palette is near it."""
REJECTED_COLOUR = (255, 0, 255)
"""Magenta."""

SPECK_SHARE = 1 / 3
"""A rejected part whose area is under a ninth of a block's top — its square
side under this share of the blocks' side — is a speck: no block of the
picture's size could be it, and the overlay does not draw it, only counts it
(mrhan_stacks: 897 of 1,066 rejections, which buried the ones that matter)."""

ToImage = Callable[[np.ndarray, float], np.ndarray]
"""World points (N × 2, m) on the plane at a height (m) → image points (N × 2,
x right, y down, pixel centres at whole numbers)."""


@dataclass(frozen=True, slots=True)
class Drawn:
    """A found block as drawn: its name, centre (m), yaw (deg), side (m) and the
    height (m) of the plane its outline lies on (its top face's, where known)."""

    name: str
    x: float
    y: float
    yaw: float
    side: float
    height: float = 0.0


class NoBlocksError(InputError):
    """No block in the picture (exit 1), with the overlay of what was rejected
    and why where one was asked for (``--plot``): that picture is the diagnosis
    of a "no blocks found", and ``demoplan perceive`` writes it alone (never the
    scene) on that exit."""

    def __init__(self, message: str, *, source: str, overlay: np.ndarray | None):
        super().__init__(message, source=source)
        self.overlay = overlay


def speck_side(sides: Sequence[float]) -> float:
    """The block side the specks are measured against: the median of the
    blocks found (``sides``, in the outlines' unit), else the smallest side the
    detector looks for by default (a picture where nothing was found)."""
    if sides:
        return float(np.median(sides))
    from demoplan.perception.blocks import PerceptionSettings

    return PerceptionSettings().min_side


def is_speck(rejection: Rejection, side: float) -> bool:
    """Whether ``rejection``'s outlines enclose less than (:data:`SPECK_SHARE` ×
    ``side``)² — measured on the table, in the outlines' own unit, so a
    calibrated photograph's perspective does not change it."""
    area = 0.0
    for piece in rejection.outlines:
        points = np.asarray(piece, dtype=float)
        if len(points) >= 3:
            x, y = points[:, 0], points[:, 1]
            area += 0.5 * abs(float(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))))
    return area < (SPECK_SHARE * side) ** 2


def specks_line(count: int) -> str:
    """The overlay's legend for the specks not drawn."""
    return f"{count:,} {'speck' if count == 1 else 'specks'} under 1/9 of a block's top, not drawn"


def _without_specks(
    rejected: Sequence[tuple[Rejection, float]], sides: Sequence[float], side: float | None
) -> tuple[list[tuple[Rejection, float]], int]:
    """The rejections but the specks (against ``side``, else the ``sides`` found),
    and how many specks there were."""
    limit = side if side is not None else speck_side(sides)
    kept = [(r, plane) for r, plane in rejected if not is_speck(r, limit)]
    return kept, len(rejected) - len(kept)


def square_corners(x: float, y: float, yaw: float, side: float) -> np.ndarray:
    """A square's four corners in world (x, y), counter-clockwise."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    h = side / 2
    return np.array(
        [(x + c * a - s * b, y + s * a + c * b) for a, b in ((-h, -h), (h, -h), (h, h), (-h, h))]
    )


def top_view_to_image(camera: Camera, height: int) -> ToImage:
    """World → pixel of a top view of ``height`` rows read with ``camera`` (the
    plane's height makes no difference there)."""

    def to_image(points: np.ndarray, _plane: float) -> np.ndarray:
        u = (points[:, 0] - camera.origin[0]) * camera.px_per_m
        v = (points[:, 1] - camera.origin[1]) * camera.px_per_m
        mapped: np.ndarray = np.c_[u - 0.5, height - v - 0.5]
        return mapped

    return to_image


def draw_overlay(
    image: np.ndarray,
    found: Sequence[Drawn],
    rejected: Sequence[tuple[Rejection, float]],
    to_image: ToImage,
    side: float | None = None,
) -> np.ndarray:
    """``image`` (RGB) with the found blocks' outlines, names and yaws (cyan) and
    the rejected regions' outlines and reasons (magenta), each ``(rejection,
    height of its plane)``, but the specks (:func:`is_speck`; ``side``, else the
    found blocks'), counted at the bottom left; lines 2 px at 640 px."""
    from demoplan.perception.opencv import cv2

    rejected, hidden = _without_specks(rejected, [b.side for b in found], side)
    picture = np.ascontiguousarray(image, dtype=np.uint8).copy()
    height, width = picture.shape[:2]
    thickness = max(1, round(max(width, height) / 640))
    limit = 4 * max(width, height)

    def polygon(points: np.ndarray) -> np.ndarray | None:
        if len(points) < 2 or not np.all(np.isfinite(points)) or np.abs(points).max() > limit:
            return None  # behind the camera or far off the image
        fixed: np.ndarray = np.rint(points * 16).astype(np.int32)  # 4 bits of sub-pixel
        return fixed

    taken: list[tuple[int, int, int, int]] = []  # the labels' boxes drawn so far

    def label(
        text: str, points: np.ndarray, colour: tuple[int, int, int], left: bool = False
    ) -> None:
        """``text`` centred above the outline (below where there is no room), unless
        it would cover another label; ``left``: starting at the one point given."""
        scale = 0.45 * thickness
        (w, h), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thickness)
        x = int(np.clip(points[:, 0].mean() - (0 if left else w / 2), 0, max(0, width - w)))
        below = points[:, 1].max() + h + 4 * thickness
        for y in (points[:, 1].max(),) if left else (points[:, 1].min() - 4 * thickness, below):
            y = int(np.clip(y, h + 1, height - 1))
            box = (x - 2, y - h - 2, x + w + 2, y + 4)
            if not any(
                box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in taken
            ):
                taken.append(box)
                for ink, weight in (((0, 0, 0), 3 * thickness), (colour, thickness)):
                    cv2.putText(
                        picture,
                        text,
                        (x, y),
                        cv2.FONT_HERSHEY_SIMPLEX,
                        scale,
                        ink,
                        weight,
                        cv2.LINE_AA,
                    )
                return

    items = [  # text, outlines in the image, colour, line weight
        (
            rejection.reason,
            [to_image(np.asarray(piece, dtype=float), plane) for piece in rejection.outlines],
            REJECTED_COLOUR,
            thickness,
        )
        for rejection, plane in rejected
    ]
    items += [
        (
            f"{block.name} {round(block.yaw)} deg",
            [to_image(square_corners(block.x, block.y, block.yaw, block.side), block.height)],
            FOUND_COLOUR,
            2 * thickness,
        )
        for block in found
    ]
    for _, pieces, colour, weight in items:  # the found blocks' outlines on top
        drawn = [p for p in map(polygon, pieces) if p is not None]
        cv2.polylines(picture, drawn, True, colour, weight, cv2.LINE_AA, 4)
    if hidden:  # the legend first: its place is kept
        legend = np.array([[4.0 * thickness, height - 2.0 * thickness]])
        label(specks_line(hidden), legend, REJECTED_COLOUR, left=True)
    for text, pieces, colour, _ in items[len(rejected) :] + items[: len(rejected)]:
        shown = [p for p in pieces if polygon(p) is not None]
        if shown:  # the found blocks' labels first: they take the best places
            label(text, np.concatenate(shown), colour)
    return picture
