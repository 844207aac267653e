"""Colour differences the exposure does not change (demoplan.perception.exposure):
two dark colours no palette colour names, touching, are told apart as well a third
of a stop under; a dark top beside a brighter one of another hue is no side face
under less light."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from demoplan.perception.colours import MIN_CHROMA, colour_regions
from demoplan.perception.exposure import MID_GREY, chroma_apart, chroma_at_mid_grey
from demoplan.perception.side_faces import side_faces_beside_tops

BLUE, PURPLE = (60, 73, 113), (83, 73, 100)  # mrhan_touching's dark cubes, about


def _touching_pair(gain: float) -> np.ndarray:
    """A grey table and a dark blue and a dark purple square face to face, the
    image's values times ``gain``."""
    image = np.full((200, 300, 3), (170, 165, 160), float)
    image[60:120, 60:120] = BLUE
    image[60:120, 120:180] = PURPLE
    noise = np.random.default_rng(0).normal(0.0, 2.0, image.shape)
    return np.clip(image * gain + noise, 0, 255).round().astype(np.uint8)


@pytest.mark.parametrize("gain", [1.0, 0.85, 0.75])
def test_two_dark_colours_touching_stay_two_regions_under_less_light(gain: float) -> None:
    """at gain 0.75 (the encoded values × 0.75) their a*b* lie 9 apart, under
    MIN_CHROMA (and at gain 1 under it too): held to it unscaled, they were one
    region whose square spans both."""
    regions, _ = colour_regions(_touching_pair(gain), min_area=300.0)
    assert len(regions) == 2
    blue, purple = sorted(regions, key=lambda region: region.rgb[0])
    for region, columns in ((blue, range(64, 116)), (purple, range(124, 176))):
        _, cols = np.nonzero(region.alpha > 0.5)
        cols = cols + region.offset[1]
        assert set(np.unique(cols)) >= set(columns)
        assert cols.min() >= columns[0] - 6 and cols.max() <= columns[-1] + 6


LIGHT = st.floats(0.0, 100.0)
AB = st.floats(-60.0, 60.0)


@given(a1=AB, b1=AB, a2=AB, b2=AB, l1=LIGHT, l2=LIGHT, k=st.floats(0.3, 1.0))
def test_less_light_keeps_two_colours_apart_below_mid_grey(
    a1: float, b1: float, a2: float, b2: float, l1: float, l2: float, k: float
) -> None:
    """Less light scales a surface's L* + 16 and its a*, b* alike: two colours whose
    lighter one is at most mid grey are apart at every exposure or at none."""
    l1, l2 = min(l1, MID_GREY), min(l2, MID_GREY)
    lit = chroma_apart((a1, b1), (a2, b2), (l1, l2), MIN_CHROMA)
    darker = [(light + 16.0) * k - 16.0 for light in (l1, l2)]
    dim = chroma_apart((a1 * k, b1 * k), (a2 * k, b2 * k), (darker[0], darker[1]), MIN_CHROMA)
    if min(darker) >= 0.0:  # L* stays on its scale
        assert lit == dim


def test_at_mid_grey_or_brighter_the_distance_is_the_rule_s_own() -> None:
    assert chroma_apart((0.0, 0.0), (MIN_CHROMA, 0.0), (MID_GREY, 20.0), MIN_CHROMA)
    assert not chroma_apart((0.0, 0.0), (MIN_CHROMA - 0.1, 0.0), (90.0, 80.0), MIN_CHROMA)
    # a top face beside its own darker side face: judged by the top's light
    assert not chroma_apart((0.0, 0.0), (9.0, 0.0), (45.0, 15.0), MIN_CHROMA)
    assert chroma_apart((0.0, 0.0), (9.0, 0.0), (30.0, 15.0), MIN_CHROMA)


DARK_RED, ORANGE = (112, 56, 52), (189, 104, 55)  # near mrhan_touching's


@pytest.mark.parametrize("gain", [1.0, 0.85, 0.75, 0.6])
def test_a_dark_red_top_beside_an_orange_one_is_no_side_face_under_less_light(
    gain: float,
) -> None:
    """A dark red top (a*b* chroma 28) face to face with an orange one, more than
    MAX_HUE_TURN of hue apart: with the encoded values × 0.75 its chroma is 22,
    under twice MIN_CHROMA, and judged so it was "too dark to show its hue", no
    channel brighter than the orange's — the orange cube's side face."""
    image = np.full((120, 200, 3), (150, 152, 150), float)
    image[40:80, 40:80] = ORANGE
    image[40:80, 80:120] = DARK_RED
    varied = np.clip(image * gain, 0, 255).round().astype(np.uint8)
    squares = [(59.5, 59.5, 0.0, 40.0), (99.5, 59.5, 0.0, 40.0)]
    assert side_faces_beside_tops(varied, squares) == {}


def test_a_dark_face_of_the_tops_colour_is_still_its_side_face() -> None:
    """The orange top's own side face, half as bright, stays a side face."""
    image = np.full((120, 200, 3), (150, 152, 150), float)
    image[40:80, 40:80] = ORANGE
    image[40:80, 80:120] = np.array(ORANGE) * 0.45
    squares = [(59.5, 59.5, 0.0, 40.0), (99.5, 59.5, 0.0, 40.0)]
    assert set(side_faces_beside_tops(image.round().astype(np.uint8), squares)) == {1}


@given(chroma=st.floats(0.0, 80.0), light=LIGHT, k=st.floats(0.3, 1.0))
def test_a_colours_chroma_at_mid_grey_does_not_change_with_less_light(
    chroma: float, light: float, k: float
) -> None:
    """Less light scales a* b* and L* + 16 alike: below mid grey the chroma as lit to
    mid grey stays."""
    light = min(light, MID_GREY)
    darker = (light + 16.0) * k - 16.0
    if darker >= 0.0:
        assert math.isclose(
            chroma_at_mid_grey(chroma * k, darker), chroma_at_mid_grey(chroma, light),
            rel_tol=1e-9, abs_tol=1e-9,
        )  # fmt: skip
