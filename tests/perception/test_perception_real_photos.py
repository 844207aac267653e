"""Block perception on the real photographs of tests/data/photos (NOTICE.md there):
the issue's acceptance on each (at least 90 % of the labelled, non-partial top
faces found within 0.6 side of their centre, at most one false block; none, and
exit 1, on the photograph without cubes), the scoring rule of their labels, and
properties the detector keeps on them."""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception.blocks import PerceptionSettings, Rejection, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.labelled import (
    FOUND_WITHIN,
    LabelledPhoto,
    PhotoScore,
    load_labelled,
    perceive_labelled,
    score_detections,
)
from demoplan.perception.synthetic import SyntheticBlock, random_blocks, render_blocks

PHOTOS = Path(__file__).parents[1] / "data" / "photos"
CAMERA = Camera(1000.0, (0.0, 0.0))  # 1 px = 1 mm
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


@pytest.mark.parametrize("name", NAMES)
def test_a_label_corrected_after_running_says_so(name: str) -> None:
    """mrhan_stacks' label said ``labelled_before_running: true`` alone, though
    two of its blocks were labelled after the detector had run (their entries
    say ``correction``): a label with a corrected entry says what and why in its
    ``corrected_after_running``, and the loader shows it; the others have none."""
    import json

    document = json.loads((PHOTOS / f"{name}.json").read_text(encoding="utf-8"))
    corrected = [b for b in document["blocks"] if "correction" in b]
    photo = _photo(name)
    assert bool(corrected) == bool(photo.corrected_after_running)
    assert photo.corrected_after_running == document.get("corrected_after_running", "")
    if corrected:
        assert f"{len(document['blocks'])} blocks" in photo.corrected_after_running


def test_a_label_whose_correction_is_not_text_is_refused(tmp_path: Path) -> None:
    import json

    from demoplan.errors import InputError

    document = json.loads((PHOTOS / "mrhan_touching.json").read_text(encoding="utf-8"))
    document["image"] = str(PHOTOS / document["image"])
    document["corrected_after_running"] = True
    (tmp_path / "label.json").write_text(json.dumps(document))
    with pytest.raises(InputError, match="corrected_after_running"):
        load_labelled(tmp_path / "label.json")


@pytest.mark.parametrize("name", NAMES)
def test_a_development_photograph_meets_the_issue_thresholds(name: str) -> None:
    """As ``demoplan perceive PHOTO --px-per-m S --origin 0 0`` (no --side) reads it:
    at least 90 % of the labelled, non-partial tops found, at most one false block
    — on the photograph without cubes none, and exit 1 ("no blocks found")."""
    photo = _photo(name)
    run = perceive_labelled(photo, timeout=60.0)
    if photo.needed == 0:
        assert run.exit_code == 1 and run.score.false == 0, (run.error, run.score)
        return
    assert run.exit_code == 0, run.error
    assert run.score.found >= 0.9 * run.score.needed, run.score
    assert run.score.false <= 1, run.score


@pytest.mark.parametrize("name", ["mrhan_phone", "mrhan_touching"])
def test_a_development_photograph_with_its_side_shows_no_false_block(name: str) -> None:
    """With the cubes' side given (``--side``, the label's one size) no size check
    is left to drop a square of that size that is no cube: a cell of the gridded
    board (a 36 mm white square bounded by its lines) and a dark part of the robot's
    base each passed for a block once (two rules taken back). Every top is found
    and nothing else."""
    photo = _photo(name)
    run = perceive_labelled(photo, timeout=60.0, side=photo.side_m[0])
    assert run.exit_code == 0, run.error
    assert run.score.found == run.score.needed and run.score.false == 0, run.score


@pytest.mark.parametrize("name", ["armlab_mrhan4", "mrhan_stacks"])
def test_a_development_photograph_of_two_sizes_with_both_sides_meets_the_thresholds(
    name: str,
) -> None:
    """A table of 38 mm and 25 mm cubes read with both sides (``--side 0.038 --side
    0.025``, the label's two sizes): at least 90 % of the tops, at most one false
    block. With ``--side 0.038`` alone the 25 mm cubes are too small to be blocks."""
    photo = _photo(name)
    assert len(photo.side_m) == 2
    run = perceive_labelled(photo, timeout=60.0, side=photo.side_m)
    assert run.exit_code == 0, run.error
    assert run.score.found >= 0.9 * run.score.needed, run.score
    assert run.score.false <= 1, run.score


