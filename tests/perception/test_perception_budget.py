"""Perception's time budget on real photographs (docs/limits.md): ``--timeout`` is
read in every expensive loop — between colour regions, before every Hough
transform and fit, and between the blocks of sides a Hough transform votes for —
so wherever it runs out, perception stops there with exit 4 and one line saying
where the time went. And the whole command's start-up: ``demoplan perceive``
imports neither SciPy nor matplotlib nor the stages it does not run. No test
here depends on the machine's speed: the clock is made to run out after a given
number of readings, or the budget is zero; imports are counted, not timed."""

from __future__ import annotations

import contextlib
import math
import random
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy.ndimage import binary_fill_holes
from scipy.spatial.distance import cdist

from demoplan import budget
from demoplan.errors import DemoplanError, LimitReachedError
from demoplan.perception import hough
from demoplan.perception.camera import Camera, load_image
from demoplan.perception.colour_classes import CLASS_SMOOTHING, smoothed_classes
from demoplan.perception.hough import hough_squares
from demoplan.perception.images import perceive_top_view
from demoplan.perception.labelled import load_labelled
from demoplan.perception.masks import SHORT_LABELS, distances, fill_holes, labelled_parts
from demoplan.perception.opencv import cv2
from tests.hostile.harness import check_refused, run

PHOTOS = Path(__file__).parents[1] / "data" / "photos"
LARGEST = "langtable_real"
"""The development set's photograph whose regions are largest (640 × 360 px)."""


def _readings(name: str) -> int:
    """How often perceiving photograph ``name`` reads its clock, with time to spare."""
    count = 0
    expired = budget.Clock.expired

    def counting(self: budget.Clock) -> bool:
        nonlocal count
        count += 1
        return expired(self)

    photo = load_labelled(PHOTOS / f"{name}.json")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(budget.Clock, "expired", counting)
        # a photograph without blocks (exit 1) reads its clock all the same
        with contextlib.suppress(DemoplanError):
            perceive_top_view(photo.image, photo.px_per_m, (0.0, 0.0), timeout=1e9)
    return count


_counted: dict[str, int] = {}


@settings(max_examples=4, deadline=None)
@given(share=st.floats(0.0, 0.99))
def test_a_budget_running_out_anywhere_in_a_real_photograph_stops_it_with_exit_4(
    share: float,
) -> None:
    """The clock runs out at its n-th reading, n anywhere among the readings a whole
    perception of the photograph makes: perception stops there — exit 4, one line
    naming ``--timeout`` and the work under way — instead of running on."""
    total = _counted.setdefault(LARGEST, _readings(LARGEST))
    assert total > 20  # the clock is read often, not only between regions
    stop_at = 1 + int(share * total)
    readings = 0

    def expiring(self: budget.Clock) -> bool:
        nonlocal readings
        readings += 1
        return readings >= stop_at

    photo = load_labelled(PHOTOS / f"{LARGEST}.json")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(budget.Clock, "expired", expiring)
        with pytest.raises(LimitReachedError) as stopped:
            perceive_top_view(photo.image, photo.px_per_m, (0.0, 0.0), timeout=1e9)
    assert readings == stop_at  # stopped at the reading that found the time up
    assert stopped.value.exit_code == 4
    message = str(stopped.value)
    assert "\n" not in message
    assert "--timeout" in message
    assert "coloured regions" in message or "colour region" in message


def test_a_hough_transform_reads_the_clock_between_its_blocks_of_sides() -> None:
    """A large region's vote is many blocks of sides (as many as fit in
    :data:`~demoplan.perception.hough.MAX_CELLS`): the clock is read before each,
    and a clock that has run out stops the vote at its first block."""
    rows, cols = np.mgrid[:200, :300]
    mask = ((np.abs(rows - 100) < 30) & (np.abs(cols - 150) < 30)).astype(float)
    readings: list[int] = []
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(hough, "MAX_CELLS", 1)  # one side at a time
        found = hough_squares(mask, (40.0, 80.0), check=lambda: readings.append(1))
        assert len(readings) == len(hough.side_bins(40.0, 80.0)) == 8  # 40, 44, ..., 77.9
        step = max(hough.S_BIN, hough.SIDE_STEP * 60.0)
        assert found and math.isclose(found[0].side, 60.0, abs_tol=step)

        def out_of_time() -> None:
            raise LimitReachedError("out of time")

        readings.clear()
        with pytest.raises(LimitReachedError):
            hough_squares(mask, (40.0, 80.0), check=out_of_time)


