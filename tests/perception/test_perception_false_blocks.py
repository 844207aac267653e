"""Kinds of false blocks real photographs showed, generated: no block is reported
in any of them, and the blocks beside them are found as without them."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st

from demoplan.perception.blocks import PerceptionSettings, Rejection, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.labelled import FOUND_WITHIN
from demoplan.perception.opencv import cv2
from demoplan.perception.synthetic import COLOURS, random_blocks, render_blocks

CAMERA = Camera(1000.0, (0.0, 0.0))  # 1 px = 1 mm
WIDTH, HEIGHT = 500, 400


def _paint(
    image: np.ndarray, rows: slice, cols: slice, colour: str, rng: np.random.Generator
) -> None:
    """Paint a flat ``colour`` (with the render's sensor noise) over ``image[rows, cols]``."""
    patch = image[rows, cols]
    tint = np.asarray(COLOURS[colour], dtype=float)
    painted = tint + rng.normal(0.0, 2.0, patch.shape)
    image[rows, cols] = np.clip(np.rint(painted), 0, 255).astype(np.uint8)


@settings(max_examples=12, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    edge=st.sampled_from(("left", "right", "top", "bottom")),
    wide=st.floats(15.0, 45.0),
    start=st.floats(0.0, 0.3),
    long=st.floats(0.5, 1.0),
)
def test_a_strip_along_the_border_is_no_block(
    seed: int, edge: str, wide: float, start: float, long: float
) -> None:
    """A strip of one colour along the image's border, as wide as a block or less
    (a wooden table beyond a board, on the right of a phone photograph), cut by the
    border: a square fitted into it with its centre near the border lies partly
    past it, and the strip runs on beyond the square along the border — no block's
    top shows whole there. No block is reported in it; the blocks inside are found."""
    rng = np.random.default_rng(seed)
    truth = random_blocks(
        int(rng.integers(1, 4)),
        Camera(1000.0, (0.07, 0.07)),
        360,
        260,
        rng,
        colours=("red", "blue"),
    )
    image = render_blocks(truth, CAMERA, WIDTH, HEIGHT, noise=2.0, rng=rng)
    across = round(wide)
    length = {"left": HEIGHT, "right": HEIGHT, "top": WIDTH, "bottom": WIDTH}[edge]
    first = round(start * length)
    stretch = slice(first, min(length, first + round(long * length)))
    if edge == "left":
        _paint(image, stretch, slice(0, across), "wood", rng)
    elif edge == "right":
        _paint(image, stretch, slice(WIDTH - across, WIDTH), "wood", rng)
    elif edge == "top":
        _paint(image, slice(0, across), stretch, "wood", rng)
    else:
        _paint(image, slice(HEIGHT - across, HEIGHT), stretch, "wood", rng)
    rejected: list[Rejection] = []
    found = detect_blocks(image, CAMERA, PerceptionSettings(), rejected)
    assert [f.colour for f in found if f.colour == "wood"] == []
    assert len(found) == len(truth)
    for block in truth:
        nearest = min(found, key=lambda f: math.dist((f.x, f.y), (block.x, block.y)))
        assert math.dist((nearest.x, nearest.y), (block.x, block.y)) < 0.001


def _board_with_cables(image: np.ndarray, rng: np.random.Generator) -> None:
    """Paint a wooden board (its grain in light and dark stripes) on the right of
    ``image``, three to six block sides wide and long, with dark cables lying across
    it: squares of a block's size fit between the cables and the board's edge."""
    x0, y0 = int(rng.integers(260, 300)), int(rng.integers(20, 60))
    wide, long = int(rng.integers(120, 180)), int(rng.integers(200, 320))
    period, phase = rng.uniform(3.0, 8.0), rng.uniform(0.0, 2 * math.pi)
    grain = 1 + 0.06 * np.sin(np.arange(wide) / period + phase)
    board = np.asarray(COLOURS["wood"], dtype=float) * grain[None, :, None]
    board = board + rng.normal(0.0, 2.0, (long, wide, 3))
    image[y0 : y0 + long, x0 : x0 + wide] = np.clip(np.rint(board), 0, 255).astype(np.uint8)
    for _ in range(int(rng.integers(3, 7))):
        top = (int(rng.integers(x0, x0 + wide)), y0 - 10)
        bottom = (int(rng.integers(x0, x0 + wide)), y0 + long + 10)
        cv2.line(image, top, bottom, (60, 60, 60), int(rng.integers(2, 5)))


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 10_000))
@example(seed=5)
def test_a_board_crossed_by_cables_is_no_block(seed: int) -> None:
    """A wooden board in the view, crossed by cables (beside mrhan_touching's
    board): squares fitted between the cables and the board's edge cover a small
    part of the board's colour region, which is no block's — no block is reported
    on it, and the blocks on the table are found as without it."""
    rng = np.random.default_rng(seed)
    truth = random_blocks(
        int(rng.integers(1, 3)),
        Camera(1000.0, (0.03, 0.03)),
        200,
        340,
        rng,
        colours=("red", "blue"),
    )
    image = render_blocks(truth, CAMERA, WIDTH, HEIGHT, noise=2.0, rng=rng)
    _board_with_cables(image, rng)
    rejected: list[Rejection] = []
    found = detect_blocks(image, CAMERA, PerceptionSettings(), rejected)
    assert [f for f in found if f.colour == "wood"] == []
    assert len(found) == len(truth)
    for block in truth:
        nearest = min(found, key=lambda f: math.dist((f.x, f.y), (block.x, block.y)))
        assert math.dist((nearest.x, nearest.y), (block.x, block.y)) < 0.001