@pytest.mark.xfail(
    strict=True,
    reason="mrhan_stacks with both sides finds 10 of 11 tops and one false block: the "
    "colour regions' least area follows the smallest side searched (0.3 × (0.85 × 25 mm)², "
    "114 px, where it is 102 px without --side) and splits the green top of the stack at "
    "the lower right from its side strip differently ('block' 186 px and 'green' 293 px, "
    "neither square); its blue side face, with no top found above it, stays a block",
)
def test_mrhan_stacks_with_both_sides_finds_every_top_and_nothing_else() -> None:
    photo = _photo("mrhan_stacks")
    run = perceive_labelled(photo, timeout=60.0, side=photo.side_m)
    assert run.score.found == run.score.needed and run.score.false == 0, run.score


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


# --------------------------------------------------------------------------- generated tables

_SURROUNDS = {"wood": (172, 122, 74), "blue": (70, 110, 170), "green": (60, 130, 80)}


def _board_in_a_table(
    seed: int, surround: str, widths: tuple[int, int, int, int], grid: bool
) -> tuple[list[SyntheticBlock], np.ndarray]:
    """A 640 × 480 top view (1 px = 1 mm) of blocks on a pale board, with a table of
    another colour around it on the sides whose width (left, top, right, bottom, px)
    is not 0 (under half the image: the board is the median colour): grained, and
    with ``grid``, ruled by dark lines every 40 px (squares of table colour between
    them)."""
    rng = np.random.default_rng(seed)
    left, top, right, bottom = widths
    inner = Camera(1000.0, ((left + 60) / 1000.0, (bottom + 60) / 1000.0))
    truth = random_blocks(
        int(rng.integers(1, 6)), inner, 520 - left - right, 360 - top - bottom, rng
    )
    image = render_blocks(truth, CAMERA, 640, 480, noise=2.0, rng=rng).astype(float)
    outside = np.zeros((480, 640), dtype=bool)
    outside[:, :left] = True
    outside[:top, :] = True
    outside[:, 640 - right :] = True
    outside[480 - bottom :, :] = True
    grain = rng.normal(0.0, 8.0, (480, 1)) + rng.normal(0.0, 3.0, (480, 640))
    table = np.asarray(_SURROUNDS[surround], dtype=float)[None, None, :] + grain[..., None]
    if grid:
        lines = np.zeros((480, 640), dtype=bool)
        lines[::40, :] = lines[1::40, :] = True
        lines[:, ::40] = lines[:, 1::40] = True
        table[lines] = (30.0, 30.0, 30.0)
    image[outside] = table[outside]
    return truth, np.clip(np.rint(image), 0, 255).astype(np.uint8)


@settings(max_examples=8, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    surround=st.sampled_from(sorted(_SURROUNDS)),
    widths=st.tuples(*(st.sampled_from((0, 50, 70)) for _ in range(4))).filter(
        lambda w: sum(x > 0 for x in w) >= 3
    ),
    grid=st.booleans(),
)
def test_a_table_around_the_board_is_table_not_blocks(
    seed: int, surround: str, widths: tuple[int, int, int, int], grid: bool
) -> None:
    """A second table colour around a board (a wooden or blue table beyond a grey
    board, as in the real photographs) is table: the blocks on the board are found as
    without it, nothing is found on the table's grain or ruled squares, and the
    overlay's record names it."""
    truth, image = _board_in_a_table(seed, surround, widths, grid)
    rejected: list[Rejection] = []
    found = detect_blocks(image, CAMERA, PerceptionSettings(), rejected)
    assert len(found) == len(truth)
    for block in truth:
        nearest = min(found, key=lambda f: math.dist((f.x, f.y), (block.x, block.y)))
        assert math.dist((nearest.x, nearest.y), (block.x, block.y)) < 0.001
        assert nearest.colour == block.colour
    assert any(r.reason == "table" for r in rejected)