@pytest.mark.parametrize("name", [LARGEST, "mrhan_touching"])
def test_a_zero_budget_on_a_real_photograph_is_exit_4_and_one_line(
    name: str, tmp_path: Path
) -> None:
    """``demoplan perceive PHOTO --timeout 0``: exit 4 and one line naming
    ``--timeout``, nothing written."""
    photo = load_labelled(PHOTOS / f"{name}.json")
    out = tmp_path / "scene.json"
    answer = run(
        [
            "perceive",
            str(photo.image),
            "--px-per-m",
            f"{photo.px_per_m:g}",
            "--origin",
            "0",
            "0",
            "--timeout",
            "0",
            "-o",
            str(out),
        ],
        tmp_path,
    )
    check_refused(answer, ["--timeout 0 s"], codes={4})
    assert not out.exists()


IMPORTED_AFTER = """
import runpy, sys
sys.argv = ["demoplan", *sys.argv[1:]]
try:
    runpy.run_module("demoplan", run_name="__main__")
except SystemExit as stop:
    sys.__stderr__.write(f"exit {stop.code}\\n")
sys.__stderr__.write(" ".join(sorted(sys.modules)) + "\\n")
"""
"""Runs ``demoplan ARGS`` as ``python -m demoplan`` does and writes its exit code and
then every module it imported to stderr."""

NOT_FOR_PERCEIVE = (
    "matplotlib",
    "demoplan.execution",
    "demoplan.scenes",
    "demoplan.studio",
    "demoplan.experiments",
    "demoplan.evaluation",
)
"""What ``demoplan perceive`` of one top view has no use for: other commands' stages
and plotting. (SciPy was a third of its start-up, about 0.4 s of CPU, and demoplan's
perception still uses none of it; numba, which compiles the square fit and the Hough
vote (demoplan/perception/jit.py), imports ``scipy.linalg`` on its first call
whatever the compiled functions use: its start is measured as part of the command
in benchmarks/perception.py.)"""
NOT_FOR_A_TOP_VIEW = ("demoplan.perception.calibration", "demoplan.documents.poses")
"""Modules ``demoplan perceive`` of a top view with ``--px-per-m`` has no use for: a
calibration's and the pose documents' models (pydantic), 0.1 s of CPU each."""