_FAR_FROM = {  # where the blocks go (a camera's origin, width, height) away from an edge
    "left": (Camera(1000.0, (0.2, 0.07)), 280, 260),
    "right": (Camera(1000.0, (0.02, 0.07)), 280, 260),
    "top": (Camera(1000.0, (0.07, 0.02)), 360, 180),
    "bottom": (Camera(1000.0, (0.07, 0.2)), 360, 180),
}


def _arm_from_the_border(
    image: np.ndarray, edge: str, wide: int, reach: int, centre: float, colour: str, frayed: int
) -> None:
    """Paint an arm of one ``colour`` reaching in from ``edge`` of ``image``: ``wide``
    px across, straight for ``reach`` px, then rounded (a half disc), its middle at
    ``centre`` of the border's length (a robot arm, a sleeve coming into view);
    within ``frayed`` px of the border, every other 4 × 4 px cell of it is left
    unpainted (a paler, glaring part of the arm that is not foreground there)."""
    height, width = image.shape[:2]
    upright = edge in ("left", "right")  # the arm runs along x
    along_x, along_y = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    depth = {"left": along_x, "right": width - along_x, "top": along_y, "bottom": height - along_y}
    place = along_y if upright else along_x
    middle = centre * (height if upright else width)
    off = np.abs(place - middle)
    inside = (off <= wide / 2) & (depth[edge] <= reach)
    inside |= np.hypot(off, depth[edge] - reach) <= wide / 2
    cells = (along_x // 4 + along_y // 4) % 2 == 1
    inside &= ~(cells & (depth[edge] <= frayed))
    tint = np.asarray(COLOURS[colour], dtype=float)
    noise = np.random.default_rng(wide * reach).normal(0.0, 2.0, image.shape)
    image[inside] = np.clip(np.rint(tint + noise), 0, 255).astype(np.uint8)[inside]


@settings(max_examples=12, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 10_000),
    edge=st.sampled_from(("left", "right", "top", "bottom")),
    wide=st.integers(100, 160),
    reach=st.integers(10, 60),
    centre=st.floats(0.3, 0.7),
    colour=st.sampled_from(("green", "blue", "yellow")),
    frayed=st.integers(0, 8),
)
# a square whose side lies on the border (0.4 px in), free on one of its three seen
# sides and at two corners where the arm's rounded end turns away
@example(seed=0, edge="left", wide=100, reach=55, centre=0.5, colour="green", frayed=1)
# a square 4 px in from the border, its side there on the arm's frayed band (no mask)
@example(seed=0, edge="left", wide=101, reach=47, centre=0.5, colour="green", frayed=5)
def test_an_arm_reaching_in_from_the_border_is_no_block(
    seed: int, edge: str, wide: int, reach: int, centre: float, colour: str, frayed: int
) -> None:
    """An arm of one colour reaching in from the border, wider than the largest block
    (the robot arm of langtable_real, a pale panel at the top of the photograph): a
    square fitted into it along the border has the arm running on beside it there
    (frayed along the border or not) and its side on the border shows no table — no
    block's top shows whole. No block is reported in it; the red blocks away from it
    are found as without it."""
    _no_block_in_the_arm(seed, edge, wide, reach, centre, colour, frayed)


