"""A large photograph is looked at reduced by a whole factor
(:mod:`demoplan.perception.working_resolution`): the factor's rule, the reduction's
pixels and origin, and a real photograph at twice its resolution (a phone's
12 megapixels are three times mrhan_phone's) found as at its own."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception.camera_variations import CameraVariation, varied_photo
from demoplan.perception.images import perceive_top_view
from demoplan.perception.labelled import load_labelled, score_detections
from demoplan.perception.working_resolution import (
    UNSCALED_SHORTER_SIDE,
    WORKING_SIDE_PX,
    factor_for_scale,
    factor_for_size,
    reduced,
)

PHOTOS = Path(__file__).parents[1] / "data" / "photos"


def test_the_factor_keeps_the_smallest_top_at_least_the_working_side() -> None:
    phone = (4032, 3024, 3)
    assert factor_for_scale(WORKING_SIDE_PX * 2 - 0.1, phone) == 1
    assert factor_for_scale(WORKING_SIDE_PX * 2, phone) == 2
    assert factor_for_scale(WORKING_SIDE_PX * 5.5, phone) == 2  # the image's own bound
    assert factor_for_scale(WORKING_SIDE_PX * 5.5, (6000, 8000, 3)) == 5
    assert factor_for_scale(10.0, phone) == 1
    assert factor_for_scale(math.nan, phone) == 1
    assert factor_for_scale(math.inf, phone) == 1
    # a robot's camera image is never reduced, however large its blocks
    assert factor_for_scale(WORKING_SIDE_PX * 10, (1080, 1920, 3)) == 1


def test_without_a_scale_only_an_image_twice_the_shorter_side_is_reduced() -> None:
    side = UNSCALED_SHORTER_SIDE
    assert factor_for_size((2 * side - 1, 10 * side, 3)) == 1
    assert factor_for_size((10 * side, 2 * side, 3)) == 2
    assert factor_for_size((4032, 3024, 3)) == 2
    assert factor_for_size((720, 1280, 3)) == 1


@settings(max_examples=40, deadline=None)
@given(
    height=st.integers(1, 40),
    width=st.integers(1, 40),
    factor=st.integers(1, 5),
    seed=st.integers(0, 2**16),
)
def test_a_reduced_pixel_is_the_mean_of_its_square_counted_from_the_bottom_left(
    height: int, width: int, factor: int, seed: int
) -> None:
    image = np.random.default_rng(seed).integers(0, 256, (height, width, 3), dtype=np.uint8)
    result = reduced(image, factor)
    rows, cols = height // factor, width // factor
    if factor == 1 or rows == 0 or cols == 0:
        assert result.factor == 1 and result.picture is image
        return
    assert result.factor == factor and result.picture.shape == (rows, cols, 3)
    # row r (from the top) of the reduction covers the photograph's rows from
    # the bottom up: the bottom-left square is the photograph's bottom-left
    for row in range(rows):
        for col in range(cols):
            top = height - (rows - row) * factor
            square = image[top : top + factor, col * factor : (col + 1) * factor]
            mean = square.reshape(-1, 3).mean(axis=0)
            assert np.all(np.abs(result.picture[row, col].astype(float) - mean) <= 1.0)


@pytest.fixture(scope="module")
def phone_twice(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """mrhan_phone (a real phone photograph, 1200 × 1600) at twice its resolution."""
    photo = load_labelled(PHOTOS / "mrhan_phone.json")
    folder = tmp_path_factory.mktemp("twice")
    return photo, varied_photo(photo, CameraVariation(scale=2.0), folder, "phone_twice")


def _px_per_m(scale: str) -> float:
    """The scale a ``--side``-only perception measured, from its scale line."""
    found = re.search(r"([0-9.]+) px/m", scale)
    assert found, scale
    return float(found.group(1))


@pytest.mark.parametrize("given", ["px_per_m", "side"])
def test_a_photograph_at_twice_its_resolution_finds_every_top(phone_twice, given: str) -> None:  # type: ignore[no-untyped-def]
    """The scale known (``--px-per-m`` 4200: a 20 mm top 84 px, reduced by 2) or only
    the cubes' side (a shorter side of 2400 px, reduced by 2): every labelled top
    found, none false (with the side alone, its positions taken at the scale it
    measured); the scale's line says the reduction. (At full resolution the side
    alone found 10 blocks on a 12-megapixel upscale of this photograph, 4 of them a
    cube's grain and glints: 3.8 s of CPU and 1 GB; reduced, 1.6 s and 0.4 GB.)"""
    _, twice = phone_twice
    if given == "side":
        seen = perceive_top_view(twice.image, None, (0.0, 0.0), side=twice.side_m[0])
        to_label = _px_per_m(seen.scale) / twice.px_per_m
    else:
        seen = perceive_top_view(twice.image, twice.px_per_m, (0.0, 0.0))
        to_label = 1.0
    assert "at 1/2 of its resolution (1200 × 1600 of 2400 × 3200 px)" in seen.scale
    centres = [(b.x * to_label, b.y * to_label) for b in seen.blocks.values()]
    score = score_detections(twice, centres)
    assert (score.found, score.false) == (score.needed, 0)
