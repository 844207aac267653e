"""A side face beside its top: of two squares found face to face in one hue, the
darker is a side face of the brighter's cube.

A camera that is not straight above a cube sees one or two of its side faces
beside its top: the same material, so the same hue, lit less (the light comes
from above), sharing a whole edge with the top. When the side faces are nearly
as large as the top (a camera low and off to the side, the `side_faces` and
`tilted` families) the colour split of :mod:`demoplan.perception.colours` may
leave one as a class of its own (a dark red is not red), and a square fits it.
Two cubes face to face are lit alike, so their tops' lightness differs little;
a face :data:`~demoplan.perception.palette.SIDE_FACE_GAP` L* darker than a
square of its hue that it shares a side with is not a top. Only coloured faces
are judged so: a grey face beside a white one may be a grey cube as well as the
white cube's side, and hue does not tell them apart.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from demoplan.perception.exposure import chroma_at_mid_grey
from demoplan.perception.opencv import cv2
from demoplan.perception.palette import MIN_CHROMA, SIDE_FACE_GAP

__all__ = ["ImageSquare", "corners_in_image", "side_faces_beside_tops", "table_shadows"]

ImageSquare = tuple[float, float, float, float]
"""A square in the image: its centre x (right), y (down) in px, θ (deg, counter-
clockwise with y up) and side (px)."""

MAX_TURN = 10.0
"""Degrees (modulo 90) by which a side face's fitted square may be turned from its
top's: they share an edge."""
MAX_HUE_TURN = 20.0
"""Degrees of a*b* hue between a side face and its top (the same material)."""


def corners_in_image(square: ImageSquare) -> np.ndarray:
    """The four corners (4 × 2: x right, y down, px) of ``square``."""
    x, y, theta, side = square
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    h = side / 2
    return np.array(
        [(x + c * a - s * b, y - (s * a + c * b)) for a, b in ((-h, -h), (h, -h), (h, h), (-h, h))]
    )


class _FaceColour(NamedTuple):
    """A face's mean colour: 8-bit RGB and CIELAB."""

    rgb: np.ndarray
    lightness: float
    a: float
    b: float

    @property
    def chroma(self) -> float:
        return math.hypot(self.a, self.b)


def _face_colour(image: np.ndarray, square: ImageSquare) -> _FaceColour:
    """The mean colour over the central half (by side) of ``square``."""
    x, y, theta, side = square
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    steps = (np.arange(8) + 0.5) / 8 * 0.5 - 0.25
    along, across = np.meshgrid(steps * side, steps * side)
    xs = np.clip(np.floor(x + c * along - s * across), 0, image.shape[1] - 1).astype(np.intp)
    ys = np.clip(np.floor(y - (s * along + c * across)), 0, image.shape[0] - 1).astype(np.intp)
    mean = image[ys, xs].reshape(-1, 3).mean(axis=0)
    lab = cv2.cvtColor((mean / 255.0).astype(np.float32).reshape(1, 1, 3), cv2.COLOR_RGB2Lab)
    return _FaceColour(mean, float(lab[0, 0, 0]), float(lab[0, 0, 1]), float(lab[0, 0, 2]))


def _of_its_material(face: _FaceColour, top: _FaceColour) -> bool:
    """Whether ``face`` may be ``top``'s material lit less: at least
    :data:`~demoplan.perception.palette.SIDE_FACE_GAP` L* darker, ``top`` coloured, and
    their hues within :data:`MAX_HUE_TURN` — or, a face too dark to show its hue
    (chroma as lit to mid grey under twice :data:`~demoplan.perception.palette.MIN_CHROMA`:
    :func:`~demoplan.perception.exposure.chroma_at_mid_grey`; less light shrinks a
    colour's chroma with it), no channel brighter than the top's."""
    if top.lightness - face.lightness < SIDE_FACE_GAP or top.chroma < MIN_CHROMA:
        return False
    if chroma_at_mid_grey(face.chroma, face.lightness) < 2 * MIN_CHROMA:
        return bool(np.all(face.rgb <= top.rgb))
    turn = math.degrees(math.atan2(face.b, face.a) - math.atan2(top.b, top.a))
    return abs((turn + 180.0) % 360.0 - 180.0) <= MAX_HUE_TURN


