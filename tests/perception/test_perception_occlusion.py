"""Tops partly hidden by a hand, and things that are not square though a square fits
in them (demoplan.perception.occlusion, demoplan.perception.shapes): a fingertip
over a cube's top does not make it no block, the hand is none; the outline of the
thing a square lies in has a cube top's four corners, a pentagon's five."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception.opencv import cv2
from demoplan.perception.shapes import hull_corners, outlines_not_square, square_pixels

SIZE = 200


def _polygon(corners: int, radius: float, turn: float, centre: tuple[float, float]) -> np.ndarray:
    """A filled regular polygon (bool, SIZE × SIZE) of ``corners`` corners."""
    angles = np.radians(turn) + np.arange(corners) * 2 * math.pi / corners
    points = np.stack([centre[0] + radius * np.cos(angles), centre[1] + radius * np.sin(angles)], 1)
    canvas = np.zeros((SIZE, SIZE), dtype=np.uint8)
    cv2.fillPoly(canvas, [np.round(points * 16).astype(np.int32)], 1, shift=4)
    return canvas.astype(bool)


POSES = {
    "radius": st.floats(15.0, 70.0),
    "turn": st.floats(0.0, 360.0),
    "du": st.floats(-20.0, 20.0),
    "dv": st.floats(-20.0, 20.0),
}


@settings(max_examples=40, deadline=None)
@given(corners=st.integers(3, 5), **POSES)
def test_a_regular_polygons_hull_has_its_corners(
    corners: int, radius: float, turn: float, du: float, dv: float
) -> None:
    mask = _polygon(corners, radius, turn, (100 + du, 100 + dv))
    assert hull_corners(mask) == corners


@settings(max_examples=30, deadline=None)
@given(notch=st.floats(0.1, 0.3), strip=st.floats(0.0, 0.25), **POSES)
def test_a_top_bitten_and_with_a_side_face_has_four_corners(
    notch: float, strip: float, radius: float, turn: float, du: float, dv: float
) -> None:
    """A square top with a fingertip's bite out of one side and a side face of its
    colour up to a quarter of a side wide along another: still four corners."""
    centre = (100 + du, 100 + dv)
    side = radius * math.sqrt(2)
    top = square_pixels((SIZE, SIZE), np.array([centre[0], SIZE - centre[1], turn, side]), 0.0)
    face = square_pixels(
        (SIZE, SIZE), np.array([centre[0], SIZE - centre[1], turn, side + 2 * strip * side]), 0.0
    )
    a = math.radians(turn)
    half = side / 2
    across = np.array([-math.sin(a), -math.cos(a)])  # rows grow downwards
    along = np.array([math.cos(a), -math.sin(a)])
    rows, cols = np.mgrid[:SIZE, :SIZE]
    # the side face: the band beyond one side only; the bite: a disc on another side
    band = (cols + 0.5 - centre[0]) * along[0] + (rows + 0.5 - centre[1]) * along[1] > half
    bite_at = np.array(centre) + half * across
    bite = np.hypot(cols + 0.5 - bite_at[0], rows + 0.5 - bite_at[1]) < notch * side
    mask = (top | (face & band)) & ~bite
    assert hull_corners(mask) == 4


def test_a_square_inscribed_in_a_pentagon_is_not_square_one_in_a_square_is() -> None:
    pentagon = _polygon(5, 40.0, 90.0, (100.0, 100.0))
    inscribed = np.array([100.0, SIZE - 96.0, 0.0, 50.0])  # as the fit puts it: 85 % in at least
    assert np.mean(pentagon[square_pixels((SIZE, SIZE), inscribed, 0.0)]) > 0.85
    assert outlines_not_square(pentagon, [inscribed]) == {0: "5 corners"}
    square = square_pixels((SIZE, SIZE), inscribed, 0.0)
    assert outlines_not_square(square, [inscribed]) == {}
    # two touching squares of one colour: each judged with the other taken out
    right = inscribed + np.array([50.0, 0.0, 0.0, 0.0])
    pair = square | square_pixels((SIZE, SIZE), right, 0.0)
    assert outlines_not_square(pair, [inscribed, right]) == {}
