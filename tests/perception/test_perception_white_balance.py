"""A photograph's colour cast taken back to the table's grey
(demoplan.perception.white_balance): the cubes keep their names under a warm or
cool white balance, and a photograph whose table is grey, or of a colour of its
own, is left as it is."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from demoplan.perception.blocks import detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.camera_variations import CameraVariation, vary_image
from demoplan.perception.white_balance import (
    MAX_CAST,
    NEUTRAL_CAST,
    table_cast,
    white_balanced,
)

CUBES = {  # name: (RGB, centre column, centre row), 38 px tops on a grey board
    "blue": ((40, 60, 140), 100, 100),
    "purple": ((90, 60, 130), 100, 260),
    "green": ((50, 120, 60), 240, 180),
    "red": ((170, 50, 45), 300, 100),
}


def _board(table: tuple[int, int, int] = (150, 152, 150)) -> np.ndarray:
    """A grey board ruled by dark grid lines every 48 px, with :data:`CUBES` on it."""
    image = np.empty((360, 480, 3), np.uint8)
    image[:] = table
    for k in range(0, 480, 48):
        image[:, k : k + 4] = (60, 60, 60)
    for k in range(0, 360, 48):
        image[k : k + 4, :] = (60, 60, 60)
    for rgb, col, row in CUBES.values():
        image[row - 19 : row + 19, col - 19 : col + 19] = rgb
    return image


def _cast(image: np.ndarray, red: float, blue: float) -> np.ndarray:
    """``image`` with its red and blue channels times ``e**red`` and ``e**blue``."""
    gains = np.array([math.exp(red), 1.0, math.exp(blue)])
    return np.clip(np.round(image * gains), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("white", [(0.88, 1.0, 1.12), (1.12, 1.0, 0.85)])
def test_the_cubes_keep_their_names_under_a_cool_or_a_warm_white_balance(
    white: tuple[float, float, float],
) -> None:
    """Named by their chromaticity as the camera gave it, the blue cube under a cool
    balance (red × 0.88, blue × 1.12 on the encoded values) was named purple."""
    image = vary_image(_board(), CameraVariation(white=white))
    found = detect_blocks(image, Camera(1000.0, (0.0, 0.0)))
    assert sorted(block.colour for block in found) == sorted(CUBES)


@given(
    angle=st.floats(0.0, 2 * math.pi),
    distance=st.floats(NEUTRAL_CAST + 0.03, MAX_CAST - 0.03),
)
def test_a_cast_beyond_the_neutral_one_is_taken_back_to_it(angle: float, distance: float) -> None:
    """A white balance moves every pixel by one step in (ln R/G, ln B/G): what of the
    table's step lies beyond NEUTRAL_CAST is divided out, its direction kept."""
    board = _board()
    own = np.array(table_cast(board))
    step = distance * np.array([math.cos(angle), math.sin(angle)])
    varied = _cast(board, *(step - own))  # the table at ``step`` from grey
    assert np.allclose(table_cast(varied), step, atol=0.015)
    balanced = np.array(table_cast(white_balanced(varied)))
    assert abs(float(np.hypot(*balanced)) - NEUTRAL_CAST) < 0.015
    assert float(balanced @ step) / (np.hypot(*balanced) * distance) > 0.98


@pytest.mark.parametrize(
    ("table", "red", "blue"),
    [
        ((150, 152, 150), 0.0, 0.0),  # a grey board
        ((150, 152, 150), 0.05, -0.07),  # a little warm: as its camera balanced it
        ((214, 212, 204), 0.0, 0.0),  # white paper under room light
        ((70, 110, 170), 0.0, 0.0),  # a blue table top: 0.63 from grey
        ((70, 110, 170), 0.11, -0.16),  # the blue table under a warm balance
    ],
)
def test_a_grey_or_coloured_table_is_left_as_it_is(
    table: tuple[int, int, int], red: float, blue: float
) -> None:
    image = _cast(_board(table), red, blue)
    assert white_balanced(image) is image