def test_an_arm_barely_wider_than_a_block_frayed_at_the_border_is_no_block() -> None:
    """A draw of the property above (found at 100 examples with --hypothesis-seed=3):
    the family's narrowest arm, frayed deepest. It failed — an 88 px square in the
    100 px arm, misfit 0.198, the arm running on only 11 px beside it — until the
    vote's side bins grew with the side (no block is reported in the arm since)."""
    _no_block_in_the_arm(0, "left", 100, 53, 0.5, "green", 5)


def _no_block_in_the_arm(
    seed: int, edge: str, wide: int, reach: int, centre: float, colour: str, frayed: int
) -> None:
    rng = np.random.default_rng(seed)
    camera, width, height = _FAR_FROM[edge]
    truth = random_blocks(int(rng.integers(1, 3)), camera, width, height, rng, colours=("red",))
    image = render_blocks(truth, CAMERA, WIDTH, HEIGHT, noise=2.0, rng=rng)
    _arm_from_the_border(image, edge, wide, reach, centre, colour, frayed)
    found = detect_blocks(image, CAMERA)
    assert [f.colour for f in found if f.colour != "red"] == []
    assert len(found) == len(truth)
    for block in truth:
        nearest = min(found, key=lambda f: math.dist((f.x, f.y), (block.x, block.y)))
        assert math.dist((nearest.x, nearest.y), (block.x, block.y)) < 0.001


