"""The blocks' size from the photograph (demoplan.perception.sizes) and the scale
of a straight-down view from the cubes' size (``perceive --side`` alone)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.commands.perception import perceive
from demoplan.errors import UsageError
from demoplan.perception.camera import Camera, save_image
from demoplan.perception.sizes import SIDE_TOLERANCE, block_sizes
from demoplan.perception.synthetic import SyntheticBlock, render_blocks

COLOURS = ("red", "green", "blue", "yellow")


@settings(max_examples=60, deadline=None)
@given(
    st.floats(10.0, 200.0),
    st.lists(st.floats(-0.05, 0.05), min_size=2, max_size=12),
    st.floats(1.5, 4.0) | st.floats(0.25, 0.6),
)
def test_the_common_size_is_the_most_squares_and_an_odd_one_is_not(
    size: float, spread: list[float], odd: float
) -> None:
    """Two or more sides within 5 % of a size, and one square 1.5–4 times larger or
    smaller: the first block size is within 5 % of the size, and the odd one lies
    more than 15 % outside the block sizes' span."""
    sides = [size * (1 + e) for e in spread] + [size * odd]
    sizes = block_sizes(sides)
    assert abs(sizes[0][0] - size) <= 0.05 * size * (1 + 1e-9)  # 5 %, up to rounding
    low = min(s[1] for s in sizes) * (1 - SIDE_TOLERANCE)
    high = max(s[2] for s in sizes) * (1 + SIDE_TOLERANCE)
    assert not low <= size * odd <= high


def test_two_sizes_of_several_cubes_each_are_both_block_sizes() -> None:
    """A table of 38 mm and 25 mm cubes (the ArmLab photograph): both sizes kept."""
    sides = [38.0, 39.0, 37.5, 38.5, 25.0, 26.0, 24.5]
    assert block_sizes(sides) == ((38.25, 37.5, 39.0), (25.0, 24.5, 26.0))
    assert block_sizes([]) == ()
    assert block_sizes([30.0]) == ((30.0, 30.0, 30.0),)


def _scene(seed: int, side: float, count: int, extent: tuple[float, float]) -> list[SyntheticBlock]:
    """``count`` cubes of ``side`` apart from one another, wholly within a table
    of ``extent`` (m) from the origin."""
    rng = np.random.default_rng(seed)
    placed: list[SyntheticBlock] = []
    margin = side
    while len(placed) < count:
        x = rng.uniform(margin, extent[0] - margin)
        y = rng.uniform(margin, extent[1] - margin)
        if all(math.dist((x, y), (b.x, b.y)) > 2.2 * side for b in placed):
            yaw = float(rng.uniform(-45.0, 45.0))
            placed.append(SyntheticBlock(COLOURS[len(placed)], x, y, yaw, side))
    return placed


@settings(max_examples=5, deadline=None)
@given(st.floats(600.0, 1400.0), st.sampled_from([0.03, 0.04, 0.05]), st.integers(0, 2**16))
def test_the_cubes_size_gives_the_scale_of_a_straight_down_view(
    tmp_path_factory: pytest.TempPathFactory, px_per_m: float, side: float, seed: int
) -> None:
    """A top view of 2–4 cubes at an unknown scale, read with ``--side`` alone: the
    scale found within 1 % of the true one, every cube within a pixel and that
    1 % of its distance from the image's bottom-left corner (the origin) of where
    it is, and the note says so."""
    blocks = _scene(seed, side, 2 + seed % 3, (500 / px_per_m, 400 / px_per_m))  # 500 × 400 px
    image = tmp_path_factory.mktemp("scale") / "top.png"
    save_image(render_blocks(blocks, Camera(px_per_m, (0.0, 0.0)), rng=seed), image)
    found = perceive(image, side=side)
    assert "the cube size" in found.scale
    scale = float(found.scale.split(" px, ")[1].split(" px/m")[0])
    assert abs(scale - px_per_m) <= 0.01 * px_per_m
    assert len(found.blocks) == len(blocks)
    for block in blocks:  # a scale 1 % off moves a point 1 % of its distance from the corner
        reach = 1 / px_per_m + 0.01 * math.hypot(block.x, block.y)
        nearest = min(math.dist((block.x, block.y), (b.x, b.y)) for b in found.blocks.values())
        assert nearest < reach
    assert found.document["description"].endswith(found.scale)


