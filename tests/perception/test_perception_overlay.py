"""``demoplan perceive --plot`` and ``--colours`` (issue 30, docs/perception.md
"Overlays" and "Colour names"): the overlay shows the blocks found (their
outline through the true corners, name and yaw) and the regions rejected with
why, on the input image — a top view or, through the calibration, an oblique
photograph; the rejections are in the result, not in the scene; ``-o`` and
``--plot`` are written together or not at all; a palette file names a block
of a colour the built-in palette does not know, and a hostile palette file is
one error line naming the file and the field."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.commands.perception import perceive
from demoplan.perception.blocks import PerceptionSettings, Rejection, detect_blocks
from demoplan.perception.calibrated import perceive_photograph
from demoplan.perception.calibration import MarkerLayout, calibrate
from demoplan.perception.camera import Camera, load_image, save_image
from demoplan.perception.images import perceive_top_view
from demoplan.perception.opencv import cv2
from demoplan.perception.overlay import (
    FOUND_COLOUR,
    REJECTED_COLOUR,
    is_speck,
    speck_side,
    square_corners,
)
from demoplan.perception.photos import PhotoRig, render_photo, top_camera
from demoplan.perception.pinhole import PinholeCamera, render_table
from demoplan.perception.synthetic import COLOURS, SyntheticBlock, render_blocks
from tests.support.cli import invoke

CAMERA = Camera(1000.0, (0.0, 0.0))  # 1 px = 1 mm
SIDE = 0.04
BLOCKS = [
    SyntheticBlock("red", 0.10, 0.10, 10.0, SIDE),
    SyntheticBlock("blue", 0.30, 0.22, -25.0, SIDE),
]


def pixel(camera: Camera, height: int, x: float, y: float) -> tuple[float, float]:
    """World (x, y) → image (column, row), pixel centres at whole numbers."""
    u, v = camera.to_pixels(x, y)
    return u - 0.5, height - v - 0.5


def near_colour(
    image: np.ndarray, point: tuple[float, float], colour: tuple[int, int, int], reach: int = 2
) -> bool:
    """Is a pixel within ``reach`` of ``point`` (column, row) drawn in ``colour``?"""
    col, row = round(point[0]), round(point[1])
    patch = image[
        max(0, row - reach) : row + reach + 1, max(0, col - reach) : col + reach + 1
    ].astype(int)
    return bool((np.abs(patch - np.array(colour)).max(axis=2) <= 40).any())


def with_distractors(image: np.ndarray) -> np.ndarray:
    """``image`` (a 500 × 400 top view, 1 px = 1 mm) with a small red patch at
    (0.40, 0.08) and a green disc 50 mm across at (0.12, 0.30)."""
    painted = image.copy()
    height = painted.shape[0]
    cv2.circle(painted, (400, height - 80), 5, COLOURS["red"], -1)  # 80 px: under a block
    cv2.circle(painted, (120, height - 300), 25, COLOURS["green"], -1, cv2.LINE_AA)
    return painted


def test_the_overlay_is_written_the_input_size_through_the_true_corners(tmp_path: Path) -> None:
    image = render_blocks(BLOCKS, CAMERA, width=500, height=400, rng=1)
    save_image(image, tmp_path / "top.png")
    result = invoke(
        "perceive", tmp_path / "top.png", "--px-per-m", "1000", "--origin", "0", "0",
        "--plot", tmp_path / "overlay.png", "-o", tmp_path / "scene.json",
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert "0 regions rejected (drawn in overlay.png)" in result.stdout
    overlay = load_image(tmp_path / "overlay.png")
    assert overlay.shape == image.shape
    for block in BLOCKS:
        for x, y in square_corners(block.x, block.y, block.yaw, block.side):
            assert near_colour(overlay, pixel(CAMERA, 400, x, y), FOUND_COLOUR, reach=1)
        # the block's middle is left as it was
        col, row = (round(c) for c in pixel(CAMERA, 400, block.x, block.y + 0.01))
        assert np.abs(overlay[row, col].astype(int) - image[row, col]).max() <= 1
    assert (overlay[5:40, 420:495] == image[5:40, 420:495]).all()  # nothing drawn far away
    assert set(json.loads((tmp_path / "scene.json").read_text())["objects"]) == {"red", "blue"}


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    x=st.floats(0.05, 0.45),
    y=st.floats(0.05, 0.35),
    yaw=st.floats(-45.0, 45.0),
    colour=st.sampled_from(["red", "green", "blue", "yellow", "wood"]),
)
def test_a_block_anywhere_is_outlined_through_its_corners(
    x: float, y: float, yaw: float, colour: str, tmp_path_factory: pytest.TempPathFactory
) -> None:
    folder = tmp_path_factory.mktemp("anywhere")
    block = SyntheticBlock(colour, x, y, yaw, SIDE)
    save_image(render_blocks([block], CAMERA, width=500, height=400, rng=2), folder / "top.png")
    seen = perceive_top_view(folder / "top.png", 1000.0, (0.0, 0.0), side=SIDE, overlay=True)
    assert seen.overlay is not None and seen.overlay.shape == (400, 500, 3)
    for cx, cy in square_corners(x, y, yaw, SIDE):
        assert near_colour(seen.overlay, pixel(CAMERA, 400, cx, cy), FOUND_COLOUR, reach=1)


def test_a_small_patch_and_a_disc_are_rejected_with_why(tmp_path: Path) -> None:
    image = with_distractors(render_blocks(BLOCKS, CAMERA, width=500, height=400, rng=3))
    save_image(image, tmp_path / "top.png")
    found = perceive(
        tmp_path / "top.png", 1000.0, (0.0, 0.0), side=SIDE, plot=tmp_path / "overlay.png"
    )
    assert set(found.blocks) == {"red", "blue"}
    assert "rejected" not in json.dumps(found.document)  # the scene is unchanged
    assert all(r.reason != "covered" for r in found.rejected)

    def at(x: float, y: float) -> list[Rejection]:
        return [
            r
            for r in found.rejected
            if any(
                cv2.pointPolygonTest(np.array(o, dtype=np.float32), (x, y), False) >= 0
                for o in r.outlines
            )
        ]

    (patch,) = at(0.40, 0.08)
    assert patch.reason == "too small"
    (disc,) = at(0.12, 0.30)
    assert (disc.reason, disc.colour) == ("not square", "green")
    assert disc.detail.startswith("misfit ")
    (outline,) = disc.outlines
    assert all(abs(math.dist(p, (0.12, 0.30)) - 0.025) < 0.003 for p in outline)
    overlay = load_image(tmp_path / "overlay.png")
    assert overlay.shape == image.shape
    for x, y in outline:
        assert near_colour(overlay, pixel(CAMERA, 400, x, y), REJECTED_COLOUR)
    # the detector alone reports the same
    rejected: list[Rejection] = []
    settings_ = PerceptionSettings(min_side=0.85 * SIDE, max_side=1.15 * SIDE)
    assert len(detect_blocks(image, CAMERA, settings_, rejected)) == 2
    assert sorted(r.reason for r in rejected) == sorted(r.reason for r in found.rejected)


def test_the_cli_says_what_was_rejected_in_one_line(tmp_path: Path) -> None:
    image = with_distractors(render_blocks(BLOCKS, CAMERA, width=500, height=400, rng=3))
    save_image(image, tmp_path / "top.png")
    result = invoke(
        "perceive", tmp_path / "top.png", "--px-per-m", "1000", "--origin", "0", "0",
        "--side", "0.04", "--plot", tmp_path / "overlay.png",
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert (
        "2 regions rejected: 1 not square, 1 too small (drawn in overlay.png; 1 speck not "
        "drawn)" in result.stdout
    )
    assert (tmp_path / "overlay.png").is_file()


SPECKS = [
    (0.03 + 0.04 * i, 0.03 + 0.04 * j)
    for i in range(12)
    for j in range(9)
    if all(math.dist((0.03 + 0.04 * i, 0.03 + 0.04 * j), c) > 0.05 for c in
           [(b.x, b.y) for b in BLOCKS] + [(0.45, 0.35)])
]  # fmt: skip
"""Places of specks 10 mm across: listed as too small (over a tenth of the
smallest block's 0.3 area), under a ninth of a 40 mm block's top."""


def with_specks(image: np.ndarray, px_per_m: float) -> np.ndarray:
    """``image`` with a red speck 10 mm across at each of :data:`SPECKS`, and a
    red patch 20 mm square at (0.45, 0.35): a quarter of a 40 mm block's top,
    more than a speck."""
    painted = image.copy()
    height = painted.shape[0]
    for x, y in SPECKS:
        centre = (round(x * px_per_m), round(height - y * px_per_m))
        cv2.circle(painted, centre, round(0.005 * px_per_m), COLOURS["red"], -1)
    corner = (round(0.44 * px_per_m), round(height - 0.36 * px_per_m))
    far = (round(0.46 * px_per_m), round(height - 0.34 * px_per_m))
    cv2.rectangle(painted, corner, far, COLOURS["red"], -1)
    return painted


@pytest.mark.parametrize("px_per_m", [1000.0, 2000.0])
def test_specks_are_counted_not_drawn_whatever_the_resolution(
    tmp_path: Path, px_per_m: float
) -> None:
    """mrhan_stacks' overlay drew 865 "too small" parts, which buried the
    rejections that matter: a rejected part under a ninth of a block's top
    (its size relative to the blocks found, not in pixels) is not drawn, and
    the overlay's legend and the command's line count them. The same table
    photographed at twice the resolution gives the same count."""
    camera = Camera(px_per_m, (0.0, 0.0))
    width, height = round(0.5 * px_per_m), round(0.4 * px_per_m)
    image = with_specks(render_blocks(BLOCKS, camera, width=width, height=height, rng=3), px_per_m)
    save_image(image, tmp_path / "top.png")
    result = invoke(
        "perceive", tmp_path / "top.png", "--px-per-m", px_per_m, "--origin", "0", "0",
        "--side", "0.04", "--plot", tmp_path / "overlay.png",
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    line = result.stdout.strip().splitlines()[-1]
    specks = int(line.split("; ")[-1].split(" ")[0])
    assert specks >= len(SPECKS), line
    overlay = load_image(tmp_path / "overlay.png")
    for x, y in SPECKS:  # a speck's place is left as it was: no outline, no label
        rim = pixel(camera, height, x + 0.005, y)
        assert not near_colour(overlay, rim, REJECTED_COLOUR, reach=1), (x, y)
    # the patch, a quarter of a top, is outlined; the legend is at the bottom left
    assert near_colour(overlay, pixel(camera, height, 0.44, 0.36), REJECTED_COLOUR, 3)
    legend = overlay[height - round(0.03 * px_per_m) :, : round(0.25 * px_per_m)]
    assert (np.abs(legend.astype(int) - REJECTED_COLOUR).max(axis=2) <= 40).sum() > 50
    counts = {}
    for scale in (1000.0, 2000.0):
        cam = Camera(scale, (0.0, 0.0))
        w, h = round(0.5 * scale), round(0.4 * scale)
        picture = with_specks(render_blocks(BLOCKS, cam, width=w, height=h, rng=3), scale)
        save_image(picture, tmp_path / f"at-{scale:g}.png")
        found = perceive_top_view(tmp_path / f"at-{scale:g}.png", scale, (0.0, 0.0), side=SIDE)
        side = speck_side([b.side for b in found.blocks.values()])
        counts[scale] = sum(is_speck(r, side) for r in found.rejected)
    assert counts[1000.0] == counts[2000.0] == specks


def test_a_side_face_is_rejected_at_its_cubes_edge() -> None:
    """A cube far off the camera's axis shows side faces, of its colour but
    darker: they are reported as rejected, along the edge of the cube's top."""
    rig = PhotoRig(nadir_px=(1200.0, 680.0))  # the camera above the top-right corner
    x0, y0, _, _ = rig.table_extent()
    cube = SyntheticBlock("yellow", x0 + 0.12, y0 + 0.12, 20.0, SIDE)
    rejected: list[Rejection] = []
    settings_ = PerceptionSettings(min_side=0.85 * SIDE, max_side=1.15 * SIDE)
    image = render_photo([cube], rig, rng=5, highlight=0.0)
    (seen,) = detect_blocks(image, top_camera(rig, SIDE), settings_, rejected)
    assert math.dist((seen.x, seen.y), (cube.x, cube.y)) < 0.002
    (face,) = [r for r in rejected if r.reason == "side face"]  # one record per cube
    assert face.colour == "yellow"
    for piece in face.outlines:
        middle = np.mean(piece, axis=0)
        assert 0.008 < math.dist(middle, (cube.x, cube.y)) < 0.03  # at an edge, not inside


def test_an_oblique_photo_is_outlined_at_its_top_faces(tmp_path: Path) -> None:
    """Calibrated by markers: the outlines go back through the homography (on the
    plane of the top faces) onto the photograph, through the top faces' true
    corners as the pinhole camera sees them."""
    markers = {0: (0.0, 0.0), 1: (0.3, 0.0), 2: (0.3, 0.2), 3: (0.0, 0.2)}
    layout = MarkerLayout("DICT_4X4_50", 0.04, {k: (x, y, 0.0) for k, (x, y) in markers.items()})
    view = PinholeCamera.looking_at(
        (0.15, 0.1), tilt=25.0, heading=-60.0, distance=0.6, focal=560.0
    )
    blocks = [
        SyntheticBlock("red", 0.08, 0.07, 10.0, SIDE),
        SyntheticBlock("green", 0.2, 0.05, 0.0, SIDE),
    ]
    image = render_table(view, blocks, markers, marker_side=0.04, rng=1)
    save_image(image, tmp_path / "view.png")
    seen = perceive_photograph(
        tmp_path / "view.png", calibrate(image, layout), side=SIDE, overlay=True
    )
    assert sorted(seen.blocks) == ["green", "red"]
    assert seen.overlay is not None and seen.overlay.shape == image.shape
    for block in blocks:
        corners = square_corners(block.x, block.y, block.yaw, SIDE)
        tops = view.project(np.c_[corners, np.full(4, SIDE)])
        for corner in tops:
            assert near_colour(seen.overlay, (corner[0], corner[1]), FOUND_COLOUR, reach=2)


@pytest.mark.parametrize(
    ("content", "extra", "code"),
    [
        # the time budget spent (exit 4): nothing drawn, nothing written
        ("blocks", ["--timeout", "0"], 4),
        ("blocks", ["-o", "{out}/same.png", "--plot", "{out}/same.png"], 2),
        ("blocks", ["--plot", "{out}/top.png"], 1),  # would overwrite the input
        # the picture cannot be written (its name is a folder): the scene is not either
        ("blocks", ["-o", "{out}/scene.json", "--plot", "{out}/sub"], 1),
    ],
)
def test_a_failing_perceive_writes_neither_file(
    tmp_path: Path, content: str, extra: list[str], code: int
) -> None:
    blocks = BLOCKS if content == "blocks" else []
    save_image(render_blocks(blocks, CAMERA, width=500, height=400, rng=1), tmp_path / "top.png")
    (tmp_path / "sub").mkdir()
    before = sorted(p.name for p in tmp_path.iterdir())
    options = [e.format(out=tmp_path) for e in extra]
    if not any(o in options for o in ("-o", "--plot")):
        options += ["-o", str(tmp_path / "scene.json"), "--plot", str(tmp_path / "overlay.png")]
    result = invoke(
        "perceive", tmp_path / "top.png", "--px-per-m", "1000", "--origin", "0", "0", *options
    )
    assert result.exit_code == code, result.output
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("demoplan: error: ")
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_no_blocks_found_writes_the_overlay_alone_never_the_scene(tmp_path: Path) -> None:
    """Exit 1, "no blocks found": the overlay of what was rejected and why is its
    diagnosis, so it is written — alone: the scene (-o) is not, there being no
    scene; the one line says where the picture is. Before, neither was written
    and the user could not see why nothing was found."""
    blank = render_blocks([], CAMERA, width=500, height=400, rng=1)
    save_image(with_distractors(blank), tmp_path / "top.png")
    overlay, scene = tmp_path / "overlay.png", tmp_path / "scene.json"
    result = invoke(
        "perceive", tmp_path / "top.png", "--px-per-m", "1000", "--origin", "0", "0",
        "-o", scene, "--plot", overlay,
    )  # fmt: skip
    assert result.exit_code == 1, result.output
    (line,) = result.stderr.splitlines()
    assert "no blocks found" in line and f"drawn in {overlay}" in line
    assert not scene.exists()
    drawn = load_image(overlay)
    assert drawn.shape == blank.shape
    # the small patch and the disc, rejected, are outlined in magenta
    assert near_colour(drawn, pixel(CAMERA, 400, 0.12, 0.30 + 0.025), REJECTED_COLOUR, 4)
    assert not any(p.name.endswith(".tmp") for p in tmp_path.iterdir())


def test_no_blocks_found_without_plot_writes_nothing(tmp_path: Path) -> None:
    save_image(render_blocks([], CAMERA, width=500, height=400, rng=1), tmp_path / "top.png")
    result = invoke(
        "perceive", tmp_path / "top.png", "--px-per-m", "1000", "--origin", "0", "0",
        "-o", tmp_path / "scene.json",
    )  # fmt: skip
    assert result.exit_code == 1 and "no blocks found" in result.stderr
    assert "drawn in" not in result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["top.png"]


def pink_picture(folder: Path) -> tuple[Path, Camera]:
    """A photo-like render of one block in pink, a colour the palette has not."""
    rig = PhotoRig()
    COLOURS["pink"] = (240, 150, 200)
    try:
        image = render_photo([SyntheticBlock("pink", 0.3, 0.2, 10.0, SIDE)], rig, rng=1)
    finally:
        del COLOURS["pink"]
    save_image(image, folder / "pink.png")
    return folder / "pink.png", top_camera(rig, SIDE)


def test_colours_names_a_block_of_a_new_colour(tmp_path: Path) -> None:
    picture, camera = pink_picture(tmp_path)
    palette = tmp_path / "colours.json"
    palette.write_text('{"pink": [240, 150, 200], "teal": [20, 128, 128]}')
    scale = ["--px-per-m", f"{camera.px_per_m}", "--origin", *map(str, camera.origin)]
    plain = invoke("perceive", picture, *scale, "--side", "0.04", "--json")
    assert plain.exit_code == 0, plain.stderr
    assert list(json.loads(plain.stdout)["objects"]) == ["block1"]
    named = invoke("perceive", picture, *scale, "--side", "0.04", "--json", "--colours", palette)
    assert named.exit_code == 0, named.stderr
    assert list(json.loads(named.stdout)["objects"]) == ["pink"]


def test_colours_and_plot_on_a_calibrated_photograph(tmp_path: Path) -> None:
    """``--markers`` with ``--colours`` and ``--plot``: a pink cube in an oblique
    photograph is named pink, and the overlay is the photograph's size."""
    from tests.support.helpers import EXAMPLES

    view = PinholeCamera.looking_at(
        (0.15, 0.1), tilt=20.0, heading=-60.0, distance=0.6, focal=560.0
    )
    markers = {0: (0.0, 0.0), 1: (0.3, 0.0), 2: (0.3, 0.2), 3: (0.0, 0.2)}
    COLOURS["pink"] = (240, 150, 200)
    try:
        cube = SyntheticBlock("pink", 0.15, 0.1, 10.0, SIDE)
        image = render_table(view, [cube], markers, marker_side=0.04, rng=2)
    finally:
        del COLOURS["pink"]
    save_image(image, tmp_path / "view.png")
    result = invoke(
        "perceive", tmp_path / "view.png", "--markers", EXAMPLES / "perception" / "markers.json",
        "--side", "0.04", "--colours", EXAMPLES / "perception" / "colours.json",
        "--plot", tmp_path / "overlay.png", "--json",
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    (pink,) = json.loads(result.stdout)["objects"].items()
    assert pink[0] == "pink"
    assert math.dist(pink[1]["position"][:2], (cube.x, cube.y)) < 0.005
    assert load_image(tmp_path / "overlay.png").shape == image.shape


def test_the_example_palette_file_reads() -> None:
    from demoplan.perception.colours import load_palette
    from tests.support.helpers import EXAMPLES

    palette = load_palette(EXAMPLES / "perception" / "colours.json")
    assert palette and all(max(rgb) == 1.0 for rgb in palette.values())


@pytest.mark.parametrize(
    ("text", "name", "field", "fragment"),
    [
        ("pink: [240, 150, 200", "colours.json", None, "JSON"),  # not JSON
        ('{"pink": [NaN, 150, 200]}', "colours.json", "pink", ""),
        ('{"pink": [240, 150, 256]}', "colours.json", "pink", "0–255"),
        ('{"pink": [240, -1, 200]}', "colours.json", "pink", "0–255"),
        ('{"pink": [0, 0, 0]}', "colours.json", "pink", "not all 0"),
        ('{"pink": [true, 150, 200]}', "colours.json", "pink", "[R, G, B]"),
        ('{"hot pink": [240, 105, 180]}', "colours.json", "hot pink", "letters, digits"),
        ('{"block3": [240, 105, 180]}', "colours.json", "block3", "not starting with 'block'"),
        ('{"": [240, 105, 180]}', "colours.json", None, "colour name"),
        ("{}", "colours.json", None, "a mapping"),
        ("[1, 2, 3]", "colours.json", None, ""),
        (
            json.dumps({f"c{i}": [i % 250 + 1, 100, 100] for i in range(65)}),
            "colours.json",
            None,
            "at most 64",
        ),
        ("pink: [240, 150, 200]\npink: [1, 2, 3]\n", "colours.yaml", None, "twice"),
    ],
)
def test_a_hostile_palette_file_is_one_error_line(
    tmp_path: Path, text: str, name: str, field: str | None, fragment: str
) -> None:
    save_image(render_blocks(BLOCKS, CAMERA, width=500, height=400, rng=1), tmp_path / "top.png")
    palette = tmp_path / name
    palette.write_text(text)
    result = invoke(
        "perceive", tmp_path / "top.png", "--px-per-m", "1000", "--origin", "0", "0",
        "--colours", palette, "-o", tmp_path / "scene.json",
    )  # fmt: skip
    assert result.exit_code == 1, result.output
    line = result.stderr
    assert line.count("\n") == 1 and line.startswith(f"demoplan: error: {palette}")
    if field:
        assert f": {field}:" in line or f": {field}[" in line
    assert fragment in line
    assert not (tmp_path / "scene.json").exists()


def test_a_palette_file_that_is_no_file(tmp_path: Path) -> None:
    save_image(render_blocks(BLOCKS, CAMERA, width=500, height=400, rng=1), tmp_path / "top.png")
    for where, fragment in ((tmp_path / "missing.json", "no such file"), (tmp_path, "folder")):
        result = invoke(
            "perceive", tmp_path / "top.png", "--px-per-m", "1000", "--origin", "0", "0",
            "--colours", where,
        )  # fmt: skip
        assert result.exit_code == 1 and fragment in result.stderr, result.output
