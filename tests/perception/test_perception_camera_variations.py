"""The development photographs as another camera would give them
(demoplan.perception.camera_variations): the image and its label varied together,
and the detector judged on them by the issue's thresholds — the variations it
holds under by hypothesis over their stated ranges, those it does not hold under
yet as named draws that fail (strict xfails, each with what was seen)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from demoplan.errors import UsageError
from demoplan.perception.camera_variations import (
    VARIATIONS,
    CameraVariation,
    varied_photo,
    vary_image,
    vary_label,
)
from demoplan.perception.labelled import (
    LabelledBlock,
    LabelledPhoto,
    load_labelled,
    perceive_labelled,
)

PHOTOS = Path(__file__).parents[1] / "data" / "photos"
CUBES = ("armlab_mrhan4", "mrhan_phone", "mrhan_stacks", "mrhan_touching")
EXPENSIVE = settings(
    deadline=None,
    phases=(Phase.explicit, Phase.reuse, Phase.generate),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)


# ------------------------------------------------------------ the label moves with the image

COLOURS = ((255, 0, 0), (0, 255, 0), (0, 0, 255))


def _squares(width: int, height: int, corners: list[tuple[int, int]], side: int) -> np.ndarray:
    """Black, with a red, a green and a blue axis-aligned square (top-left corners)."""
    image = np.zeros((height, width, 3), np.uint8)
    for (u0, v0), colour in zip(corners, COLOURS, strict=True):
        image[v0 : v0 + side, u0 : u0 + side] = colour
    return image


@st.composite
def _scenes(draw: st.DrawFn) -> tuple[np.ndarray, LabelledPhoto]:
    width, height, side = draw(st.integers(120, 180)), draw(st.integers(60, 120)), 16
    corners = [
        (draw(st.integers(4 + 40 * i, 4 + 40 * i + 10)), draw(st.integers(4, height - side - 4)))
        for i in range(3)
    ]
    blocks = tuple(
        LabelledBlock(u0 + (side - 1) / 2, v0 + (side - 1) / 2, float(side), False)
        for u0, v0 in corners
    )
    label = LabelledPhoto("squares", Path("squares.png"), width, height, 400.0, (0.04,), blocks)
    return _squares(width, height, corners, side), label


@settings(max_examples=60, deadline=None)
@given(
    scene=_scenes(),
    mirror=st.booleans(),
    turns=st.integers(-3, 5),
    scale=st.sampled_from([1.0, 0.6, 0.75, 1.25, 1.6, 2.0]),
)
def test_the_varied_label_points_at_the_same_squares(
    scene: tuple[np.ndarray, LabelledPhoto], mirror: bool, turns: int, scale: float
) -> None:
    """Each labelled square's centre is its colour's centroid in the varied image
    (weighted by the channel: Lanczos resampling blurs its edges), its side the
    root of its area, the label's size the image's."""
    image, label = scene
    variation = CameraVariation(mirror=mirror, turns=turns, scale=scale)
    varied, moved = vary_image(image, variation), vary_label(label, variation)
    assert varied.shape == (moved.height, moved.width, 3)
    for block, colour in zip(moved.blocks, COLOURS, strict=True):
        weight = varied[..., colour.index(255)].astype(float) / 255  # its square alone
        v, u = np.indices(weight.shape)
        centre = (weight * u).sum() / weight.sum(), (weight * v).sum() / weight.sum()
        assert abs(centre[0] - block.u) < 0.1 and abs(centre[1] - block.v) < 0.1, (block, centre)
        assert abs(np.sqrt(weight.sum()) - block.side_px) < 0.3, (block, weight.sum())
    assert moved.px_per_m == pytest.approx(label.px_per_m * scale, rel=0.02)


def test_a_photometric_variation_leaves_the_label_and_the_geometry_alone() -> None:
    image = _squares(120, 80, [(4, 4), (44, 30), (90, 50)], 16)
    label = LabelledPhoto("s", Path("s.png"), 120, 80, 400.0, (0.04,), ())
    for key in ("gain0.75", "warm", "gamma0.7", "noise6", "jpeg40", "blur1.5"):
        assert VARIATIONS[key].photometric
        assert vary_label(label, VARIATIONS[key]) == label
        assert vary_image(image, VARIATIONS[key]).shape == image.shape
    assert np.array_equal(vary_image(image, VARIATIONS["none"]), image)


def test_the_light_is_changed_on_the_encoded_values_and_clipped() -> None:
    image = np.full((4, 4, 3), (200, 100, 40), np.uint8)
    assert vary_image(image, CameraVariation(gain=0.75))[0, 0].tolist() == [150, 75, 30]
    assert vary_image(image, CameraVariation(gain=1.5))[0, 0].tolist() == [255, 150, 60]
    warm = vary_image(image, CameraVariation(white=(1.12, 1.0, 0.85)))
    assert warm[0, 0].tolist() == [224, 100, 34]
    dark = vary_image(image, CameraVariation(gamma=2.0))[0, 0].tolist()
    assert dark == [round(255 * (200 / 255) ** 2), round(255 * (100 / 255) ** 2), 6]


def test_the_sensor_noise_is_drawn_from_the_seed() -> None:
    image = np.full((40, 40, 3), 128, np.uint8)
    noisy = CameraVariation(noise=6.0)
    first, again = vary_image(image, noisy, seed=3), vary_image(image, noisy, seed=3)
    assert np.array_equal(first, again)
    assert not np.array_equal(first, vary_image(image, noisy, seed=4))
    assert 5.0 < first.astype(float).std() < 7.0


@pytest.mark.parametrize(
    "wrong",
    [
        {"gain": 0.0},
        {"gamma": -1.0},
        {"scale": 0.0},
        {"white": (1.0, 0.0, 1.0)},
        {"noise": -1.0},
        {"blur": -0.5},
        {"jpeg": 0},
        {"jpeg": 100},
    ],
)
def test_a_variation_out_of_range_is_refused(wrong: dict[str, object]) -> None:
    with pytest.raises(UsageError):
        CameraVariation(**wrong)  # type: ignore[arg-type]


def test_a_varied_photograph_is_written_with_its_label(tmp_path: Path) -> None:
    photo = load_labelled(PHOTOS / "mrhan_phone.json")
    varied = varied_photo(photo, VARIATIONS["turn90"], tmp_path, "turned")
    assert varied.image == tmp_path / "turned.png" and varied.image.is_file()
    assert (varied.width, varied.height) == (photo.height, photo.width)
    assert varied.blocks == vary_label(photo, VARIATIONS["turn90"]).blocks


# ------------------------------------------------------------ the detector under them


def _meets(name: str, variation: CameraVariation, side_given: bool, folder: Path) -> None:
    photo = load_labelled(PHOTOS / f"{name}.json")
    side = photo.side_m[0] if side_given and len(photo.side_m) == 1 else None
    run = perceive_labelled(varied_photo(photo, variation, folder, "varied"), side=side)
    assert run.exit_code == 0, run.error
    assert run.score.found >= 0.9 * run.score.needed, (name, variation, side, run.score)
    assert run.score.false <= 1, (name, variation, side, run.score)


ORIENTED = (
    ("armlab_mrhan4", False),
    ("mrhan_phone", True),
    ("mrhan_stacks", False),
    ("mrhan_touching", False),
    ("mrhan_touching", True),
)
"""The photographs (and --side given) the detector holds in all eight orientations
on today; mrhan_phone without --side is in :data:`NOT_YET` (``turn180``)."""


@pytest.mark.parametrize(("name", "side_given"), ORIENTED)
@settings(EXPENSIVE, max_examples=3, derandomize=True)
@given(mirror=st.booleans(), turns=st.integers(0, 3))
def test_a_photograph_mirrored_or_turned_meets_the_thresholds(
    tmp_path_factory: pytest.TempPathFactory,
    name: str,
    side_given: bool,
    mirror: bool,
    turns: int,
) -> None:
    """The camera's orientation on the table is the photographer's: the same cubes
    are found whichever way up the photograph is."""
    folder = tmp_path_factory.mktemp("turned")
    _meets(name, CameraVariation(mirror=mirror, turns=turns), side_given, folder)


NOT_YET: dict[str, tuple[str, tuple[tuple[str, bool], ...]]] = {
    # variation: (what is missed, draws (photograph, --side given) failing today)
    "gain0.75": (
        "the encoded values x 0.75: mrhan_phone 4/6 (not looked into); mrhan_touching "
        "9/9 since a side face's chroma is judged as lit to mid grey "
        "(demoplan.perception.exposure.chroma_at_mid_grey: its dark red top was taken "
        "for the orange cube's side face)",
        (("mrhan_phone", True),),
    ),
    "turn180": (
        "mrhan_phone without --side 5/6 turned by 180° (and mirrored then turned by 90° "
        "or 270°; 6/6 with --side and in the other orientations; not looked into)",
        (("mrhan_phone", False),),
    ),
    "gain1.2": ("a fifth over: mrhan_stacks 5/11 (not looked into)", (("mrhan_stacks", False),)),
    "gamma0.7": (
        "mrhan_touching 8/9: under the tone curve its orange and dark red tops are both "
        "named wood, one class whose darker lightness mode (the red top) is taken for "
        "side faces",
        (("mrhan_touching", False),),
    ),
    "gamma1.4": ("armlab_mrhan4 40/47 (not looked into)", (("armlab_mrhan4", False),)),
    "cool": (
        "a cool white balance (R × 0.88, B × 1.12), its cast taken back to the "
        "development photographs' (demoplan.perception.white_balance): armlab_mrhan4 "
        "38/47 (not looked into), mrhan_touching 8/9 and 7/9 with --side: its orange and "
        "dark red tops one region (12/47, 7/9 and 8/9 before the white balance)",
        (("armlab_mrhan4", False), ("mrhan_touching", True)),
    ),
    "noise6": (
        "sensor noise σ 6: mrhan_touching's 2 × 2 group of dark purple and blue cubes "
        "one rejected region, 5/9",
        (("mrhan_touching", False),),
    ),
    "jpeg40": (
        "armlab_mrhan4 32/47, mrhan_stacks 8/11 (not looked into)",
        (("mrhan_touching", True),),
    ),
    "scale0.8": (
        "mrhan_touching 7/9 without --side (not looked into)",
        (("mrhan_touching", False),),
    ),
    "scale1.25": ("mrhan_stacks 3 false blocks (not looked into)", (("mrhan_stacks", False),)),
    "blur1.5": ("mrhan_stacks 9/11 and 1 false (not looked into)", (("mrhan_stacks", False),)),
}
"""The named variations (:data:`VARIATIONS`) the detector does not hold under yet,
each with draws it fails on (``benchmarks/perception_camera.py`` tables them all).
The day one of these passes, its test says so (strict)."""


@pytest.mark.parametrize(
    ("key", "name", "side_given"),
    [
        pytest.param(key, name, side, marks=pytest.mark.xfail(strict=True, reason=reason))
        for key, (reason, draws) in sorted(NOT_YET.items())
        for name, side in draws
    ],
)
def test_a_variation_not_held_yet_fails_where_it_was_seen_failing(
    tmp_path: Path, key: str, name: str, side_given: bool
) -> None:
    _meets(name, VARIATIONS[key], side_given, tmp_path)


HELD = ("scale0.6", "warm")
"""Named variations other than the orientations that every photograph meets (with
--side too where its label names one size): 0.6 of the resolution since the
second look at the block size (mrhan_stacks 9 → 10 of 11); a warm white balance
since the table's cast is taken back to the development photographs'
(demoplan.perception.white_balance: mrhan_stacks 1 → 11 of 11, mrhan_touching 3
and 2 → 9 of 9, armlab_mrhan4 23 → 44 of 47)."""


@pytest.mark.parametrize("key", HELD)
@pytest.mark.parametrize(("name", "side_given"), ORIENTED + (("mrhan_phone", False),))
def test_a_held_variation_meets_the_thresholds(
    tmp_path: Path, key: str, name: str, side_given: bool
) -> None:
    _meets(name, VARIATIONS[key], side_given, tmp_path)


HELD_ON: dict[str, tuple[tuple[str, bool], ...]] = {
    # variation in NOT_YET: draws (photograph, --side given) it meets on, and since what
    "cool": (  # the table's cast taken back (demoplan.perception.white_balance)
        ("mrhan_stacks", False),  # 2/11 and 1 false before
        ("mrhan_phone", True),  # 5/6 before
    ),
    "gain0.75": (  # a side face's chroma as lit to mid grey (demoplan.perception.exposure)
        ("mrhan_touching", False),  # 8/9 before: its dark red top taken for a side face
        ("mrhan_touching", True),
    ),
}
"""Draws that meet under a variation not held on every photograph yet (:data:`NOT_YET`),
each met by a named rule: they stay met."""


@pytest.mark.parametrize(
    ("key", "name", "side_given"),
    [(key, name, side) for key, draws in sorted(HELD_ON.items()) for name, side in draws],
)
def test_a_draw_met_under_a_variation_not_held_yet_stays_met(
    tmp_path: Path, key: str, name: str, side_given: bool
) -> None:
    assert key in NOT_YET
    _meets(name, VARIATIONS[key], side_given, tmp_path)


def test_every_named_variation_is_held_or_named_not_yet() -> None:
    held = {"none", "mirror", "turn90", *HELD}
    assert set(VARIATIONS) == held | set(NOT_YET)