def test_a_block_far_from_the_common_size_is_rejected_with_why(tmp_path: Path) -> None:
    """Three 4 cm cubes and a 6.5 cm block (within the default 2–8 cm), the scale
    known, no ``--side``: the three are blocks, the large one is rejected as not a
    block size."""
    cubes = [
        SyntheticBlock("red", 0.09, 0.10, 20.0, 0.04),
        SyntheticBlock("green", 0.40, 0.08, -10.0, 0.04),
        SyntheticBlock("blue", 0.10, 0.30, 5.0, 0.04),
    ]
    large = SyntheticBlock("wood", 0.30, 0.25, 12.0, 0.065)
    image = tmp_path / "top.png"
    save_image(render_blocks([*cubes, large], Camera(1000.0, (0.0, 0.0)), rng=3), image)
    found = perceive(image, 1000.0, (0.0, 0.0))
    assert sorted(found.blocks) == sorted(c.colour for c in cubes)
    odd = [r for r in found.rejected if r.reason == "not a block size"]
    assert [r.colour for r in odd] == ["wood"]
    assert "side 65 mm, the blocks here 40 mm" in odd[0].detail


def test_a_cube_measured_at_an_odd_size_is_looked_at_again_not_dropped() -> None:
    """Family ``patterned``, seed 0, without ``--side``: the detector fits the
    print on a 40 mm white top as a 24 mm square — its centre right, its size
    not one of the photograph's. Looked at again there at the block sizes, the
    cube is kept at the block size (every top the detector found is still
    found, no block named twice) and nothing is rejected as not a block size.
    (A 65 mm lid among 40 mm cubes is still rejected:
    test_a_block_far_from_the_common_size_is_rejected_with_why.)"""
    from demoplan.perception.blocks import PerceptionSettings, detect_blocks
    from demoplan.perception.image_measures import ImageMeasures
    from demoplan.perception.labelled import score_detections
    from demoplan.perception.photo_families import family_case
    from demoplan.perception.sizes import held_to_sizes, within_sizes

    case = family_case("patterned", 0)
    camera = Camera(case.label.px_per_m, (0.0, 0.0))
    measures = ImageMeasures(case.image)
    found = detect_blocks(case.image, camera, PerceptionSettings(), [], measures)
    sizes = block_sizes([block.side for block in found])
    low, high = within_sizes(sizes)
    odd = [block for block in found if not low <= block.side <= high]
    assert odd  # the print's square, or the case no longer shows what it is for
    kept, rejected = held_to_sizes(found, sizes, seen=(measures, camera))
    before = score_detections(case.label, [(b.x, b.y) for b in found])
    after = score_detections(case.label, [(b.x, b.y) for b in kept])
    assert after.found == before.found
    assert after.false <= before.false
    assert all(low <= block.side <= high for block in kept)
    assert len({block.name for block in kept}) == len(kept)
    assert not [r for r in rejected if r.reason == "not a block size"]


def test_neither_a_scale_nor_the_cubes_size_is_one_line_and_exit_2(tmp_path: Path) -> None:
    image = tmp_path / "top.png"
    save_image(
        render_blocks(_scene(1, 0.04, 2, (0.5, 0.4)), Camera(1000.0, (0.0, 0.0)), rng=1), image
    )
    with pytest.raises(UsageError, match="--side"):
        perceive(image)
    result = CliRunner().invoke(app, ["perceive", str(image)])
    assert result.exit_code == 2
    assert "how pixels map to the table is needed" in result.output
    assert "--side" in result.output
    shown = CliRunner().invoke(app, ["perceive", str(image), "--side", "0.04"])
    assert shown.exit_code == 0, shown.output
    assert "scale from the cube size: --side 0.04 m is" in shown.output
    given_scale = CliRunner().invoke(
        app, ["perceive", str(image), "--px-per-m", "1000", "--origin", "0", "0"]
    )
    assert "scale from --px-per-m 1000, origin 0 0" in given_scale.output


