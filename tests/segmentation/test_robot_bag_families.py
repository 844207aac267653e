"""Robot bags of table settings over generated families (hypothesis).

A robot's ROS 2 bag (map → odom (moving) → table → objects, as
``test_segment_cli._robot_bag``) of a table being set: a plate carried first,
then objects set on the table or on the plate — the last one, like
Experiment 1's napkin, most often on the plate. The families vary what a
real robot's tracking gives: 1–3 mm of noise, 20–60 Hz, the objects' heights
in the objects file off by up to 5 mm (the CLI test's plate is 2 cm where its
stream's plate is 1.5 cm), and a last release 0.3–1.5 s before the recording
stops. Every step must come out, in order.

The weakness these families were made for: an object set on the plate was
judged against the plate's height read from one sample (the one at the end
of the object's rest). One draw of 2 mm noise at +6.5 mm (3.2 σ) put the
plate's top 11.6 mm above the napkin resting on it, more than
``support_tolerance`` (10 mm), so the napkin's rest was taken for a pause in
the air and its step was lost; the plate is now read over the napkin's pose
window (docs/segmentation.md, step 5).
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.segmentation import load_stream, segment, stream_from_demonstration, write_bag
from demoplan.segmentation.detect import Move
from tests.segmentation.test_tf_tree import robot_tree

BOX = 0.02  # m: the true height of every object but the plate
GEOMETRY_ERROR = 0.005  # m: how far the objects file's heights may be off


@st.composite
def table_settings(draw: st.DrawFn) -> tuple[Demonstration, dict[str, ObjectGeometry]]:
    """A plate (1–2.5 cm high) carried to the middle of the table, then 2–6
    objects, each set on the plate (within 6 cm of its centre, each in its own
    direction) or on the table (25 cm around it); and the objects file's
    geometry, each height off by up to ``GEOMETRY_ERROR``."""
    count = draw(st.integers(2, 6))
    plate_h = draw(st.floats(0.01, 0.025))
    cx, cy = draw(st.floats(0.45, 0.55)), draw(st.floats(0.40, 0.50))
    names = [f"o{i}" for i in range(count)]
    initial = [("plate", Pose((0.15, 0.2, 0.0)))]
    initial += [(name, Pose((0.1 + 0.08 * i, 0.0, 0.0))) for i, name in enumerate(names)]
    steps = [Step("plate", Pose((cx, cy, 0.0)))]
    for i, name in enumerate(names):
        if draw(st.booleans()) or (i == count - 1 and draw(st.integers(0, 4)) > 0):
            r, a = draw(st.floats(0.0, 0.06)), 2 * math.pi * i / count  # apart on the plate
            steps.append(Step(name, Pose((cx + r * math.cos(a), cy + r * math.sin(a), plate_h))))
        else:
            a = 2 * math.pi * i / count
            steps.append(Step(name, Pose((cx + 0.25 * math.cos(a), cy + 0.25 * math.sin(a), 0.0))))
    # Half the heights off by the most the family allows: the margin left for
    # the noise within support_tolerance is smallest there.
    errors = st.sampled_from([-GEOMETRY_ERROR, GEOMETRY_ERROR]) | st.floats(
        -GEOMETRY_ERROR, GEOMETRY_ERROR
    )
    geometry = {name: ObjectGeometry("box", (0.05, 0.05, BOX + draw(errors))) for name in names}
    geometry["plate"] = ObjectGeometry("cylinder", (0.26, 0.26, plate_h + draw(errors)))
    return Demonstration("table", tuple(steps), initial=tuple(initial)), geometry


def assert_whole(demo: Demonstration, moves: tuple[Move, ...], noise: float) -> None:
    assert [m.object for m in moves] == [s.object for s in demo.steps]
    for want, got in zip(demo.steps, moves, strict=True):
        error = math.dist(want.pose.position, got.pose.position)
        assert error < 0.005 + 3 * noise, f"{want.object}: {error * 1000:.1f} mm off"


recordings = {
    "rate": st.sampled_from([20.0, 30.0, 60.0]),
    "noise": st.just(0.003) | st.floats(0.001, 0.003),  # half at the edge, as the heights
    "end_rest_s": st.floats(0.3, 1.5),
    "seed": st.integers(0, 2**16),
}


@settings(max_examples=300, deadline=None)
@given(case=table_settings(), **recordings)
def test_a_noisy_table_setting_is_segmented_whole(
    case: tuple[Demonstration, dict[str, ObjectGeometry]],
    rate: float,
    noise: float,
    end_rest_s: float,
    seed: int,
) -> None:
    """The family in the frame the bag below is read in (its poses to float
    round-off), many draws: with the plate read from one sample, one bag in
    23 (3 mm of noise) to 143 (2 mm) lost a step when the plate was given 5 mm
    off, so a few dozen draws did not show it."""
    demo, geometry = case
    world = stream_from_demonstration(
        demo, rate_hz=rate, noise_m=noise, start_time=10.0, end_rest_s=end_rest_s, rng=seed
    )
    assert_whole(demo, segment(world, geometry=geometry).moves, noise)


@pytest.mark.slow
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=table_settings(), **recordings)
def test_a_noisy_robot_bag_of_a_table_setting_is_segmented_whole(
    tmp_path_factory: pytest.TempPathFactory,
    case: tuple[Demonstration, dict[str, ObjectGeometry]],
    rate: float,
    noise: float,
    end_rest_s: float,
    seed: int,
) -> None:
    """The same family written as robot bags (TF tree, MCAP) and read in the map frame."""
    demo, geometry = case
    world = stream_from_demonstration(
        demo, rate_hz=rate, noise_m=noise, start_time=10.0, end_rest_s=end_rest_s, rng=seed
    )
    relative, parents, static = robot_tree(world)
    path: Path = tmp_path_factory.mktemp("robot") / "bag"
    write_bag(relative, path, storage="mcap", parents=parents, static=static)
    stream = load_stream(path, frame="map", objects=list(world.objects))
    assert_whole(demo, segment(stream, geometry=geometry).moves, noise)
