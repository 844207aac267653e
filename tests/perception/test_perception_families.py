"""Block perception on the generated photograph families (issue 41, docs/perception.md
"Generated families"): renders carrying what makes real photographs hard — cubes
touching in rows, stacks, black and white cubes, patterned tops, hands, side faces,
over-exposure, small cubes, a camera tilted up to 30°, shapes that are no cubes —
scored as the real photographs are (demoplan.perception.labelled: a top face is
found by a detection within 0.6 of its side of its centre).

The acceptance is the issue's, by hypothesis over each family: at least 90 % of the
labelled, non-partial top faces found and at most one false block per image (none in
a photograph without cubes: the shapes photograph of the real set), with ``--side``
given or not, for every family but those out of reach (:data:`OUT_OF_REACH`); draws
seen failing are named (:data:`NOT_YET`, strict xfails). Each example renders one
1280 × 720 image and perceives it, so the counts are small and failing examples are
not shrunk (a smaller seed is no simpler a photograph). The other tests check the
families' truth itself: where the labels put the tops, how much of a face is in
view, the tilted camera's mapping, and that a saved case reads back as the real
photographs' labels do."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from demoplan.perception.labelled import load_labelled, score_detections
from demoplan.perception.photo_families import (
    ACHROMATIC,
    CHROMATIC,
    FAMILIES,
    HIDDEN_BELOW,
    PARTIAL_BELOW,
    family_case,
    perceive_case,
    save_case,
)
from demoplan.perception.photo_families_scene import (
    BACKGROUNDS,
    Cube,
    Hand,
    PhotoScene,
    render_scene,
)
from demoplan.perception.photos import PhotoRig, light_falloff, top_camera

EXPENSIVE = settings(
    deadline=None,
    phases=(Phase.explicit, Phase.reuse, Phase.generate),
    suppress_health_check=[HealthCheck.too_slow],
)
SEEDS = st.integers(0, 2**31 - 1)


# --------------------------------------------------------------------------- the acceptance


NOT_YET: dict[str, tuple[str, tuple[tuple[int, bool], ...]]] = {
    # family: (what is missed, draws (seed, --side given) on which the detector fails today)
    "achromatic": (
        "a black top on the board whose side faces, as dark, and the grid lines beside "
        "them are one part with it (not square, not compact: 30, 40, 66 without --side, 70 "
        "with it)",
        (
            (30, False),
            (40, False),
            (66, False),
            (70, True),
        ),
    ),
    "patterned": (
        "with --side a white frame on a blue top on the board (the blue rim outside it "
        "broken, the frame rings nothing); with --side a yellow top with dots and a glint on "
        "the blue table, 'not square' (misfit 0.21: the dot the glint lights, 11 L* under the "
        "table, is not taken for print and opens to the edge) (52)",
        (
            (14, True),
            (52, True),
        ),
    ),
    "touching_rows": (
        "a new seed tried at a stop, not looked into yet: 11 of 13 tops found without "
        "--side, 8 of 13 with it (7777)",
        ((7777, False), (7777, True)),
    ),
    "tipped_rows": (
        "the faces of cubes lying tipped over in a row taken for tops",
        ((2, False), (2, True)),
    ),
}
"""Draws seen failing while developing, by family, each with what is missed (not
every failing draw: the benchmark below gives the rate) — named draws, not
hypothesis's: its derandomized draws change with its version, so a
strict xfail over them passed or failed by the version installed. The day one of
these draws passes, its test says so (strict). How often each family fails over
many seeds: ``python benchmarks/perception_families.py --first 0 --last 80``."""

OUT_OF_REACH = {
    "tipped_rows": "a cube lying tipped over is a standing cube seen off the camera's "
    "axis to one picture without the camera's position (docs/perception.md, Limits)",
}
"""Families left out of the hypothesis acceptance, with why: ``tipped_rows`` is not
one of the cases the real photographs' thresholds are asked of and is documented
as a limit."""


def _meets_the_thresholds(family: str, seed: int, side_given: bool) -> None:
    case = family_case(family, seed)
    run = perceive_case(case, side_given=side_given)
    assert run.exit_code == 0, run.error
    score = run.score
    assert score.found >= 0.9 * score.needed, (case.name, side_given, score)
    assert score.false <= (1 if score.needed else 0), (case.name, side_given, score)


@pytest.mark.parametrize("family", sorted(set(FAMILIES) - set(OUT_OF_REACH)))
@settings(EXPENSIVE, max_examples=4, derandomize=True)  # the same draws for one hypothesis
@given(seed=SEEDS, side_given=st.booleans())
def test_a_family_photograph_meets_the_issue_thresholds(
    family: str, seed: int, side_given: bool
) -> None:
    _meets_the_thresholds(family, seed, side_given)


@pytest.mark.parametrize(
    ("family", "seed", "side_given"),
    [
        pytest.param(family, seed, side, marks=pytest.mark.xfail(strict=True, reason=reason))
        for family, (reason, draws) in sorted(NOT_YET.items())
        for seed, side in draws
    ],
)
def test_a_family_not_met_yet_fails_where_it_was_seen_failing(
    family: str, seed: int, side_given: bool
) -> None:
    _meets_the_thresholds(family, seed, side_given)


MET_SINCE: dict[str, tuple[tuple[int, bool], ...]] = {
    # family: draws (seed, --side given) it once failed on and meets now
    # pentagons of a cube's colour and size, a square fitted inside each: their
    # outline has five corners (demoplan.perception.shapes)
    "distractors": ((2147483646, False),),
    # a fingertip over a top: the pixels it hides do not count against the top's
    # square (demoplan.perception.occlusion), also where the hand and forearm are
    # a second table (with --side); a yellow or purple top beside a forearm: the
    # forearm's shading, rim and shadow that its second table leaves foreground
    # joined the top's class and made it "larger than its squares" (they no longer
    # count in its size: demoplan.perception.masks.TableReach)
    "hands": ((126342, False), (126342, True), (1, True), (9, False), (9, True)),
    "achromatic": (
        (5, True),
        (23, True),
        (40, True),
        # a board's grid line a few px off a black top's side, fused to it: a
        # straight line running on past the part at both ends, nearly along its
        # side, is dropped from it (demoplan.perception.fused_lines)
        (21, True),
        (27, False),
        # a glint near a grey top's edge on paper: the opening broke the rim of top
        # between its hole and the edge, and the hole was a notch; the dark pixels
        # within the part's rectangle that enclose a round hole inside it are given back
        # (achromatic._rims_given_back)
        (29, True),
        (61, False),
        (61, True),
        (75, True),
        (80, True),
        # a black top with its side faces in one dark part, beside its grid line: a
        # square at the photograph's block size fits it (blocks._second_look)
        (72, False),
        # a white top on white paper lit as the paper, 2-3 L* over it (under the bright
        # contrast): its side faces in shade, a band of real width along its near edges,
        # and its shading edge all round outline it (demoplan.perception.faint_white)
        (46, False),
        (46, True),
        (59, False),
        (59, True),
        (64, False),
        (64, True),
        (105, False),
    ),
    # a frame printed round a coloured top rings the plain face inside it, larger
    # than the ring: filled as the top's (demoplan.perception.highlights.printed)
    "patterned": (
        (1, False),
        (4, False),
        (4, True),
        (16, False),
        (19, False),
        (6, False),
        (1, True),
        (9, True),
        # a white top with a frame fitted at its print's 24 mm, rejected by the size
        # check, is looked at again at the block size (sizes.looked_again)
        (0, False),
        # a letter on an orange or yellow top on the grey board: its blurred edge, left
        # as thin holes as light as the board once the glint rule filled its body, is
        # judged with the body (the holes as they were before that rule: printed)
        (2, True),
        (3, True),
        (8, True),
        # a frame on a white top, on paper or the board: the frame, a dark ring thinner
        # than the opening, rings a bright face; with that face it is the top's
        # (demoplan.perception.highlights.framed_on_white)
        (0, True),
        (7, True),
        # a black H on a white top on paper: its hole, with its blurred rim 0.31 of the
        # white part, was taken for a marker's cells, and without --side it is larger
        # than a block of the smallest side; a letter's ink (its dark pixels) is judged
        # against the marker share, and its size against none
        # (demoplan.perception.achromatic._printed_on_white)
        (28, False),
        (28, True),
        # a white top with dots or a letter on the blue table beside its grey side face:
        # its component's one class was its rim (the table's blue mixed with its edges
        # and shadow), whose soft mask took the top and side face as a glint, "not
        # filled"; a region coloured at its rim alone, mostly without hue, is left to the
        # black, white and grey search (demoplan.perception.colour_classes.without_rims)
        (42, False),
        (162408, False),
        # a white top with a letter or dots on white paper lit as the paper (an L 2.5 L*
        # over it): outlined by its side faces in shade and its shading edge
        # (demoplan.perception.faint_white)
        (29, False),
        (29, True),
        (444, True),
        (2427, False),
        (2427, True),
    ),
    # a top whose side faces, darker and larger than it, stayed in its mask: it
    # alone covered under half of the region (acceptance.explained_share)
    "side_faces": ((536870913, True),),
    # a row's next top of one hue, a little darker, read as the end cube's side
    # strip: the strips pointed along the rows, the nadir hundreds of px off, and a
    # row's cube of another colour was taken for a stack's side face (stack_sides)
    # a square fitted at a row's end took the row's width (its tops and the side
    # faces across it) and reached past the seam into the next top, cut short then:
    # a block is fitted again up to the seams along its shared sides (blocks)
    "touching_rows": ((2, False), (3, False), (3, True), (6, True), (12, True), (25, True)),
    # the lit faces of a row lying tipped over near the image's centre, each beside
    # a darker face a third of the side deep pointing away from the centre, where a
    # standing cube shows a few px: no tops (stack_sides.upturned_faces)
    "tipped_rows": ((1, False), (1, True)),
}
"""Draws seen failing and met now (a crop's closing, a glint's notch, a letter
printed on a coloured or a white top, a top's side faces): kept met, also while
the rest of their family (in :data:`NOT_YET`) is not."""


@pytest.mark.parametrize(
    ("family", "seed", "side_given"),
    [(family, seed, side) for family, draws in sorted(MET_SINCE.items()) for seed, side in draws],
)
def test_a_family_draw_once_failed_meets_the_issue_thresholds(
    family: str, seed: int, side_given: bool
) -> None:
    _meets_the_thresholds(family, seed, side_given)


# --------------------------------------------------------------------------- the truth


@settings(EXPENSIVE, max_examples=8, derandomize=True)  # see the white cube below
@given(family=st.sampled_from(sorted(FAMILIES)), seed=SEEDS)
def test_a_labelled_centre_shows_its_cubes_top(family: str, seed: int) -> None:
    """Around each labelled centre of a plain top in full view the photograph has
    that cube's colour: of the cubes' colours and the table's, in the light that
    falls there, the median colour of a disc half the side across is nearest to
    it (a glint and the noise do not move it to another)."""
    case = family_case(family, seed)
    if case.scene.exposure != 1.0:
        return  # over-exposure clips colours on purpose
    palette = {**CHROMATIC, **ACHROMATIC, "table": BACKGROUNDS[case.scene.background]}
    rows, cols = np.mgrid[: case.label.height, : case.label.width]
    for truth in case.truths:
        if truth.in_view < 0.99 or truth.cube.pattern:
            continue
        disc = (cols - truth.u) ** 2 + (rows - truth.v) ** 2 <= (truth.side_px / 4) ** 2
        seen = np.median(case.image[disc].astype(float), axis=0)
        light = light_falloff(case.scene.rig)[round(truth.v), round(truth.u)]
        nearest = min(
            palette, key=lambda name: float(np.linalg.norm(seen - light * np.array(palette[name])))
        )
        assert nearest == truth.cube.colour, (case.name, truth.cube, seen)


@pytest.mark.xfail(
    strict=True,
    reason="found by the test above on a random draw: a white cube on white paper reads "
    "(204, 204, 200) at its centre, nearer the paper in that light than white",
)
def test_a_white_cube_on_white_paper_is_seen_white() -> None:
    """A known defect of the achromatic family's light (or of this check's light
    model), kept in view until it is understood."""
    test_a_labelled_centre_shows_its_cubes_top.hypothesis.inner_test(  # type: ignore[attr-defined]
        family="achromatic", seed=11296
    )


@settings(EXPENSIVE, max_examples=8)
@given(family=st.sampled_from(sorted(FAMILIES)), seed=SEEDS)
def test_the_label_is_the_cubes_in_view(family: str, seed: int) -> None:
    """A cube's top face is labelled when 30 % or more of it is in view, partial
    under 85 %; a straight-down camera's label is the exact top-down camera of the
    plane of the tops (photos.top_camera) for cubes standing on the table, and
    detections at the labelled centres find every face."""
    case = family_case(family, seed)
    label = case.label
    labelled = [t for t in case.truths if t.in_view >= HIDDEN_BELOW]
    assert len(label.blocks) == len(labelled)
    assert label.needed == sum(t.in_view >= PARTIAL_BELOW for t in labelled)
    assert all(0 <= b.u < label.width and 0 <= b.v < label.height for b in label.blocks)
    rig = case.scene.rig
    if not rig.tilt:
        camera = top_camera(rig, label.side_m[0])
        assert label.px_per_m == pytest.approx(camera.px_per_m)
        for truth in labelled:
            if truth.cube.z == 0:
                u, v = camera.to_pixels(truth.cube.x, truth.cube.y)
                assert truth.u == pytest.approx(u - 0.5, abs=1e-6)
                assert truth.v == pytest.approx(label.height - v - 0.5, abs=1e-6)
                assert truth.side_px == pytest.approx(truth.cube.side * camera.px_per_m)
    centres = [
        ((b.u + 0.5) / label.px_per_m, (label.height - b.v - 0.5) / label.px_per_m)
        for b in label.blocks
    ]
    score = score_detections(label, centres)
    assert (score.found, score.false) == (label.needed, 0)


def _one_cube_scene(cube: Cube, hands: tuple[Hand, ...] = ()) -> PhotoScene:
    rig = PhotoRig(height=1.2, nadir=(0.3, 0.2))
    return PhotoScene(rig, (cube,), hands=hands, background="paper", glints=0.0)


@settings(max_examples=10, deadline=None)
@given(inside=st.floats(-0.4, 1.4), seed=SEEDS)
def test_the_share_in_view_of_a_top_cut_by_the_border(inside: float, seed: int) -> None:
    """A top face (turned square to the image) whose left ``inside`` share lies
    in the image: that share is in view, to the canvas' sampling."""
    rig = _one_cube_scene(Cube("red", (200, 40, 40), 0.0, 0.0, 0.0, 0.04)).rig
    scale = rig.scale_at(0.0, 0.0, 0.04)
    left_edge, _ = rig.to_table(0.0, 360.0, 0.04)
    x = left_edge + (inside - 0.5) * 0.04  # the face's centre
    cube = Cube("red", (200, 40, 40), x, 0.2, 0.0, 0.04)
    _, (truth,) = render_scene(_one_cube_scene(cube), np.random.default_rng(seed), noise=0.0)
    assert truth.in_view == pytest.approx(min(1.0, max(0.0, inside)), abs=2.0 / (0.04 * scale))


