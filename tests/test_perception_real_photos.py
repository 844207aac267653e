"""Block perception on the real photographs of tests/data/photos (NOTICE.md there):
the scoring rule of their labels, and properties the detector keeps on them."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception.labelled import (
    FOUND_WITHIN,
    LabelledPhoto,
    PhotoScore,
    load_labelled,
    score_detections,
)

PHOTOS = Path(__file__).parent / "data" / "photos"
NAMES = sorted(path.stem for path in PHOTOS.glob("*.json"))


def _photo(name: str) -> LabelledPhoto:
    return load_labelled(PHOTOS / f"{name}.json")


def _world(photo: LabelledPhoto, u: float, v: float) -> tuple[float, float]:
    """The table point (origin 0 0) of pixel (u, v): the label's own mapping."""
    return (u + 0.5) / photo.px_per_m, (photo.height - v - 0.5) / photo.px_per_m


def test_the_development_set_is_five_labelled_photographs() -> None:
    assert NAMES == [
        "armlab_mrhan4",
        "langtable_real",
        "mrhan_phone",
        "mrhan_stacks",
        "mrhan_touching",
    ]
    for name in NAMES:
        photo = _photo(name)
        assert photo.image.is_file()
        assert all(0 <= b.u < photo.width and 0 <= b.v < photo.height for b in photo.blocks)
    assert _photo("langtable_real").needed == 0


@pytest.mark.parametrize("name", [n for n in NAMES if n != "langtable_real"])
def test_detections_at_the_labelled_centres_find_every_face(name: str) -> None:
    photo = _photo(name)
    centres = [_world(photo, b.u, b.v) for b in photo.blocks]
    assert score_detections(photo, centres).found == photo.needed
    assert score_detections(photo, centres).false == 0
    assert score_detections(photo, []).found == 0


@settings(max_examples=40, deadline=None)
@given(
    index=st.integers(0, 8),
    share=st.floats(0.0, 2.0),
    angle=st.floats(0.0, 2 * math.pi),
)
def test_a_detection_finds_a_face_only_within_the_share_of_its_side(
    index: int, share: float, angle: float
) -> None:
    photo = _photo("mrhan_touching")  # nine faces, none partial
    block = photo.blocks[index]
    reach = share * block.side_px
    u, v = block.u + reach * math.cos(angle), block.v + reach * math.sin(angle)
    others = [b for b in photo.blocks if b is not block]
    clear = all(math.hypot(u - b.u, v - b.v) > FOUND_WITHIN * b.side_px for b in others)
    if not clear:  # near another face too: that one may take it
        return
    score = score_detections(photo, [_world(photo, u, v)])
    within = reach <= FOUND_WITHIN * block.side_px - 1e-6
    beyond = reach >= FOUND_WITHIN * block.side_px + 1e-6
    if within:
        assert (score.found, score.false) == (1, 0)
    if beyond:
        assert (score.found, score.false) == (0, 1)


def test_two_detections_on_one_face_find_it_once() -> None:
    photo = _photo("mrhan_touching")
    block = photo.blocks[0]
    twice = [_world(photo, block.u, block.v), _world(photo, block.u + 2, block.v)]
    assert score_detections(photo, twice) == PhotoScore(found=1, needed=9, false=1)