def _face_to_face(top: ImageSquare, face: ImageSquare) -> bool:
    """Whether ``face`` lies against a side of ``top``: its centre about a side away
    across one of ``top``'s sides (not past a corner), turned alike."""
    x, y, theta, side = top
    turn = (face[2] - theta + 45.0) % 90.0 - 45.0
    if abs(turn) > MAX_TURN:
        return False
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    dx, dy = face[0] - x, y - face[1]  # y up
    along, across = abs(c * dx + s * dy), abs(-s * dx + c * dy)
    apart, aside = max(along, across), min(along, across)
    reach = (side + face[3]) / 2
    return 0.6 * reach <= apart <= 1.25 * reach and aside <= 0.35 * side


def side_faces_beside_tops(image: np.ndarray, squares: Sequence[ImageSquare]) -> dict[int, str]:
    """The indices of ``squares`` (accepted in ``image``, H × W × 3) that are side
    faces beside a top, each with why: a square face to face with another that is
    of its material and brighter (:func:`_of_its_material`)."""
    colours = [_face_colour(image, square) for square in squares]
    side_faces: dict[int, str] = {}
    for i, (face, colour) in enumerate(zip(squares, colours, strict=True)):
        for top, top_colour in zip(squares, colours, strict=True):
            if _of_its_material(colour, top_colour) and _face_to_face(top, face):
                side_faces[i] = (
                    f"L* {colour.lightness:.0f} beside a top of its colour at L* "
                    f"{top_colour.lightness:.0f}"
                )
                break
    return side_faces


SHADOW_LIGHT = (0.35, 0.85)
"""The share of the table's light a shadow on it keeps (every channel alike): lit by
the room, never black, and at least a sixth darker than the table (a face as
bright as the table is no shadow)."""
SHADOW_TINT = 1.2
"""The most by which a shadow's channels' shares of the table's may differ (the
largest over the smallest): a shadow darkens, it does not tint."""


def _around(image: np.ndarray, square: ImageSquare) -> np.ndarray:
    """The median colour (RGB) of ``image`` in a band around ``square``, from 0.7 to 1
    side from its centre: the table it stands on, mostly."""
    x, y, theta, side = square
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    steps = (np.arange(16) + 0.5) / 16 * 2.0 - 1.0
    along, across = np.meshgrid(steps * side, steps * side)
    band = np.maximum(np.abs(along), np.abs(across)) >= 0.7 * side
    along, across = along[band], across[band]
    xs = np.floor(x + c * along - s * across)
    ys = np.floor(y - (s * along + c * across))
    inside = (xs >= 0) & (xs < image.shape[1]) & (ys >= 0) & (ys < image.shape[0])
    points = image[ys[inside].astype(np.intp), xs[inside].astype(np.intp)].reshape(-1, 3)
    return np.median(points.astype(float), axis=0) if points.size else np.zeros(3)


def table_shadows(
    image: np.ndarray, squares: Sequence[ImageSquare], colours: Sequence[np.ndarray]
) -> dict[int, str]:
    """The indices of ``squares`` (accepted in ``image``; ``colours`` their regions'
    mean RGB) that are a shadow on a coloured table, each with why: the colour of
    the table around the square, every channel at a like share
    (:data:`SHADOW_TINT`) of :data:`SHADOW_LIGHT` of it. On a coloured table (a
    blue one) a cube's shadow differs from the table in chroma too, and so is
    foreground; on a grey board it is not."""
    shadows: dict[int, str] = {}
    for index, (square, rgb) in enumerate(zip(squares, colours, strict=True)):
        table = _around(image, square)
        lab = cv2.cvtColor((table / 255.0).astype(np.float32).reshape(1, 1, 3), cv2.COLOR_RGB2Lab)
        if math.hypot(float(lab[0, 0, 1]), float(lab[0, 0, 2])) < MIN_CHROMA or table.min() <= 0:
            continue  # a grey table: its shadows are no foreground
        shares = np.asarray(rgb, dtype=float) / table
        light = float(shares.mean())
        tint = float(shares.max() / max(float(shares.min()), 1e-9))
        if SHADOW_LIGHT[0] <= light <= SHADOW_LIGHT[1] and tint <= SHADOW_TINT:
            shadows[index] = f"the table's colour at {light:.0%} of its light"
    return shadows