def _fill_square(
    image: np.ndarray, x: float, y: float, yaw: float, side: float, rgb: np.ndarray
) -> None:
    """Fill a square (centre ``x``, ``y`` in px, x right, y down; ``yaw`` counter-
    clockwise with y up; ``side`` px) of ``image`` with ``rgb``, anti-aliased."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    h = side / 2
    corners = [
        (x + c * a - s * b, y - (s * a + c * b)) for a, b in ((-h, -h), (h, -h), (h, h), (-h, h))
    ]
    points = np.rint(np.array(corners) * 16).astype(np.int32)
    colour = tuple(float(v) for v in np.clip(rgb, 0, 255))
    cv2.fillPoly(image, [points], colour, cv2.LINE_AA, shift=4)


@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    side=st.floats(30.0, 70.0),
    inside=st.floats(0.55, 1.0),
    yaw=st.floats(-10.0, 10.0),
)
@example(seed=8, side=68.24, inside=0.64, yaw=6.57)
def test_a_block_cut_by_the_border_is_found(
    seed: int, side: float, inside: float, yaw: float
) -> None:
    """A block alone at the left border, ``inside`` of its top in view (the rest
    past the border): the border rules above (its side there not free, its region
    looked at along the border) leave it a block — nothing runs on beside it along
    the border. It is found, at its centre. (A square fitted inside it, smaller and
    past the border too, is the piece its region runs on beyond.)"""
    rng = np.random.default_rng(seed)
    x, y = inside * side - side / 2, float(rng.uniform(100, 300))
    image = np.empty((HEIGHT, WIDTH, 3), dtype=float)
    image[:] = (128, 128, 128)
    _fill_square(image, x, y, yaw, side, np.asarray(COLOURS["red"], dtype=float))
    image += rng.normal(0.0, 2.0, image.shape)
    found = detect_blocks(np.clip(np.rint(image), 0, 255).astype(np.uint8), CAMERA)
    assert len(found) == 1, [(f.colour, f.x, f.y, f.side) for f in found]
    assert math.dist((found[0].x * 1000 - 0.5, HEIGHT - found[0].y * 1000 - 0.5), (x, y)) < 3.0


_TABLES = {"blue": (62, 96, 150), "green": (70, 120, 80)}  # coloured table tops (RGB)


@settings(max_examples=12, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    table=st.sampled_from(sorted(_TABLES)),
    light=st.floats(0.45, 0.8),
    away=st.floats(0.95, 1.2),
)
def test_a_cube_s_shadow_on_a_coloured_table_is_no_block(
    seed: int, table: str, light: float, away: float
) -> None:
    """On a coloured table top (blue, green) a cube's shadow is the table's colour,
    darker, and so differs from the table in chroma too (it is foreground, unlike
    a shadow on a grey board); beside the cube (a low light: a square about a side
    away) it is as square as the cube. It is no block (the ``side_faces`` and
    ``tilted`` families' false blocks on the blue table); the cubes are found."""
    rng = np.random.default_rng(seed)
    truth = random_blocks(
        int(rng.integers(1, 4)),
        Camera(1000.0, (0.08, 0.08)),
        340,
        240,
        rng,
        sides=(0.035, 0.05),
        gap=0.06,
        colours=("red", "yellow"),
    )
    image = np.empty((HEIGHT, WIDTH, 3), dtype=float)
    image[:] = _TABLES[table]
    towards = math.radians(float(rng.uniform(0.0, 360.0)))
    for block in truth:  # shadows first, the cubes over them
        x, y = block.x * 1000 - 0.5, HEIGHT - block.y * 1000 - 0.5
        side = block.side * 1000
        sx, sy = x + away * side * math.cos(towards), y - away * side * math.sin(towards)
        _fill_square(image, sx, sy, block.yaw, side, np.asarray(_TABLES[table]) * light)
    for block in truth:
        x, y = block.x * 1000 - 0.5, HEIGHT - block.y * 1000 - 0.5
        _fill_square(image, x, y, block.yaw, block.side * 1000, np.asarray(COLOURS[block.colour]))
    image += rng.normal(0.0, 2.0, image.shape)
    found = detect_blocks(np.clip(np.rint(image), 0, 255).astype(np.uint8), CAMERA)
    assert len(found) == len(truth), [(f.colour, f.x, f.y) for f in found]
    for block in truth:
        nearest = min(found, key=lambda f: math.dist((f.x, f.y), (block.x, block.y)))
        assert math.dist((nearest.x, nearest.y), (block.x, block.y)) < 0.001


@settings(max_examples=12, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    colour=st.sampled_from(("red", "green", "blue", "yellow")),
    light=st.floats(0.35, 0.65),
    towards=st.integers(0, 3),
)
def test_a_side_face_as_large_as_its_top_is_no_block(
    seed: int, colour: str, light: float, towards: int
) -> None:
    """A camera low and off to the side sees a cube's side face nearly as large as
    its top, beside it: the top's colour, darker (lit less). Were it taken for a cube
    of its own, it would be a block beside the top, one side away (the
    ``side_faces`` family's false blocks); it is no block, and the top is found."""
    rng = np.random.default_rng(seed)
    side = float(rng.uniform(40.0, 55.0))
    x, y, yaw = (
        float(rng.uniform(150, 350)),
        float(rng.uniform(130, 270)),
        float(rng.uniform(-40, 40)),
    )
    image = np.empty((HEIGHT, WIDTH, 3), dtype=float)
    image[:] = (128, 128, 128)
    rgb = np.asarray(COLOURS[colour], dtype=float)
    turn = math.radians(yaw + 90.0 * towards)
    face_x, face_y = x + side * math.cos(turn), y - side * math.sin(turn)
    _fill_square(image, face_x, face_y, yaw, side, rgb * light)
    _fill_square(image, x, y, yaw, side, rgb)
    image += rng.normal(0.0, 2.0, image.shape)
    found = detect_blocks(np.clip(np.rint(image), 0, 255).astype(np.uint8), CAMERA)
    assert len(found) == 1, [(f.colour, f.x, f.y, f.side) for f in found]
    assert math.dist((found[0].x * 1000 - 0.5, HEIGHT - found[0].y * 1000 - 0.5), (x, y)) < 1.0


@settings(max_examples=12, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    colour=st.sampled_from(("red", "green", "blue", "yellow")),
    light=st.floats(0.15, 0.3),
    reach=st.floats(1.0, 1.6),
    towards=st.floats(0.0, 360.0),
)
def test_a_top_beside_side_faces_larger_than_itself_is_found(
    seed: int, colour: str, light: float, reach: float, towards: float
) -> None:
    """A camera low and far off to the side (the ``side_faces`` family: 0.45 m up, its
    axis beyond the image) sees a cube's side faces swept ``reach`` of a side towards
    it, larger than the top together: two faces of the top's colour lit less
    (``light`` and a tenth more), left in the top's colour region when they are not
    told apart by lightness there. The top covers under half of that region, yet it
    is no larger thing's piece: its side faces are darker than it by more than the
    side-face gap and count as explained. One block, found as the issue scores a top
    (its centre within 0.6 of the side of the top's centre; the region's own centre
    lies half a side or more off it): the faces left in its mask may pull its fit —
    a dark blue face swept 1.5 sides took a 47 px top's square to 64 px, 6 px off."""
    rng = np.random.default_rng(seed)
    side = float(rng.uniform(40.0, 55.0))
    x, y = float(rng.uniform(170, 330)), float(rng.uniform(150, 250))
    yaw = float(rng.uniform(-45, 45))
    image = np.empty((HEIGHT, WIDTH, 3), dtype=float)
    image[:] = (128, 128, 128)
    rgb = np.asarray(COLOURS[colour], dtype=float)
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    h = side / 2
    corners = np.array(
        [(x + c * a - s * b, y - (s * a + c * b)) for a, b in ((-h, -h), (h, -h), (h, h), (-h, h))]
    )
    turn = math.radians(towards)
    sweep = reach * side * np.array([math.cos(turn), -math.sin(turn)])
    shades = iter((light, 1.1 * light))
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        outward = np.array([b[1] - a[1], a[0] - b[0]])  # y down: clockwise on screen
        if outward @ (np.array([x, y]) - (a + b) / 2) > 0:
            outward = -outward
        if outward @ sweep <= 0:
            continue  # a face turned away from the camera
        quad = np.rint(np.array([a, b, b + sweep, a + sweep]) * 16).astype(np.int32)
        shade = next(shades)
        cv2.fillPoly(image, [quad], tuple(float(v) for v in rgb * shade), cv2.LINE_AA, shift=4)
    _fill_square(image, x, y, yaw, side, rgb)
    image += rng.normal(0.0, 2.0, image.shape)
    found = detect_blocks(np.clip(np.rint(image), 0, 255).astype(np.uint8), CAMERA)
    assert len(found) == 1, [(f.colour, f.x, f.y, f.side) for f in found]
    centre = (found[0].x * 1000 - 0.5, HEIGHT - found[0].y * 1000 - 0.5)
    assert math.dist(centre, (x, y)) < FOUND_WITHIN * side


def _fill_rectangle(
    image: np.ndarray, corner: tuple[float, float], far: tuple[float, float], rgb: np.ndarray
) -> None:
    """Fill the upright rectangle from ``corner`` to ``far`` (px, x right, y down) of
    ``image`` with ``rgb``, anti-aliased."""
    (x0, y0), (x1, y1) = corner, far
    points = np.rint(np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)]) * 16).astype(np.int32)
    cv2.fillPoly(image, [points], tuple(float(v) for v in rgb), cv2.LINE_AA, shift=4)


