"""A photographed cube's top has rounded corners (its bevel, the lens's blur): it
is still a square block; a disc (a cylinder's top) of the same size and blur is
not; a square sharing a whole side with more of its region (a 2:1 brick) is judged
sharp. (armlab_mrhan4, whose cubes' corners are so rounded, is scored with the
other real photographs: test_perception_real_photos.)"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception.acceptance import CORNER_ROUNDING, shares_a_side
from demoplan.perception.blocks import Rejection, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.opencv import cv2

CAMERA = Camera(1000.0, (0.0, 0.0))  # 1 px = 1 mm
WIDTH, HEIGHT = 240, 200
TABLE = (205, 205, 200)
COLOURS = {
    "red": (200, 40, 40),
    "green": (50, 150, 60),
    "blue": (40, 80, 190),
    "orange": (225, 110, 35),
}


def _render(
    side: float,
    radius: float,
    yaw: float,
    blur: float,
    rgb: tuple[int, int, int],
    seed: int,
) -> tuple[np.ndarray, tuple[float, float]]:
    """A top view of a ``side`` px square with corners rounded at ``radius`` px (a disc
    when the radius is half the side), turned by ``yaw``, at the image's centre give or
    take a pixel, four times supersampled, blurred (Gaussian σ ``blur`` px), with 2
    grey levels of noise; and its centre in pixels (x right, y up)."""
    rng = np.random.default_rng(seed)
    cx, cy = WIDTH / 2 + rng.uniform(-1, 1), HEIGHT / 2 + rng.uniform(-1, 1)
    n = 4
    xs, ys = np.meshgrid(
        (np.arange(WIDTH * n) + 0.5) / n, HEIGHT - (np.arange(HEIGHT * n) + 0.5) / n
    )
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    qu = np.abs(c * (xs - cx) + s * (ys - cy))
    qv = np.abs(-s * (xs - cx) + c * (ys - cy))
    du = np.maximum(qu - (side / 2 - radius), 0.0)
    dv = np.maximum(qv - (side / 2 - radius), 0.0)
    inside = np.where(
        (du > 0) & (dv > 0), np.hypot(du, dv) <= radius, (qu <= side / 2) & (qv <= side / 2)
    )
    cover = inside.reshape(HEIGHT, n, WIDTH, n).mean(axis=(1, 3))[..., None]
    image = (1 - cover) * np.array(TABLE, float) + cover * np.array(rgb, float)
    if blur > 0:
        image = cv2.GaussianBlur(image, (0, 0), blur)
    image += rng.normal(0.0, 2.0, image.shape)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8), (cx, cy)


@settings(max_examples=25, deadline=None)
@given(
    side=st.floats(30.0, 45.0),
    rounding=st.floats(0.0, CORNER_ROUNDING[-1]),
    yaw=st.floats(-45.0, 45.0),
    blur=st.floats(0.0, 1.5),
    colour=st.sampled_from(sorted(COLOURS)),
    seed=st.integers(0, 1000),
)
def test_a_top_with_rounded_corners_and_soft_edges_is_found(
    side: float, rounding: float, yaw: float, blur: float, colour: str, seed: int
) -> None:
    image, (cx, cy) = _render(side, rounding * side, yaw, blur, COLOURS[colour], seed)
    found = detect_blocks(image, CAMERA)
    assert len(found) == 1, (found, rounding, blur)
    block = found[0]
    assert math.hypot(block.x * 1000 - cx, block.y * 1000 - cy) < 1.5
    assert abs(block.side * 1000 - side) < 2.5


@settings(max_examples=20, deadline=None)
@given(
    diameter=st.floats(30.0, 45.0),
    blur=st.floats(0.0, 1.5),
    colour=st.sampled_from(sorted(COLOURS)),
    seed=st.integers(0, 1000),
)
def test_a_disc_of_a_cube_s_size_is_no_block(
    diameter: float, blur: float, colour: str, seed: int
) -> None:
    image, _ = _render(diameter, diameter / 2, 0.0, blur, COLOURS[colour], seed)
    rejected: list[Rejection] = []
    assert detect_blocks(image, CAMERA, rejected=rejected) == []
    assert rejected


def _brick_mask(length: float, side: float, yaw: float) -> np.ndarray:
    """A soft mask (crop, 160 × 160 px) of a ``length`` × ``side`` px rectangle at
    its centre, turned by ``yaw``, edges ramping over one pixel."""
    us, vs = np.meshgrid(np.arange(160) + 0.5, 160 - np.arange(160) - 0.5)
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    along = np.abs(c * (us - 80) + s * (vs - 80)) - length / 2
    across = np.abs(-s * (us - 80) + c * (vs - 80)) - side / 2
    mask: np.ndarray = np.clip(0.5 - np.maximum(along, across), 0.0, 1.0)
    return mask


@settings(max_examples=30, deadline=None)
@given(
    side=st.floats(24.0, 48.0),
    yaw=st.floats(-45.0, 45.0),
    strip=st.floats(0.0, 0.2),
    shift=st.floats(-0.5, 0.5),
)
def test_a_square_with_its_region_beyond_a_whole_side_shares_it(
    side: float, yaw: float, strip: float, shift: float
) -> None:
    """A square at either end of a 2:1 brick (or anywhere along it, ``shift`` of a
    side from its end) has the brick beyond a side; a lone top with a strip of side
    face up to a fifth of its side beside it has not."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    brick = _brick_mask(2 * side, side, yaw)
    for end in (-1, 1):
        offset = end * (side / 2 - shift * side / 2)
        square = np.array([80 + c * offset, 80 + s * offset, yaw, side])
        assert shares_a_side(brick, square)
    lone = _brick_mask(side * (1 + strip), side, yaw)
    back = strip * side / 2  # the top at one end, the strip at the other
    assert not shares_a_side(lone, np.array([80 + c * back, 80 + s * back, yaw, side]))