def test_a_hand_over_a_cube_and_a_cube_on_a_cube_hide_its_top() -> None:
    rng = np.random.default_rng(1)
    cube = Cube("blue", (40, 80, 190), 0.3, 0.2, 10.0, 0.04)
    _, (alone,) = render_scene(_one_cube_scene(cube), rng)
    assert alone.in_view >= 0.99
    palm = Hand(0.3, 0.2, 30.0, 0.085, (224, 172, 140))
    _, (under_hand,) = render_scene(_one_cube_scene(cube, (palm,)), rng)
    assert under_hand.in_view < HIDDEN_BELOW
    fingers = Hand(0.3 - 0.02 - 0.09, 0.2, 0.0, 0.085, (224, 172, 140))  # fingertips over it
    _, (touched,) = render_scene(_one_cube_scene(cube, (fingers,)), rng)
    assert HIDDEN_BELOW <= touched.in_view < PARTIAL_BELOW
    upper = Cube("red", (200, 40, 40), 0.3, 0.2, 10.0, 0.04, z=0.04)
    scene = PhotoScene(_one_cube_scene(cube).rig, (cube, upper), background="paper")
    _, (lower, top) = render_scene(scene, rng)
    assert lower.in_view == 0.0 and top.in_view >= 0.99
    assert top.side_px > lower.side_px  # nearer the camera