def test_two_cube_sizes_on_a_real_photograph_are_both_kept() -> None:
    """The ArmLab photograph (tests/data/photos: 38 mm and 25 mm cubes, some on
    stacks, nearer the camera): no square the detector finds on a labelled top
    face is rejected as not a block size."""
    from demoplan.perception.images import perceive_top_view
    from demoplan.perception.labelled import FOUND_WITHIN, load_labelled

    photo = load_labelled(Path(__file__).parents[1] / "data" / "photos" / "armlab_mrhan4.json")
    seen = perceive_top_view(photo.image, photo.px_per_m, (0.0, 0.0), timeout=60)
    assert len(seen.blocks) >= 20
    for rejection in seen.rejected:
        if rejection.reason != "not a block size":
            continue
        corners = np.array(rejection.outlines[0])
        u, v = photo.to_pixel(*corners.mean(axis=0))
        assert all(
            math.hypot(u - face.u, v - face.v) > FOUND_WITHIN * face.side_px
            for face in photo.blocks
        )


def _two_sizes(tmp_path: Path) -> tuple[Path, list[SyntheticBlock], SyntheticBlock]:
    """A top view (1000 px/m) of two 70 mm and two 20 mm cubes and a 42 mm block
    between the two sizes (beyond 1.2 × the small size's window, under 0.8 × the
    large one's)."""
    cubes = [
        SyntheticBlock("red", 0.10, 0.10, 20.0, 0.07),
        SyntheticBlock("green", 0.40, 0.10, -10.0, 0.07),
        SyntheticBlock("blue", 0.09, 0.30, 5.0, 0.02),
        SyntheticBlock("yellow", 0.22, 0.31, -30.0, 0.02),
    ]
    between = SyntheticBlock("wood", 0.38, 0.29, 12.0, 0.042)
    image = tmp_path / "two_sizes.png"
    save_image(render_blocks([*cubes, between], Camera(1000.0, (0.0, 0.0)), rng=3), image)
    return image, cubes, between


def test_several_sides_find_the_cubes_of_each_and_no_block_between(tmp_path: Path) -> None:
    """``--side 0.07 --side 0.02``: each size's cubes found at their sides, and the
    42 mm block between the sizes rejected with both windows named; one side alone
    misses the other size's cubes. (Searched from the smallest to the largest side
    instead, 17–80 mm, the 42 mm block would pass.)"""
    image, cubes, between = _two_sizes(tmp_path)
    found = perceive(image, 1000.0, (0.0, 0.0), side=(0.07, 0.02))
    assert sorted(found.blocks) == sorted(c.colour for c in cubes)
    for cube in cubes:
        assert abs(found.blocks[cube.colour].side - cube.side) < 0.002
    odd = [r for r in found.rejected if r.colour == between.colour]
    assert odd and odd[0].reason in ("too small", "too large")
    assert "14–28 / 48–97 mm allowed" in odd[0].detail
    large = perceive(image, 1000.0, (0.0, 0.0), side=0.07)
    assert {"blue", "yellow"}.isdisjoint(large.blocks)


def test_several_sides_where_one_is_needed_are_one_line_naming_them(tmp_path: Path) -> None:
    """The scale of a straight-down view comes from one block size, and a camera
    file's top faces lie at one height: several sides there are a usage error
    naming the values given (exit 2)."""
    image, _, _ = _two_sizes(tmp_path)
    with pytest.raises(UsageError, match=r"--side 0.07 --side 0.02: one block size expected"):
        perceive(image, side=(0.07, 0.02))
    result = CliRunner().invoke(app, ["perceive", str(image), "--side", "0.07", "--side", "0.02"])
    assert result.exit_code == 2
    assert "--side 0.07 --side 0.02: one block size expected" in result.output
    camera = tmp_path / "camera.json"
    camera.write_text("{}")
    with pytest.raises(UsageError, match="with --camera or --markers"):
        perceive(image, camera=camera, side=(0.07, 0.02))


def test_the_blocks_are_the_same_when_no_rejections_are_recorded(tmp_path: Path) -> None:
    """``perceive`` without recording the regions rejected (the command without
    ``--plot`` shows none): the same blocks, no rejections — with them, the large
    block's among others."""
    image, _, between = _two_sizes(tmp_path)
    recorded = perceive(image, 1000.0, (0.0, 0.0), side=(0.07, 0.02))
    spared = perceive(image, 1000.0, (0.0, 0.0), side=(0.07, 0.02), rejections=False)
    assert spared.blocks == recorded.blocks and spared.document == recorded.document
    assert spared.rejected == () and any(r.colour == between.colour for r in recorded.rejected)
    plot = tmp_path / "overlay.png"
    plotted = perceive(image, 1000.0, (0.0, 0.0), side=(0.07, 0.02), plot=plot, rejections=False)
    assert plotted.rejected == recorded.rejected  # an overlay draws them
