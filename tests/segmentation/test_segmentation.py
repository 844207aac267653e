"""Segmentation: pose streams generated from known demonstrations give those demonstrations back.

Streams come from :func:`demoplan.segmentation.stream_from_demonstration`
(lift–carry–place trajectories, Gaussian noise, chosen rates); a step is
recovered when the object matches and the pose is within 5 mm, in order.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.documents.demonstrations import demonstrations_from_document, load_demonstrations
from demoplan.errors import InputError
from demoplan.fileio import read_document
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.plotting.segmentation import plot_segmentation
from demoplan.rotations import angle_between, quat_from_rpy, quat_from_yaw
from demoplan.segmentation import (
    ObjectTrack,
    PoseStream,
    SegmentationSettings,
    compare_steps,
    load_stream,
    segment,
    stream_from_demonstration,
    write_bag,
    write_csv,
    write_demonstration,
)
from demoplan.segmentation.detect import track_speed
from demoplan.segmentation.readers.csv import quats_from_rpy_array
from tests.support.helpers import EXAMPLES

TOLERANCE = 0.005  # m: the acceptance bound on step poses
SET_TABLE = load_demonstrations([EXAMPLES / "set_table"])


def assert_recovered(expected: Demonstration, found: Demonstration | tuple[Step, ...]) -> None:
    """Every expected step, in order, nothing else, each pose within 5 mm."""
    steps = found.steps if isinstance(found, Demonstration) else found
    assert [s.object for s in steps] == [s.object for s in expected.steps]
    for want, got in zip(expected.steps, steps, strict=True):
        error = math.dist(want.pose.position, got.pose.position)
        assert error < TOLERANCE, f"{want.object}: {error * 1000:.1f} mm off"


def oriented_demo() -> Demonstration:
    return Demonstration(
        "oriented",
        (
            Step("cup", Pose((0.50, 0.40, 0.0), quat_from_yaw(30))),
            Step("box", Pose((0.30, 0.60, 0.0), quat_from_yaw(-90))),
            Step("cup", Pose((0.55, 0.20, 0.0), quat_from_yaw(120))),
        ),
        initial=(
            ("cup", Pose((0.10, 0.10, 0.0), quat_from_yaw(0))),
            ("box", Pose((0.20, 0.25, 0.0), quat_from_yaw(10))),
        ),
    )


# --------------------------------------------------------------------------- detection


@pytest.mark.parametrize("rate_hz", [30, 60, 120])
@pytest.mark.parametrize("noise_m", [0.001, 0.003])
def test_set_table_steps_are_recovered_at_every_rate_and_noise(
    rate_hz: int, noise_m: float
) -> None:
    for index, demo in enumerate(SET_TABLE):
        stream = stream_from_demonstration(demo, rate_hz=rate_hz, noise_m=noise_m, rng=index)
        found = segment(stream)
        assert_recovered(demo, found.to_demonstration())
        assert not found.nudges
        # Initial poses come from each object's first rest.
        initial = found.to_demonstration().initial_poses()
        for name, pose in demo.initial:
            assert math.dist(initial[name].position, pose.position) < TOLERANCE


@pytest.mark.parametrize(
    ("case", "options"),
    [
        ("dropped samples", {"drop_fraction": 0.15}),
        ("uneven sampling", {"rate_jitter": 0.6}),
        ("two hands", {"overlap": 0.6}),
        ("all at once", {"overlap": 0.6, "drop_fraction": 0.1, "rate_jitter": 0.5}),
    ],
)
def test_steps_survive_drops_uneven_rates_and_overlap(case: str, options: dict[str, float]) -> None:
    for index, demo in enumerate(SET_TABLE):
        stream = stream_from_demonstration(demo, rate_hz=30, noise_m=0.003, rng=index, **options)
        assert_recovered(demo, segment(stream).steps)


def test_uneven_sampling_really_is_uneven() -> None:
    stream = stream_from_demonstration(SET_TABLE[0], rate_hz=60, rate_jitter=0.6, rng=1)
    intervals = np.diff(stream.tracks[0].times)
    assert intervals.min() < 0.6 / 60 and intervals.max() > 1.4 / 60
    assert not np.array_equal(stream.tracks[0].times[:10], stream.tracks[1].times[:10])
    dropped = stream_from_demonstration(SET_TABLE[0], rate_hz=60, drop_fraction=0.15, rng=1)
    assert dropped.n_samples < 0.9 * stream.n_samples


def test_two_overlapping_moves_are_two_steps_ordered_by_when_each_comes_to_rest() -> None:
    demo = Demonstration(
        "two-hands",
        (Step("left", Pose((0.2, 0.5, 0.0))), Step("right", Pose((0.8, 0.5, 0.0)))),
        initial=(("left", Pose((0.2, 0.1, 0.0))), ("right", Pose((0.8, 0.1, 0.0)))),
    )
    stream = stream_from_demonstration(demo, rate_hz=60, noise_m=0.002, overlap=0.8, rng=2)
    found = segment(stream)
    first, second = found.moves
    assert (first.object, second.object) == ("left", "right")
    assert second.start < first.end  # really at once
    assert first.end < second.end
    assert_recovered(demo, found.steps)


def test_a_nudge_below_the_threshold_is_not_a_step() -> None:
    settings = SegmentationSettings()
    for index, demo in enumerate(SET_TABLE):
        stream = stream_from_demonstration(
            demo, rate_hz=60, noise_m=0.002, nudges=2, nudge_m=0.01, rng=index
        )
        found = segment(stream, settings)
        assert_recovered(demo, found.steps)
    assert settings.min_distance == 0.02  # the documented threshold: 1 cm is a nudge


def test_a_fast_nudge_is_detected_as_motion_but_kept_out_of_the_steps() -> None:
    demo = Demonstration(
        "nudge",
        (Step("a", Pose((0.5, 0.5, 0.0))), Step("b", Pose((0.3, 0.5, 0.0)))),
        initial=(("a", Pose((0.1, 0.1, 0.0))), ("b", Pose((0.3, 0.1, 0.0)))),
    )
    # A 1.5 cm push within 0.25 s peaks at ~0.11 m/s: faster than start_speed.
    stream = stream_from_demonstration(
        demo, rate_hz=120, noise_m=0.001, nudges=1, nudge_m=0.015, rng=0
    )
    found = segment(stream, SegmentationSettings(start_speed=0.05, stop_speed=0.02))
    assert_recovered(demo, found.steps)
    assert len(found.nudges) == 1
    assert 0.01 < found.nudges[0].distance < 0.02


def test_a_push_beyond_the_threshold_is_reported_not_a_step() -> None:
    demo = Demonstration(
        "push", (Step("a", Pose((0.5, 0.5, 0.0))),), initial=(("a", Pose((0.1, 0.1, 0.0))),)
    )
    stream = stream_from_demonstration(
        demo, rate_hz=60, noise_m=0.001, nudges=1, nudge_m=0.05, rng=0
    )
    found = segment(stream)
    assert [m.object for m in found.moves] == ["a"]
    assert [m.object for m in found.pushes] == ["a"]
    assert 0.045 < found.pushes[0].distance < 0.055


def test_a_move_the_tracker_did_not_see_is_still_a_step() -> None:
    demo = Demonstration(
        "dark", (Step("a", Pose((0.6, 0.4, 0.0))),), initial=(("a", Pose((0.1, 0.1, 0.0))),)
    )
    stream = stream_from_demonstration(demo, rate_hz=60, noise_m=0.002, rng=0)
    track = stream.tracks[0]
    speed = track_speed(track.times, track.positions, 0.4)
    moving = speed > 0.04
    hidden = ~moving | (track.times < track.times[np.argmax(moving)] - 0.3)  # drop the whole carry
    hidden |= track.times > track.times[len(moving) - 1 - np.argmax(moving[::-1])] + 0.3
    dark = PoseStream((ObjectTrack("a", track.times[hidden], track.positions[hidden]),))
    assert np.diff(dark.tracks[0].times).max() > 1.0
    assert_recovered(demo, segment(dark).steps)


def test_a_tracker_glitch_is_not_a_step() -> None:
    times = np.arange(0.0, 6.0, 1 / 60)
    positions = np.tile([0.3, 0.3, 0.0], (times.size, 1))
    positions[180:183] += [0.2, 0.0, 0.0]  # three samples 20 cm away, then back
    found = segment(PoseStream((ObjectTrack("a", times, positions),)))
    assert found.moves == ()
    assert len(found.nudges) == 1


def test_an_object_still_moving_at_the_end_gives_no_step(caplog: pytest.LogCaptureFixture) -> None:
    stream = stream_from_demonstration(SET_TABLE[0], rate_hz=60, noise_m=0.002, rng=0)
    plate = stream.track("plate")
    found_end = segment(stream).moves[0].end
    cut = PoseStream(
        (
            ObjectTrack(
                "plate",
                plate.times[plate.times < found_end - 0.5],
                plate.positions[plate.times < found_end - 0.5],
            ),
        )
    )
    assert segment(cut).moves == ()
    assert "still moving" in caplog.text


@pytest.mark.parametrize("end_rest_s", [1.5, 0.05])
def test_a_rest_the_sizes_given_put_on_no_support_is_named_in_a_warning(
    end_rest_s: float, caplog: pytest.LogCaptureFixture
) -> None:
    """The napkin rests on the plate at 1.5 cm; an objects file with a 3.5 cm
    plate puts the plate's top 2 cm above it, beyond support_tolerance (1 cm):
    the rest cannot be a placement, and the warning says where the napkin lay,
    when, and which top it was measured against — whether the recording goes
    on 1.5 s after the release or stops 0.05 s after it."""
    demo = SET_TABLE[0]
    stream = stream_from_demonstration(
        demo, rate_hz=30, noise_m=0.002, rng=0, end_rest_s=end_rest_s
    )
    geometry = {name: ObjectGeometry("box", (0.05, 0.05, 0.02)) for name in stream.objects}
    geometry["plate"] = ObjectGeometry("cylinder", (0.26, 0.26, 0.035))
    found = segment(stream, geometry=geometry)
    assert [m.object for m in found.moves] == [s.object for s in demo.steps][:-1]
    (warning,) = [r.getMessage() for r in caplog.records if r.name.endswith("detect")]
    assert warning.startswith("napkin: ") and warning.endswith("is not a step")
    assert "on no support within support_tolerance (10 mm; plate's top beneath at 3" in warning
    high = float(warning.split(" mm high")[0].rsplit(" ", 1)[1])
    assert abs(high - 15) < 5  # the napkin's rest (15 mm), from 2 or more samples of 2 mm noise


def test_a_track_that_begins_mid_move_still_gives_the_step_but_no_initial_pose() -> None:
    demo = Demonstration(
        "late", (Step("a", Pose((0.6, 0.4, 0.0))),), initial=(("a", Pose((0.1, 0.1, 0.0))),)
    )
    track = stream_from_demonstration(demo, rate_hz=60, noise_m=0.002, rng=0).tracks[0]
    middle = (segment(PoseStream((track,))).moves[0].start + 0.6) <= track.times
    late = PoseStream((ObjectTrack("a", track.times[middle], track.positions[middle]),))
    found = segment(late)
    assert_recovered(demo, found.steps)
    assert found.initial == ()
    assert found.moves[0].before is None and math.isnan(found.moves[0].distance)


def test_a_turn_in_place_counts_when_large_and_a_wobble_does_not() -> None:
    demo = Demonstration(
        "turns",
        (
            Step("cup", Pose((0.30, 0.30, 0.0), quat_from_yaw(90))),
            Step("box", Pose((0.5, 0.5, 0.0), quat_from_yaw(5))),
        ),
        initial=(
            ("cup", Pose((0.30, 0.31, 0.0), quat_from_yaw(0))),
            ("box", Pose((0.5, 0.51, 0.0), quat_from_yaw(0))),
        ),
    )
    stream = stream_from_demonstration(demo, rate_hz=60, noise_m=0.001, rng=0)
    found = segment(stream)
    assert [m.object for m in found.moves] == ["cup"]
    cup = found.moves[0].pose.orientation
    assert cup is not None and angle_between(cup, quat_from_yaw(90)) < 2.0
    assert [m.object for m in found.nudges] == ["box"]


def test_orientations_are_recovered() -> None:
    demo = oriented_demo()
    found = segment(
        stream_from_demonstration(demo, rate_hz=60, noise_m=0.002, noise_deg=1.0, rng=4)
    )
    assert_recovered(demo, found.steps)
    for want, got in zip(demo.steps, found.steps, strict=True):
        assert want.pose.orientation is not None and got.pose.orientation is not None
        assert angle_between(want.pose.orientation, got.pose.orientation) < 1.0


positions = st.tuples(st.floats(0.05, 0.95), st.floats(0.05, 0.95))


@st.composite
def random_demonstrations(draw: st.DrawFn) -> Demonstration:
    """1–5 steps of 1–4 objects on a 1 m table, each move at least 5 cm long."""
    names = [f"o{i}" for i in range(draw(st.integers(1, 4)))]
    current = {name: draw(positions) for name in names}
    initial = tuple((n, Pose((*current[n], 0.0))) for n in names)
    steps = []
    for _ in range(draw(st.integers(1, 5))):
        name = draw(st.sampled_from(names))
        target = draw(positions.filter(lambda p, c=current[name]: math.dist(p, c) > 0.05))
        current[name] = target
        steps.append(Step(name, Pose((target[0], target[1], 0.0))))
    return Demonstration("random", tuple(steps), initial=initial)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    demo=random_demonstrations(),
    rate_hz=st.floats(30, 120),
    noise_m=st.floats(0.001, 0.003),
    overlap=st.sampled_from([0.0, 0.5]),
    jitter=st.sampled_from([0.0, 0.5]),
    drop=st.sampled_from([0.0, 0.1]),
    seed=st.integers(0, 2**16),
)
def test_random_demonstrations_come_back_in_order(
    demo: Demonstration,
    rate_hz: float,
    noise_m: float,
    overlap: float,
    jitter: float,
    drop: float,
    seed: int,
) -> None:
    stream = stream_from_demonstration(
        demo,
        rate_hz=rate_hz,
        noise_m=noise_m,
        overlap=overlap,
        rate_jitter=jitter,
        drop_fraction=drop,
        rng=seed,
    )
    assert_recovered(demo, segment(stream).steps)


def test_track_speed_of_a_steady_motion_on_an_uneven_clock() -> None:
    rng = np.random.default_rng(0)
    times = np.cumsum(rng.uniform(0.005, 0.03, 400))
    positions = np.outer(times, [0.3, -0.4, 0.0])  # 0.5 m/s
    speed = track_speed(times, positions, 0.4)
    assert np.allclose(speed, 0.5, rtol=1e-9)


def test_settings_are_checked() -> None:
    with pytest.raises(InputError, match="stop_speed"):
        SegmentationSettings(stop_speed=0.2, start_speed=0.1)
    with pytest.raises(InputError, match="min_distance"):
        SegmentationSettings(min_distance=-1.0)
    with pytest.raises(AttributeError):
        SegmentationSettings().min_distance = 0.5  # type: ignore[misc]


def test_compare_steps_scores_order_and_extras() -> None:
    a, b = Step("a", Pose((0.0, 0.0, 0.0))), Step("b", Pose((1.0, 0.0, 0.0)))
    assert compare_steps([a, b], [a, b]).exact
    swapped = compare_steps([a, b], [b, a])
    assert (swapped.matched, swapped.precision, swapped.recall) == (1, 0.5, 0.5)
    extra = compare_steps([a], [a, b])
    assert (extra.precision, extra.recall) == (0.5, 1.0)


# --------------------------------------------------------------------------- demonstrations


def test_to_demonstration_writes_a_demonstration_file(tmp_path: Path) -> None:
    demo = SET_TABLE[0]
    found = segment(stream_from_demonstration(demo, rate_hz=60, noise_m=0.002, rng=0))
    segmented = found.to_demonstration("set-table-1", objects=demo.objects)
    assert segmented.objects == demo.objects
    assert {n for n, _ in segmented.initial} == {n for n, _ in demo.initial}
    path = tmp_path / "demo.json"
    write_demonstration(segmented, path)
    (back,) = demonstrations_from_document(read_document(path), str(path))
    assert back == segmented
    assert_recovered(demo, back)


def test_to_demonstration_landmarks_and_errors() -> None:
    demo = Demonstration(
        "with-board",
        (Step("cup", Pose((0.5, 0.4, 0.0))),),
        landmarks=(("board", Pose((0.4, 0.4, 0.0))),),
        initial=(("cup", Pose((0.1, 0.1, 0.0))),),
    )
    found = segment(stream_from_demonstration(demo, rate_hz=60, noise_m=0.001, rng=0))
    segmented = found.to_demonstration(landmarks=["board"])
    assert [n for n, _ in segmented.landmarks] == ["board"]
    assert [n for n, _ in segmented.initial] == ["cup"]
    with pytest.raises(InputError, match="moved"):
        found.to_demonstration(landmarks=["cup"])
    with pytest.raises(InputError, match="not in the stream"):
        found.to_demonstration(landmarks=["table"])
    still = PoseStream(
        (ObjectTrack("a", np.arange(0, 3, 0.1), np.zeros((30, 3))),), source="still.csv"
    )
    with pytest.raises(InputError, match=r"still\.csv: no pick-and-place step"):
        segment(still).to_demonstration()


def test_plot_shows_speed_and_shaded_moves(tmp_path: Path) -> None:
    found = segment(
        stream_from_demonstration(SET_TABLE[0], rate_hz=30, noise_m=0.002, nudges=1, rng=0)
    )
    path = tmp_path / "speed.png"
    axes = plot_segmentation(found, path)
    assert path.stat().st_size > 10_000
    assert len(axes) == len(SET_TABLE[0].initial)
    assert sum(len(ax.patches) for ax in axes) == len(found.moves) + len(found.nudges)
    assert axes[0].get_ylabel().startswith("plate")


def test_importing_the_package_loads_neither_rosbags_nor_matplotlib() -> None:
    code = (
        "import sys, demoplan.segmentation as s; s.segment; s.load_stream;"
        "print('rosbags' in ' '.join(sys.modules), 'matplotlib' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]


# --------------------------------------------------------------------------- CSV


def assert_same_stream(a: PoseStream, b: PoseStream, atol: float = 0.0) -> None:
    assert a.objects == b.objects
    for x, y in zip(a.tracks, b.tracks, strict=True):
        assert np.allclose(x.times, y.times, atol=atol, rtol=0)
        assert np.allclose(x.positions, y.positions, atol=atol, rtol=0)
        assert (x.orientations is None) == (y.orientations is None)
        if x.orientations is not None and y.orientations is not None:
            same = np.abs(np.sum(x.orientations * y.orientations, axis=1))
            assert np.allclose(same, 1.0, atol=1e-12)


def test_csv_round_trip_is_exact(tmp_path: Path) -> None:
    stream = stream_from_demonstration(oriented_demo(), rate_hz=40, rate_jitter=0.3, rng=0)
    plain = stream_from_demonstration(SET_TABLE[0], rate_hz=40, rng=0)
    for name, source in (("oriented.csv", stream), ("plain.csv", plain)):
        write_csv(source, tmp_path / name)
        back = load_stream(tmp_path / name)
        assert_same_stream(source, back)
        assert back.source == str(tmp_path / name)
    assert (tmp_path / "plain.csv").read_text().splitlines()[0] == "t,object,x,y,z"


def test_csv_orientation_columns_and_row_order(tmp_path: Path) -> None:
    path = tmp_path / "s.csv"
    path.write_text(
        "# a comment\nobject,t,x,y,z,yaw\nb,0.1,1,2,0,90\na,0.0,0.5,0.5,0,0\n\nb,0.0,1,2,0,90\n"
    )
    stream = load_stream(path)
    assert stream.objects == ("b", "a")
    b = stream.track("b")
    assert b.times.tolist() == [0.0, 0.1]
    assert b.orientations is not None
    assert angle_between(tuple(b.orientations[0]), quat_from_yaw(90)) < 1e-9
    path.write_text("t,object,x,y,z,roll,pitch,yaw\n0,a,0,0,0,10,20,30\n")
    q = load_stream(path).tracks[0].orientations
    assert q is not None and angle_between(tuple(q[0]), quat_from_rpy([10, 20, 30])) < 1e-9
    path.write_text("t,object,x,y,z,qx,qy,qz,qw\n0,a,0,0,0,0,0,0,1.05\n")  # noise: normalised
    q = load_stream(path).tracks[0].orientations
    assert q is not None and q[0].tolist() == [0.0, 0.0, 0.0, 1.0]


def test_vectorised_rpy_matches_the_scalar_conversion() -> None:
    angles = np.random.default_rng(0).uniform(-180, 180, (50, 3))
    quats = quats_from_rpy_array(angles)
    for row, q in zip(angles, quats, strict=True):
        assert angle_between(tuple(q), quat_from_rpy(row)) < 1e-6


@pytest.mark.parametrize(
    ("text", "field", "expected"),
    [
        ("t,object,x,y,z\n0,a,0,nan,0\n", "line 2, column 'y'", "finite number"),
        ("t,object,x,y,z\n0,a,0,0,0\n1,a,0,x1,0\n", "line 3, column 'y'", "not a number"),
        ("t,object,x,y\n0,a,0,0\n", "line 1 (header)", "missing column z"),
        ("t,object,x,y,z,qx,qy,qz\n0,a,0,0,0,0,0,0\n", "line 1 (header)", "unknown orientation"),
        ("t,object,x,y,z,roll,yaw\n0,a,0,0,0,0,0\n", "line 1 (header)", "roll,yaw"),
        ("t,object,x,y,z\n0,a,0,0\n", "line 2", "4 cells; 5 expected"),
        ("t,object,x,y,z\n0,,0,0,0\n", "line 2, column 'object'", "empty object"),
        ("t,object,x,y,z\n0,a,0,0,0\n0,a,1,0,0\n", "line 3", "two samples"),
        ("t,object,x,y,z,qx,qy,qz,qw\n0,a,0,0,0,0,0,0,0\n", "line 2", "unit quaternion expected"),
        ("t,object,x,y,z,qx,qy,qz,qw\n0,a,0,0,0,0,0,0,2\n", "line 2", "this one is 2 long"),
        (
            "t,object,x,y,z,qx,qy,qz,qw\n0,a,0,0,0,,,,\n1,a,0,0,0,0,0,0,1\n",
            "line 2",
            "some samples",
        ),
        ("t,object,x,y,z\n", None, "no samples"),
        ("", None, "empty file"),
        ("t,t,object,x,y,z\n", "line 1 (header)", "twice"),
    ],
)
def test_malformed_csv_names_file_and_field(
    tmp_path: Path, text: str, field: str | None, expected: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=expected) as info:
        load_stream(path)
    assert str(path) in str(info.value)
    assert info.value.field == field


def test_missing_input_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        load_stream(tmp_path / "nothing.csv")
    with pytest.raises(InputError, match=r"no metadata\.yaml"):
        load_stream(tmp_path)


# --------------------------------------------------------------------------- ROS 2 bags


@pytest.mark.parametrize(
    ("kind", "storage"), [("tf", "sqlite3"), ("pose", "mcap"), ("tf", "mcap"), ("pose", "sqlite3")]
)
def test_bag_round_trip_gives_the_same_demonstration(
    tmp_path: Path, kind: str, storage: str
) -> None:
    demo = oriented_demo()
    stream = stream_from_demonstration(demo, rate_hz=50, noise_m=0.002, rng=3)
    write_bag(stream, tmp_path / "bag", kind=kind, storage=storage)  # type: ignore[arg-type]
    back = load_stream(tmp_path / "bag")
    assert_same_stream(stream, back, atol=1e-9)  # stamps are whole nanoseconds
    direct = segment(stream).to_demonstration("oriented")
    via_bag = segment(back).to_demonstration("oriented")
    assert_recovered(demo, via_bag)
    assert [s.object for s in via_bag.steps] == [s.object for s in direct.steps]
    for a, b in zip(direct.steps, via_bag.steps, strict=True):
        # Nanosecond stamps can move a sample across a window edge: a 0.1 mm effect.
        assert math.dist(a.pose.position, b.pose.position) < 5e-4
    assert via_bag.initial_poses().keys() == direct.initial_poses().keys()
    # The storage file alone reads as well.
    (storage_file,) = [p for p in (tmp_path / "bag").iterdir() if p.suffix in {".db3", ".mcap"}]
    assert load_stream(storage_file).objects == back.objects


def _write_bag_by_hand(path: Path, demo: Demonstration, storage: str) -> None:
    """A bag as a motion-capture driver writes it: one PoseStamped topic per object,
    header stamps in epoch time; written with rosbags directly (not demoplan)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    stream = stream_from_demonstration(demo, rate_hz=100, noise_m=0.001, rng=5, start_time=1.7e9)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        chatter = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
        writer.write(
            chatter,
            1,
            store.serialize_cdr(types["std_msgs/msg/String"](data="hi"), "std_msgs/msg/String"),
        )
        for track in stream.tracks:
            topic = writer.add_connection(
                f"/vrpn_client_node/{track.name}/pose",
                "geometry_msgs/msg/PoseStamped",
                typestore=store,
            )
            quats = (
                track.orientations
                if track.orientations is not None
                else np.tile([0, 0, 0, 1.0], (len(track), 1))
            )
            for t, p, q in zip(track.times, track.positions, quats, strict=True):
                ns = round(t * 1e9)
                message = types["geometry_msgs/msg/PoseStamped"](
                    header=types["std_msgs/msg/Header"](
                        stamp=types["builtin_interfaces/msg/Time"](
                            sec=ns // 10**9, nanosec=ns % 10**9
                        ),
                        frame_id="world",
                    ),
                    pose=types["geometry_msgs/msg/Pose"](
                        position=types["geometry_msgs/msg/Point"](*map(float, p)),
                        orientation=types["geometry_msgs/msg/Quaternion"](*map(float, q)),
                    ),
                )
                writer.write(
                    topic,
                    ns + 2_000_000,
                    store.serialize_cdr(message, "geometry_msgs/msg/PoseStamped"),
                )


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_bag_written_with_rosbags_round_trips_to_the_demonstration(
    tmp_path: Path, storage: str
) -> None:
    demo = oriented_demo()
    _write_bag_by_hand(tmp_path / "mocap", demo, storage)
    stream = load_stream(tmp_path / "mocap")
    assert set(stream.objects) == {"cup", "box"}
    assert stream.start_time == pytest.approx(1.7e9, abs=1.0)  # header stamps, not receive times
    segmented = segment(stream).to_demonstration("mocap")
    assert_recovered(demo, segmented)
    for want, got in zip(demo.steps, segmented.steps, strict=True):
        assert want.pose.orientation is not None and got.pose.orientation is not None
        assert angle_between(want.pose.orientation, got.pose.orientation) < 2.0


