"""A white cube on white paper lit as the paper: its top two or three L* over the
paper, under the bright contrast, found by its outline (demoplan.perception.faint_white)
— and a board's cell as faint, bounded by thin lines running on past its corners, not."""

from __future__ import annotations

import math

import numpy as np
import pytest

from demoplan.perception.blocks import PerceptionSettings, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.opencv import cv2

PX_PER_M = 1500.0
SIDE_PX = 60  # a 4 cm top
PAPER = 190.0  # grey level of the paper (L* about 76)
TOP = 197.0  # the top: about 2.5 L* over the paper
FACE = 140.0  # a side face in shade, the shadow (about 0.75 of the paper's L*)


def _noisy(image: np.ndarray, seed: int) -> np.ndarray:
    """``image`` (grey levels) with a little noise, blurred as a lens does, as RGB,
    a blue pen line drawn at its bottom left (a photograph in colour: a grey one
    is a monochrome camera's, looked at otherwise)."""
    rng = np.random.default_rng(seed)
    noisy = image + rng.normal(0.0, 1.0, image.shape)
    blurred = cv2.GaussianBlur(noisy.astype(np.float32), (3, 3), 0.8)
    rgb = np.repeat(np.clip(blurred, 0, 255).astype(np.uint8)[..., None], 3, axis=2)
    rgb[440:443, 20:140] = (40, 60, 170)
    return rgb


def _white_cube_on_paper(u: int, v: int, seed: int) -> np.ndarray:
    """A 640 × 480 grey image (neutral: white paper in a room's light) with one cube's
    top (SIDE_PX square, top-left at u, v) lit as the paper but a few L* over it, its
    two side faces turned away from the light below and right of it (a quarter of a
    side wide, ending at its corners) and a 2 px rim in shade on its other edges (the
    generated family's, 7-10 L* under the paper)."""
    image = np.full((480, 640), PAPER)
    s, w = SIDE_PX, SIDE_PX // 4
    image[v + s : v + s + w, u + w // 2 : u + s + w // 2] = FACE  # the near side face
    image[v + w // 2 : v + s + w, u + s : u + s + w] = FACE - 10  # the other, darker
    image[v - 2 : v, u - 2 : u + s] = PAPER - 20  # the far edges' shading line
    image[v - 2 : v + s, u - 2 : u] = PAPER - 20
    image[v : v + s, u : u + s] = TOP
    return _noisy(image, seed)


def _board_cell(u: int, v: int, seed: int) -> np.ndarray:
    """The same paper with a grid of thin dark lines (2 px, every SIDE_PX + 2 px, on
    past every corner) and one cell lit as the top above is."""
    image = np.full((480, 640), PAPER)
    pitch = SIDE_PX + 2
    for line in range(u - 2 - 3 * pitch, 640, pitch):
        if line >= 0:
            image[:, line : line + 2] = PAPER - 60
    for line in range(v - 2 - 3 * pitch, 480, pitch):
        if line >= 0:
            image[line : line + 2, :] = PAPER - 60
    image[v : v + SIDE_PX, u : u + SIDE_PX] = TOP
    return _noisy(image, seed)


@pytest.mark.parametrize("side_given", [False, True])
@pytest.mark.parametrize(("u", "v", "seed"), [(200, 150, 1), (350, 260, 2)])
def test_a_white_top_lit_as_the_paper_is_found_by_its_side_faces(
    side_given: bool, u: int, v: int, seed: int
) -> None:
    """Its side faces in shade (a quarter of a side wide) and its shaded far edges
    outline it: one white block within 0.6 side of its centre (main: no block,
    the top under the bright contrast: no bright part holds it)."""
    image = _white_cube_on_paper(u, v, seed)
    settings = (
        PerceptionSettings(min_side=0.034, max_side=0.046) if side_given else PerceptionSettings()
    )
    found = detect_blocks(image, Camera(PX_PER_M, (0.0, 0.0)), settings)
    centre = (u + SIDE_PX / 2 - 0.5, v + SIDE_PX / 2 - 0.5)
    pixels = [(b.x * PX_PER_M - 0.5, image.shape[0] - b.y * PX_PER_M - 0.5) for b in found]
    assert len(found) == 1, found
    assert math.dist(pixels[0], centre) <= 0.6 * SIDE_PX
    assert found[0].colour == "white"


@pytest.mark.parametrize("side_given", [False, True])
def test_a_board_cell_as_faint_bounded_by_thin_lines_is_no_block(side_given: bool) -> None:
    """A cell as much over the board as the top above over the paper, bounded by 2 px
    lines (darker all round) but no band of a side face's width: nothing."""
    image = _board_cell(200, 150, 3)
    settings = (
        PerceptionSettings(min_side=0.034, max_side=0.046) if side_given else PerceptionSettings()
    )
    try:
        found = detect_blocks(image, Camera(PX_PER_M, (0.0, 0.0)), settings)
    except Exception as error:  # "no blocks found" is the answer here
        assert "no blocks" in str(error).lower(), error
        return
    assert found == [], found