@settings(max_examples=8, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    colour=st.sampled_from(("red", "green", "blue", "yellow")),
    grain=st.floats(0.12, 0.2),
    wide=st.floats(0.3, 0.6),
)
def test_a_grained_top_beside_its_side_face_is_found_whole(
    seed: int, colour: str, grain: float, wide: float
) -> None:
    """A cube's top whose paint is grained (wood grain, brush strokes: mrhan_phone's
    purple cube) — a third of its columns ``grain`` darker, less than the side-face
    gap of 12 L* (a darker grain is a second lightness mode: a side face) — beside
    its side face (its colour at half the light, ``wide`` of a side across: a phone
    held at an angle). The side face drops out of the top's mask by lightness, the grain does
    not (the mask is full from the lower quartile of the top's lightness, not its
    median): one block, at the top's centre, of the top's side."""
    rng = np.random.default_rng(seed)
    side = float(rng.uniform(40.0, 55.0))
    x, y = float(rng.uniform(150, 350)), float(rng.uniform(130, 270))
    image = np.empty((HEIGHT, WIDTH, 3), dtype=float)
    image[:] = (128, 128, 128)
    rgb = np.asarray(COLOURS[colour], dtype=float)
    left, top, right, bottom = x - side / 2, y - side / 2, x + side / 2, y + side / 2
    _fill_rectangle(image, (left - wide * side, top), (left, bottom), rgb * 0.5)
    face = np.zeros((HEIGHT, WIDTH), dtype=float)
    _fill_rectangle(face, (left, top), (right, bottom), np.array([1.0]))
    streaks = np.where(rng.random(WIDTH) < 1 / 3, 1.0 - grain, 1.0)
    grained = rgb[None, None, :] * streaks[None, :, None]
    image = image * (1.0 - face[..., None]) + grained * face[..., None]
    image += rng.normal(0.0, 2.0, image.shape)
    found = detect_blocks(np.clip(np.rint(image), 0, 255).astype(np.uint8), CAMERA)
    assert len(found) == 1, [(f.colour, f.x, f.y, f.side) for f in found]
    assert math.dist((found[0].x * 1000 - 0.5, HEIGHT - found[0].y * 1000 - 0.5), (x, y)) < 1.5
    assert abs(found[0].side * 1000 - side) < 2.0