@settings(max_examples=60, deadline=None)
@given(
    tilt=st.floats(0.0, 30.0),
    towards=st.floats(0.0, 360.0),
    u=st.floats(0.0, 1280.0),
    v=st.floats(0.0, 720.0),
    z=st.floats(0.0, 0.12),
)
def test_a_tilted_camera_maps_the_table_and_back(
    tilt: float, towards: float, u: float, v: float, z: float
) -> None:
    """Pixel → table (at height z) → pixel is the identity; the scale grows towards
    the camera and is the straight-down camera's focal / distance without a tilt."""
    rig = PhotoRig(tilt=tilt, tilt_towards=towards)
    x, y = rig.to_table(u, v, z)
    back = rig.to_pixels(x, y, z)
    assert math.dist(back, (u, v)) < 1e-6
    if tilt == 0:
        assert rig.scale_at(x, y, z) == pytest.approx(rig.focal / (rig.height - z), rel=1e-6)
    elif tilt > 1:
        a = math.radians(towards)
        nearer = (x - 0.05 * math.cos(a), y - 0.05 * math.sin(a))  # back towards the camera
        assert rig.scale_at(*nearer, z) > rig.scale_at(x, y, z)


def test_a_saved_case_reads_back_as_a_real_photographs_label(tmp_path: Path) -> None:
    case = family_case("stacks", 3)
    again = family_case("stacks", 3)
    assert np.array_equal(case.image, again.image) and case.label == again.label
    read = load_labelled(save_case(case, tmp_path))
    assert (read.width, read.height, read.needed) == (1280, 720, case.label.needed)
    assert read.px_per_m == pytest.approx(case.label.px_per_m, abs=1e-3)
    for saved, block in zip(read.blocks, case.label.blocks, strict=True):
        assert (saved.u, saved.v, saved.side_px) == pytest.approx(
            (block.u, block.v, block.side_px), abs=0.01
        )
        assert saved.partial == block.partial
    assert read.image.is_file()


