"""A detector of cubes seen from above answers alike on a photograph turned or
mirrored: each rule is checked here on the eight turns and mirrors of a real
photograph (tests/data/photos), its answer mapped back."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

import demoplan.perception.blocks as blocks_module
from demoplan.perception.blocks import PerceptionSettings, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.labelled import load_labelled
from demoplan.perception.side_faces import ImageSquare
from demoplan.perception.stack_sides import lower_side_faces

PHOTOS = Path(__file__).parents[1] / "data" / "photos"

_Point = Callable[[float, float, int, int], tuple[float, float]]
TURNS: dict[str, tuple[Callable[[np.ndarray], np.ndarray], _Point, bool]] = {
    # the image turned or mirrored; where an image point (x right, y down, px
    # continuous: pixel i spans [i, i + 1)) of a W x H image goes; mirrored or not
    "as taken": (lambda a: a, lambda x, y, w, h: (x, y), False),
    "mirrored left-right": (lambda a: a[:, ::-1], lambda x, y, w, h: (w - x, y), True),
    "mirrored top-bottom": (lambda a: a[::-1], lambda x, y, w, h: (x, h - y), True),
    "turned 180": (lambda a: a[::-1, ::-1], lambda x, y, w, h: (w - x, h - y), False),
    "turned 90 left": (np.rot90, lambda x, y, w, h: (y, w - x), False),
    "turned 90 right": (lambda a: np.rot90(a, 3), lambda x, y, w, h: (h - y, x), False),
    "transposed": (lambda a: a.transpose(1, 0, 2), lambda x, y, w, h: (y, x), True),
    "transposed across": (
        lambda a: a[::-1, ::-1].transpose(1, 0, 2),
        lambda x, y, w, h: (h - y, w - x),
        True,
    ),
}


@pytest.fixture(scope="module")
def stacks_squares() -> tuple[np.ndarray, list[ImageSquare]]:
    """mrhan_stacks and the squares the detector accepted in it, as the stack
    sides' rule is given them."""
    photo = load_labelled(PHOTOS / "mrhan_stacks.json")
    image = np.asarray(Image.open(photo.image).convert("RGB"))
    given: list[list[ImageSquare]] = []

    def spy(image: Any, squares: list[ImageSquare], *shared: Any) -> dict[int, str]:
        given.append(list(squares))
        return lower_side_faces(image, squares, *shared)

    with pytest.MonkeyPatch.context() as patched:
        patched.setattr(blocks_module, "lower_side_faces", spy)
        detect_blocks(image, Camera(photo.px_per_m, (0.0, 0.0)), PerceptionSettings())
    (squares,) = given
    return image, squares


@pytest.mark.parametrize("turn", sorted(TURNS))
def test_the_stacks_side_faces_are_the_same_on_a_turned_or_mirrored_photograph(
    stacks_squares: tuple[np.ndarray, list[ImageSquare]], turn: str
) -> None:
    """The same squares are a stack's side faces (mrhan_stacks' two) whichever way
    the photograph is turned or mirrored, and the nadir they are told by is the
    turned one (within a pixel)."""
    image, squares = stacks_squares
    height, width = image.shape[:2]
    change, point, mirrored = TURNS[turn]
    turned = np.ascontiguousarray(change(image))
    moved = [
        (*point(x, y, width, height), -theta if mirrored else theta, side)
        for x, y, theta, side in squares
    ]
    expected = lower_side_faces(image, squares)
    found = lower_side_faces(turned, moved)
    assert sorted(found) == sorted(expected) and len(expected) == 2
    for index, why in found.items():
        nadir = _nadir(why)
        assert math.dist(nadir, point(*_nadir(expected[index]), width, height)) <= 1.5, (
            why,
            expected[index],
        )


def _nadir(why: str) -> tuple[float, float]:
    """The nadir (px) a stack's side face's reason names."""
    x, y = re.findall(r"nadir at \((-?\d+), (-?\d+)\)", why)[0]
    return float(x), float(y)