@settings(max_examples=8, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    light=st.floats(0.55, 0.75),
    corner=st.sampled_from(((1, 1), (1, -1), (-1, 1), (-1, -1))),
)
def test_a_light_square_in_a_shadowed_patch_of_its_colour_is_no_block(
    seed: int, light: float, corner: tuple[int, int]
) -> None:
    """A wooden table patch between dark things, most of it in shadow (``light`` of
    the lit wood's light: 12 L* darker and more) and a lit square of it at one corner
    (mrhan_touching, right): the square covers a fifth of the patch or less, too
    little to be a cube's top however low the camera (its side faces would cover
    more than four tops), so the shadowed wood is not taken for its side faces and
    the patch is no block. The block beside it is found."""
    rng = np.random.default_rng(seed)
    side = float(rng.uniform(36.0, 46.0))
    image = np.empty((HEIGHT, WIDTH, 3), dtype=float)
    image[:] = (128, 128, 128)
    wood = np.asarray((190.0, 140.0, 90.0))
    x0, y0 = float(rng.uniform(160, 220)), float(rng.uniform(130, 170))
    patch = (x0 - 2.5 * side, y0 - 2.2 * side), (x0 + 2.5 * side, y0 + 2.2 * side)
    _fill_rectangle(image, *patch, wood * light)
    (left, top), (right, bottom) = patch
    cx = left + side / 2 if corner[0] < 0 else right - side / 2
    cy = top + side / 2 if corner[1] < 0 else bottom - side / 2
    _fill_square(image, cx, cy, 0.0, side, wood)
    block = (420.0, 80.0)
    _fill_square(image, *block, 10.0, 40.0, np.asarray(COLOURS["blue"], dtype=float))
    image += rng.normal(0.0, 2.0, image.shape)
    found = detect_blocks(np.clip(np.rint(image), 0, 255).astype(np.uint8), CAMERA)
    assert len(found) == 1, [(f.colour, f.x * 1000, HEIGHT - f.y * 1000, f.side) for f in found]
    assert math.dist((found[0].x * 1000 - 0.5, HEIGHT - found[0].y * 1000 - 0.5), block) < 1.5