# --------------------------------------------------------------------------- the time budget


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_the_budget_is_read_before_every_hough_transform_and_every_fit(seed: int) -> None:
    """A large region costs many Hough transforms and fits (a real photograph's took
    seconds between two readings of the clock): the budget is read before each, so
    ``--timeout`` stops perception within one fit of its limit."""
    import demoplan.perception.blocks as blocks_module
    from demoplan.budget import check_time as real_check
    from demoplan.perception.hough import hough_squares as real_hough

    events: list[str] = []
    real_fit = blocks_module.fit_square

    def check(where: str = "") -> None:
        events.append("check")
        real_check(where)

    def hough(*args: Any, **kwargs: Any) -> Any:
        events.append("hough")
        return real_hough(*args, **kwargs)

    def fit(*args: Any, **kwargs: Any) -> Any:
        events.append("fit")
        return real_fit(*args, **kwargs)

    with pytest.MonkeyPatch.context() as patched:
        patched.setattr(blocks_module, "check_time", check)
        patched.setattr(blocks_module, "hough_squares", hough)
        patched.setattr(blocks_module, "fit_square", fit)
        truth, image = _board_in_a_table(seed, "wood", (0, 0, 0, 0), grid=False)
        # a disc (no square: every candidate is tried) beside the blocks
        rows, cols = np.ogrid[:480, :640]
        disc = (rows - 60) ** 2 + (cols - 590) ** 2 < 30**2
        image[disc] = (40, 150, 60)
        found = detect_blocks(image, CAMERA)
    assert len(found) == len(truth)
    assert events.count("hough") >= len(truth) + 1
    for before, event in itertools.pairwise(events):
        if event == "hough":
            assert before == "check"
    # a candidate's fits (a coarse one and its refinement at most) follow a reading
    runs = "".join("f" if e == "fit" else "." for e in events).split(".")
    assert max(map(len, runs)) <= 2


# --------------------------------------------------------------------------- the image's border


@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    edge=st.sampled_from(("left", "right", "top", "bottom")),
    cut=st.floats(0.55, 0.85),
    along=st.floats(0.2, 0.8),
)
def test_no_block_is_reported_centred_past_the_border(
    seed: int, edge: str, cut: float, along: float
) -> None:
    """A block whose centre lies past the border (a phone photo's edge through a
    cube, through a strip of ruled table) shows neither its size nor its centre,
    and a fit run off the image has nothing to check it: no block is reported
    centred past the border (what is in view of it may still be taken for smaller
    cubes wholly in view: a strip as wide as a block is one). The blocks inside
    are found as without it."""
    rng = np.random.default_rng(seed)
    inner = Camera(1000.0, (0.1, 0.1))
    truth = random_blocks(int(rng.integers(1, 4)), inner, 300, 200, rng, colours=("red", "blue"))
    side = float(rng.uniform(0.03, 0.075))
    reach = (cut - 0.5) * side  # the centre this far past the border
    x, y = {
        "left": (-reach, along * 0.4),
        "right": (0.5 + reach, along * 0.4),
        "bottom": (along * 0.5, -reach),
        "top": (along * 0.5, 0.4 + reach),
    }[edge]
    cut_block = SyntheticBlock("yellow", x, y, 0.0, side)
    image = render_blocks([*truth, cut_block], CAMERA, noise=2.0, rng=rng)
    rejected: list[Rejection] = []
    found = detect_blocks(image, CAMERA, PerceptionSettings(), rejected)
    assert all(0 <= f.x <= 0.5 and 0 <= f.y <= 0.4 for f in found)
    for block in truth:
        nearest = min(found, key=lambda f: math.dist((f.x, f.y), (block.x, block.y)))
        assert math.dist((nearest.x, nearest.y), (block.x, block.y)) < 0.001
        assert nearest.colour == block.colour


@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    edge=st.sampled_from(("left", "right", "top", "bottom")),
    yaw=st.floats(25.0, 45.0),
    poke=st.floats(0.5, 3.0),
)
def test_a_block_with_a_corner_past_the_border_is_found(
    seed: int, edge: str, yaw: float, poke: float
) -> None:
    """A turned block whose corner pokes ``poke`` px past the border (a few per cent
    of its top: two whole sides in view) is still found, where it is."""
    rng = np.random.default_rng(seed)
    side = float(rng.uniform(0.03, 0.05))
    reach = side / 2 * (math.cos(math.radians(yaw)) + math.sin(math.radians(yaw)))
    inset = reach - poke / 1000.0  # the centre's distance from the border (m)
    x, y = {
        "left": (inset, 0.2),
        "right": (0.5 - inset, 0.2),
        "bottom": (0.25, inset),
        "top": (0.25, 0.4 - inset),
    }[edge]
    block = SyntheticBlock("red", x, y, yaw, side)
    image = render_blocks([block], CAMERA, noise=2.0, rng=rng)
    found = detect_blocks(image, CAMERA)
    assert len(found) == 1
    assert math.dist((found[0].x, found[0].y), (x, y)) < 0.002