def test_a_bag_without_pose_topics_is_refused(tmp_path: Path) -> None:
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with Writer(tmp_path / "chat", version=9) as writer:
        chatter = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
        writer.write(
            chatter,
            1,
            store.serialize_cdr(
                store.types["std_msgs/msg/String"](data="hi"), "std_msgs/msg/String"
            ),
        )
    with pytest.raises(
        InputError, match=r"no usable topic.*TFMessage.*/chatter \(std_msgs/msg/String\)"
    ) as info:
        load_stream(tmp_path / "chat")
    assert str(tmp_path / "chat") in str(info.value)
    assert info.value.field == "topics"


def test_a_bag_with_a_nan_pose_names_the_topic(tmp_path: Path) -> None:
    times = np.arange(0.0, 1.0, 0.1)
    positions = np.zeros((10, 3))
    positions[4, 1] = np.nan
    stream = PoseStream((ObjectTrack("cup", times, positions),))
    write_bag(stream, tmp_path / "nan", kind="pose")
    with pytest.raises(InputError, match="NaN") as info:
        load_stream(tmp_path / "nan")
    assert info.value.field is not None and "/cup/pose" in info.value.field


@pytest.mark.parametrize("entry", ["nan.db3", "metadata.yaml", "loop.db3"])
def test_a_link_leading_out_of_a_bag_folder_is_refused_before_reading(
    tmp_path: Path, entry: str
) -> None:
    """A bag is read from its own folder: a storage file or metadata.yaml that
    links elsewhere (a valid bag's, which rosbags would read) is refused."""
    stream = PoseStream((ObjectTrack("cup", np.arange(0.0, 1.0, 0.1), np.zeros((10, 3))),))
    write_bag(stream, tmp_path / "nan", kind="pose")
    assert load_stream(tmp_path / "nan").objects == ("cup",)  # read as written
    (tmp_path / "elsewhere").mkdir()
    target = tmp_path / "elsewhere" / entry
    if entry == "loop.db3":  # a link to itself: leads nowhere in the folder
        target = Path(entry)
    else:
        (tmp_path / "nan" / entry).rename(target)
    (tmp_path / "nan" / entry).symlink_to(target)
    for named in (tmp_path / "nan", tmp_path / "nan" / "metadata.yaml"):
        with pytest.raises(InputError, match="a link leading out of the bag's folder") as info:
            load_stream(named)
        assert info.value.source == str(tmp_path / "nan" / entry)
        assert str(target) in str(info.value)


