"""Tops partly hidden by a hand, and things that are not square though a square fits
in them (demoplan.perception.occlusion, demoplan.perception.shapes): a fingertip
over a cube's top does not make it no block, the hand is none; the outline of the
thing a square lies in has a cube top's four corners, a pentagon's five."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from demoplan.perception.blocks import Rejection, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.occlusion import MAX_HIDDEN_SHARE, seen_fit
from demoplan.perception.opencv import cv2
from demoplan.perception.photo_families_scene import Cube, Hand, PhotoScene, render_scene
from demoplan.perception.photos import PhotoRig
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


@settings(max_examples=30, deadline=None)
@given(
    share=st.floats(0.03, 0.4),
    side=st.floats(20.0, 60.0),
    turn=st.floats(-45.0, 45.0),
)
def test_the_pixels_a_finger_hides_do_not_count(share: float, side: float, turn: float) -> None:
    """A square mask with a band over one side's part hidden (the mask empty
    there, the occluder covering it): measured over the seen pixels it is the
    square (covered, no misfit) while the band is within MAX_HIDDEN_SHARE of it;
    beyond, it is not judged so; with nothing hidden, not either."""
    params = np.array([50.0, 50.0, turn, side])
    square = square_pixels((100, 100), params, 0.0).astype(float)
    c, s = math.cos(math.radians(turn)), math.sin(math.radians(turn))
    uu, vv = np.meshgrid(np.arange(100) + 0.5, 100 - np.arange(100) - 0.5)
    across = c * (uu - 50.0) + s * (vv - 50.0)  # along the square's own u axis
    hidden = across > side / 2 - share * side
    alpha = np.where(hidden, 0.0, square)
    fit = (params, 0.0, 1.0, 1.0)
    seen = seen_fit(alpha, fit, hidden & (alpha < 0.5))
    inside = square_pixels((100, 100), params, -2.0)
    hidden_inside = np.count_nonzero(hidden & inside) / np.count_nonzero(inside)
    if hidden_inside > MAX_HIDDEN_SHARE + 0.03:
        assert seen is None
    elif hidden_inside < MAX_HIDDEN_SHARE - 0.03:
        assert seen is not None
        assert seen[1] > 0.99 and seen[2] < 0.2
    assert seen_fit(alpha, fit, np.zeros_like(hidden)) is None


@settings(max_examples=6, deadline=None)
@given(
    yaw=st.floats(-45.0, 45.0),
    towards=st.floats(0.0, 360.0),
    over=st.floats(0.005, 0.012),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_top_a_fingertip_is_over_is_found_and_the_hand_is_no_block(
    yaw: float, towards: float, over: float, seed: int
) -> None:
    """One cube on paper, a hand's fingers reaching over its top by ``over`` metres
    (5-12 mm of 40): the cube is found where it stands (within a quarter side: the
    square fitted to what is seen of a top whose whole side the fingers cross is
    smaller), and nothing else is (the hand is rejected, with a reason)."""
    rig = PhotoRig(height=1.2, nadir=(0.3, 0.2))
    cube = Cube("blue", (40, 80, 190), 0.3, 0.2, yaw, 0.04)
    width = 0.085
    a = math.radians(towards)
    # the longest finger's tip is 1.35 palm widths from the palm's centre (Hand.outlines)
    reach = 0.02 + 1.35 * width - over
    palm = (0.3 - reach * math.cos(a), 0.2 - reach * math.sin(a))
    hand = Hand(*palm, towards, width, (224, 172, 140))
    scene = PhotoScene(rig, (cube,), hands=(hand,), background="paper", glints=0.0)
    image, (truth,) = render_scene(scene, np.random.default_rng(seed))
    assume(0.8 <= truth.in_view <= 0.97)  # a fingertip's bite (not a miss, not a hand)
    px_per_m = rig.scale_at(0.3, 0.2, 0.04)
    rejected: list[Rejection] = []
    found = detect_blocks(image, Camera(px_per_m, (0.0, 0.0)), rejected=rejected)
    height = image.shape[0]
    centre = ((truth.u + 0.5) / px_per_m, (height - truth.v - 0.5) / px_per_m)
    assert len(found) == 1, found
    assert math.dist((found[0].x, found[0].y), centre) < 0.25 * 0.04
    assert any(r.colour not in ("blue", "") for r in rejected)  # the hand, with its reason