@pytest.mark.parametrize("name", ["mrhan_phone", LARGEST])
def test_demoplan_perceive_imports_only_what_it_needs(name: str, tmp_path: Path) -> None:
    """``demoplan perceive PHOTO --px-per-m S --origin 0 0`` — a photograph with blocks
    and one without (exit 1): the modules the whole command imported hold none of
    :data:`NOT_FOR_PERCEIVE` and :data:`NOT_FOR_A_TOP_VIEW` (the start-up is part of
    the command's time)."""
    photo = load_labelled(PHOTOS / f"{name}.json")
    args = [str(photo.image), "--px-per-m", f"{photo.px_per_m:g}", "--origin", "0", "0"]
    done = subprocess.run(
        [sys.executable, "-c", IMPORTED_AFTER, "perceive", *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        check=False,
        timeout=300,
    )
    *_, exit_line, modules = done.stderr.splitlines()
    assert exit_line == ("exit 0" if photo.needed else "exit 1"), done.stderr
    imported = modules.split()
    assert "demoplan.perception.blocks" in imported  # it did perceive
    unwanted = [m for m in imported if m.split(".")[0] in NOT_FOR_PERCEIVE]
    unwanted += [m for m in imported if ".".join(m.split(".")[:2]) in NOT_FOR_PERCEIVE]
    unwanted += [m for m in imported if m in NOT_FOR_A_TOP_VIEW]
    assert unwanted == []


@settings(max_examples=30, deadline=None)
@given(
    st.integers(1, 4).flatmap(
        lambda d: st.tuples(
            hnp.arrays(
                np.float64, st.tuples(st.integers(1, 50), st.just(d)), elements=st.floats(-300, 300)
            ),
            hnp.arrays(
                np.float64, st.tuples(st.integers(1, 6), st.just(d)), elements=st.floats(-2, 2)
            ),
        )
    )
)
def test_the_colour_distances_are_scipy_s_to_the_last_bit(
    arrays: tuple[np.ndarray, np.ndarray],
) -> None:
    """The distances colours are classified by (computed without importing SciPy)
    are ``cdist``'s exactly: a pixel on a tie between two palette colours goes the
    same way."""
    points, centres = arrays
    assert np.array_equal(distances(points, centres), cdist(points, centres))


@settings(max_examples=30, deadline=None)
@given(
    st.floats(1.0, 1e5),
    st.tuples(st.floats(-10.0, 10.0), st.floats(-10.0, 10.0)),
    st.integers(1, 5000),
    hnp.arrays(np.int32, st.tuples(st.integers(1, 60), st.just(2)), elements=st.integers(0, 5000)),
)
def test_an_outline_goes_to_the_world_as_each_of_its_points_does(
    px_per_m: float, origin: tuple[float, float], height: int, outline: np.ndarray
) -> None:
    """A rejected region's outline (whole pixels, x right, y down) converted at once
    gives, to the last bit, what :meth:`Camera.to_world` gives for each point's
    pixel centre (the overlays and the rejections' outlines do not move)."""
    camera = Camera(px_per_m, origin)
    each = tuple(camera.to_world(float(x) + 0.5, height - float(y) - 0.5) for x, y in outline)
    assert camera.image_outline_to_world(outline, height) == each


@settings(max_examples=60, deadline=None)
@given(
    hnp.arrays(np.bool_, st.tuples(st.integers(1, 40), st.integers(1, 40)), elements=st.booleans()),
)
def test_holes_are_filled_as_scipy_fills_them(mask: np.ndarray) -> None:
    """The holes of a mask (filled without importing SciPy, by one flood fill of its
    outside) are ``binary_fill_holes``' exactly: the outside's parts, 4-connected,
    that do not reach the crop's border."""
    assert np.array_equal(fill_holes(mask), binary_fill_holes(mask))


def _same_parts_as_int32_labels(mask: np.ndarray, connectivity: int) -> None:
    count, labels, stats = labelled_parts(mask, connectivity)
    expected = cv2.connectedComponentsWithStats(
        mask.astype(np.uint8), connectivity=connectivity, ltype=cv2.CV_32S
    )
    assert count == expected[0]
    assert np.array_equal(labels, expected[1])
    assert np.array_equal(stats, expected[2])


@settings(max_examples=40, deadline=None)
@given(
    hnp.arrays(np.bool_, st.tuples(st.integers(1, 60), st.integers(1, 60)), elements=st.booleans()),
    st.sampled_from([4, 8]),
)
def test_parts_labelled_in_16_bits_are_those_labelled_in_32(
    mask: np.ndarray, connectivity: int
) -> None:
    """A sparse mask's parts, labelled in 16 bits for speed, have the labels (in the
    same order) and the boxes and areas that 32-bit labels give them."""
    _same_parts_as_int32_labels(mask, connectivity)


@pytest.mark.parametrize("connectivity", [4, 8])
def test_a_photographs_dense_foreground_is_labelled_right_in_16_bits(connectivity: int) -> None:
    """A photograph-sized foreground (1280 × 720, half its pixels set in blobs and
    specks: far more than 65,535 pixels, fewer runs): its 16-bit labels are the
    32-bit ones."""
    rng = np.random.default_rng(5)
    noise = cv2.blur(rng.random((720, 1280)).astype(np.float32), (25, 25))
    mask = noise > np.median(noise)
    assert labelled_parts(mask)[1].dtype == np.uint16  # labelled in 16 bits
    _same_parts_as_int32_labels(mask, connectivity)


def test_a_photographs_sparse_parts_are_labelled_right_in_16_bits() -> None:
    """A photograph-sized mask (1600 × 1200) with a few hundred parts spread over
    every row, 8- and 4-connected: the 16-bit labels are the 32-bit ones, whatever
    the stripes OpenCV may label the rows in."""
    rng = np.random.default_rng(3)
    mask = np.zeros((1600, 1200), dtype=bool)
    for row, col in zip(rng.integers(0, 1597, 400), rng.integers(0, 1197, 400), strict=True):
        mask[row : row + rng.integers(1, 4), col : col + rng.integers(1, 4)] = True
    for connectivity in (4, 8):
        _same_parts_as_int32_labels(mask, connectivity)


@pytest.mark.parametrize("extra", [-1, 0, 1])
def test_a_mask_of_as_many_runs_as_16_bits_hold_is_labelled_right(extra: int) -> None:
    """Around the number of runs of set pixels where the labels go from 16 to 32
    bits, each pixel of a checkerboard a run and a part of its own (4-connected):
    the labels are still right."""
    side = 512
    board = (np.add.outer(np.arange(side), np.arange(side)) % 2 == 0).ravel()
    kept = np.flatnonzero(board)[: SHORT_LABELS + extra]
    mask = np.zeros(side * side, dtype=bool)
    mask[kept] = True
    _same_parts_as_int32_labels(mask.reshape(side, side), 4)


@settings(max_examples=20, deadline=None)
@given(
    hnp.arrays(
        np.uint8, st.tuples(st.integers(1, 30), st.integers(1, 30), st.sampled_from([3, 4]))
    ),
    st.booleans(),
)
def test_a_png_decoded_by_opencv_has_pils_pixels(
    tmp_path_factory: pytest.TempPathFactory, pixels: np.ndarray, optimised: bool
) -> None:
    """An 8-bit RGB or RGBA PNG (decoded by OpenCV, for speed) loads as PIL reads it,
    alpha dropped, the colours under it kept."""
    from PIL import Image

    path = tmp_path_factory.mktemp("png") / "image.png"
    Image.fromarray(pixels).save(path, optimize=optimised)
    with Image.open(path) as opened:
        expected = np.asarray(opened.convert("RGB"))
    assert np.array_equal(load_image(path), expected)


def test_the_development_photographs_load_as_pil_reads_them() -> None:
    """The development set's photographs (8-bit RGB PNGs, decoded by OpenCV) load
    with PIL's pixels."""
    from PIL import Image

    for label in sorted(PHOTOS.glob("*.json")):
        image = load_labelled(label).image
        with Image.open(image) as opened:
            expected = np.asarray(opened.convert("RGB"))
        assert np.array_equal(load_image(image), expected), image.name


@settings(max_examples=40, deadline=None)
@given(
    hnp.arrays(np.bool_, st.tuples(st.integers(1, 30), st.integers(1, 30)), elements=st.booleans()),
    st.integers(1, 4),
    st.randoms(use_true_random=False),
)
def test_the_classes_smoothed_by_counts_are_those_by_mean(
    core: np.ndarray, kinds: int, draw: random.Random
) -> None:
    """Each core pixel's class, the most common in the square around it, counted in
    8 bits, is the one whose 0/1 mask's mean over the square (a float blur) is
    largest, the first of a tie the same."""
    classes = np.array([draw.randrange(kinds) for _ in range(int(core.sum()))])
    labels = np.unique(classes)
    size = (CLASS_SMOOTHING, CLASS_SMOOTHING)
    means = []
    for label in labels:
        mask = np.zeros(core.shape, dtype=np.float32)
        mask[core] = classes == label
        means.append(np.asarray(cv2.blur(mask, size))[core])
    expected = classes if labels.size < 2 else labels[np.argmax(np.stack(means, axis=1), axis=1)]
    assert np.array_equal(smoothed_classes(classes, core), expected)