def test_a_corrupt_bag_is_an_input_error(tmp_path: Path) -> None:
    (tmp_path / "broken.mcap").write_bytes(b"not an mcap file at all")
    with pytest.raises(InputError, match=r"broken\.mcap"):
        load_stream(tmp_path / "broken.mcap")


def test_geometry_is_passed_through_only_for_stream_objects() -> None:
    found = segment(stream_from_demonstration(oriented_demo(), rate_hz=30, rng=0))
    geometry = {
        "cup": ObjectGeometry("cylinder", (0.08, 0.08, 0.1)),
        "ghost": ObjectGeometry("box", (1.0, 1.0, 1.0)),
    }
    assert found.to_demonstration(objects=geometry).objects == (("cup", geometry["cup"]),)


def test_a_segmented_demonstration_records_the_thresholds_it_was_made_with() -> None:
    chosen = SegmentationSettings(min_lift=0.02, settle_radius=0.005)
    found = segment(stream_from_demonstration(SET_TABLE[0], rate_hz=30, rng=0), chosen)
    demo = found.to_demonstration()
    recorded = dict(demo.provenance)
    assert recorded["segment.min_lift"] == 0.02 and recorded["segment.settle_radius"] == 0.005
    assert recorded["pushes"] == 0
    from demoplan.documents.demonstrations import demonstration_to_dict

    (again,) = demonstrations_from_document(demonstration_to_dict(demo), "memory")
    assert dict(again.provenance) == recorded