def test_shapes_and_hands_are_labelled_as_no_cubes() -> None:
    case = family_case("distractors", 2)
    assert case.scene.shapes and len(case.label.blocks) == len(case.scene.cubes)
    kinds = [entry["kind"] for entry in case.document["non_cubes"]]
    assert kinds == [shape.kind for shape in case.scene.shapes]
    held = family_case("hands", 2)
    assert [e["kind"] for e in held.document["non_cubes"]] == ["hand and forearm"] * len(
        held.scene.hands
    )


_EDGES = ((-1, -1), (-1, 1), (1, -1), (1, 1))
"""The four long edges of a tipped row: ± its two rolled axes across."""


@settings(max_examples=4, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_a_tipped_row_lies_on_the_table_shows_upturned_faces_and_is_no_cube(seed: int) -> None:
    """A row of cubes lying tipped over rests on its lowest edge (no corner below the
    table, one on it), is labelled as no cube, and shows each cube's colour: at the
    middle of each cube seen from the camera (its highest edge, nearest the camera)
    the photograph is nearer that cube's colour than the table's."""
    case = family_case("tipped_rows", seed)
    rows = case.scene.tipped
    assert rows and len(case.label.blocks) == len(case.scene.cubes)
    tipped = [e for e in case.document["non_cubes"] if "tipped" in e["kind"]]
    assert len(tipped) == len(rows)
    table = np.asarray(BACKGROUNDS[case.scene.background], dtype=float)
    rig = case.scene.rig
    for row in rows:
        centre, along, first, second = row.frame()
        heights = [float((centre + (j * first + k * second) * row.side / 2)[2]) for j, k in _EDGES]
        assert min(heights) == pytest.approx(0.0, abs=1e-9)
        for index, rgb in enumerate(row.rgbs):
            middle = centre + (index - (len(row.colours) - 1) / 2) * row.side * along
            edges = [middle + (j * first + k * second) * row.side / 2 for j, k in _EDGES]
            highest = max(edges, key=lambda point: float(point[2]))
            probe = (middle + highest) / 2  # on an upturned face, halfway to the top edge
            u, v = rig.to_pixels(float(probe[0]), float(probe[1]), float(probe[2]))
            row_px, col_px = round(rig.height_px - v - 0.5), round(u - 0.5)
            if not (0 <= row_px < rig.height_px and 0 <= col_px < rig.width):
                continue
            seen = case.image[row_px, col_px].astype(float)
            tint = seen / max(float(seen.max()), 1.0)  # the colour, whatever the shade
            colour = np.asarray(rgb, dtype=float)
            nearer = np.linalg.norm(tint - colour / colour.max())
            assert nearer < np.linalg.norm(tint - table / table.max()), (seen, colour, table)
