"""ROS 2 TF trees: frames published relative to moving parents are composed to a world frame.

Bags are written with rosbags' Writer (through ``write_bag(..., parents=...,
static=...)``): objects of a demonstration's stream are published relative to
chains of links (``odom`` moving in ``map``, a static ``table`` under it, …)
whose motions are known in closed form; the reader must give back the
objects' world poses and the same segmentation as the world-frame stream.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import demoplan.budget
from demoplan.budget import time_budget
from demoplan.documents.demonstrations import load_demonstrations
from demoplan.errors import InputError, LimitReachedError
from demoplan.segmentation import (
    ObjectTrack,
    PoseStream,
    load_stream,
    segment,
    stream_from_demonstration,
    write_bag,
    write_csv,
)
from demoplan.segmentation.tftree import FrameLink, TransformTree, interpolate_link
from tests.support.helpers import EXAMPLES

SET_TABLE = load_demonstrations([EXAMPLES / "set_table"])
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Link:
    """A link frame moving in its parent at constant velocity and constant turn rate
    about a fixed axis: linear interpolation and slerp between its samples are exact."""

    name: str
    parent: str
    start: tuple[float, float, float]
    velocity: tuple[float, float, float]
    axis: tuple[float, float, float]
    rate: float  # rad/s
    angle: float  # rad at t = 0
    static: bool = False

    def at(self, times: np.ndarray) -> tuple[np.ndarray, Rotation]:
        t = np.zeros_like(times) if self.static else times
        positions = np.asarray(self.start) + t[:, None] * np.asarray(self.velocity)
        axis = np.asarray(self.axis) / np.linalg.norm(self.axis)
        return positions, Rotation.from_rotvec((self.angle + self.rate * t)[:, None] * axis)


def chain_pose(links: Sequence[Link], times: np.ndarray) -> tuple[np.ndarray, Rotation]:
    """Pose of the last link in the root frame (links root-first)."""
    positions = np.zeros((len(times), 3))
    rotation = Rotation.identity(len(times))
    for link in links:
        p, r = link.at(times)
        positions = positions + rotation.apply(p)
        rotation = rotation * r
    return positions, rotation


def tree_stream(
    world: PoseStream,
    links: Sequence[Link],
    attach: dict[str, int],
    link_rate_hz: float,
) -> tuple[PoseStream, dict[str, str], set[str]]:
    """Tracks of the links (own samples) and of the objects relative to their parent.

    ``links`` is a chain, root-first (``links[0].parent`` is the root); object
    ``o`` hangs under ``links[attach[o] - 1]`` (``attach[o] = 0``: under the root).
    """
    root = links[0].parent if links else "map"
    tracks: list[ObjectTrack] = []
    parents: dict[str, str] = {}
    static: set[str] = set()
    span = np.arange(world.start_time - 0.5, world.end_time + 0.5, 1.0 / link_rate_hz)
    for link in links:
        times = span[:1] if link.static else span
        p, r = link.at(times)
        tracks.append(ObjectTrack(link.name, times, p, r.as_quat()))
        parents[link.name] = link.parent
        if link.static:
            static.add(link.name)
    for name, depth in attach.items():
        track = world.track(name)
        p_link, r_link = chain_pose(links[:depth], track.times)
        r_world = Rotation.from_quat(
            track.orientations
            if track.orientations is not None
            else np.tile(IDENTITY, (len(track), 1))
        )
        inverse = r_link.inv()
        relative = ObjectTrack(
            name,
            track.times,
            inverse.apply(track.positions - p_link),
            (inverse * r_world).as_quat(),
        )
        tracks.append(relative)
        parents[name] = links[depth - 1].name if depth else root
    return PoseStream(tuple(tracks)), parents, static


def assert_world_poses(world: PoseStream, found: PoseStream, names: Sequence[str]) -> None:
    for name in names:
        want, got = world.track(name), found.track(name)
        np.testing.assert_allclose(got.times, want.times, atol=1e-9)  # ns stamps
        np.testing.assert_allclose(got.positions, want.positions, rtol=0, atol=1e-6)
        assert got.orientations is not None
        expected = want.orientations if want.orientations is not None else IDENTITY[None]
        angles = Rotation.from_quat(got.orientations).inv() * Rotation.from_quat(expected)
        assert float(np.max(angles.magnitude())) < 1e-6


def assert_same_steps(world: PoseStream, found: PoseStream, names: Sequence[str]) -> None:
    direct = segment(PoseStream(tuple(world.track(n) for n in names))).moves
    composed = segment(PoseStream(tuple(found.track(n) for n in names))).moves
    assert [m.object for m in composed] == [m.object for m in direct]
    for a, b in zip(direct, composed, strict=True):
        assert math.dist(a.pose.position, b.pose.position) < 5e-4


# --------------------------------------------------------------------------- property


vectors = st.tuples(*[st.floats(-1.0, 1.0)] * 3)
axes = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda a: math.hypot(*a) > 0.1)


@st.composite
def trees(draw: st.DrawFn) -> tuple[int, list[Link], dict[str, int], float, str]:
    demo_index = draw(st.integers(0, len(SET_TABLE) - 1))
    depth = draw(st.integers(1, 3))
    root = draw(st.sampled_from(["map", "world", "mocap"]))
    links: list[Link] = []
    for k, name in enumerate(["odom", "table", "tray"][:depth]):
        links.append(
            Link(
                name,
                links[-1].name if links else root,
                draw(vectors),
                tuple(0.3 * v for v in draw(vectors)),  # type: ignore[arg-type]
                draw(axes),
                draw(st.floats(-1.0, 1.0)),
                draw(st.floats(-math.pi, math.pi)),
                static=k > 0 and draw(st.booleans()),
            )
        )
    objects = sorted({step.object for step in SET_TABLE[demo_index].steps})
    chosen = draw(st.lists(st.sampled_from(objects), min_size=1, max_size=4, unique=True))
    attach = {name: draw(st.integers(0, depth)) for name in chosen}
    rate = draw(st.floats(5.0, 30.0))
    storage = draw(st.sampled_from(["sqlite3", "mcap"]))
    return demo_index, links, attach, rate, storage


@settings(
    max_examples=20,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(trees())
def test_objects_under_moving_links_come_back_in_the_world_frame(
    tmp_path_factory: pytest.TempPathFactory,
    case: tuple[int, list[Link], dict[str, int], float, str],
) -> None:
    demo_index, links, attach, rate, storage = case
    world = stream_from_demonstration(
        SET_TABLE[demo_index], rate_hz=30, noise_m=0.002, rng=1, start_time=10.0
    )
    relative, parents, static = tree_stream(world, links, attach, rate)
    path = tmp_path_factory.mktemp("tree") / "bag"
    write_bag(relative, path, storage=storage, parents=parents, static=static)  # type: ignore[arg-type]

    found = load_stream(path)
    # The default object set: the tree's leaves — the objects, and the last
    # link when nothing hangs under it.
    leaves = set(attach) | ({links[-1].name} if max(attach.values()) < len(links) else set())
    assert set(found.objects) == leaves
    assert_world_poses(world, found, list(attach))
    assert_same_steps(world, found, list(attach))

    # Chosen by name, the objects alone.
    only = load_stream(path, objects=list(attach))
    assert set(only.objects) == set(attach)


# --------------------------------------------------------------------------- plain


def robot_tree(world: PoseStream) -> tuple[PoseStream, dict[str, str], set[str]]:
    """map → odom (moving) → table (static) → objects; odom → base_link (moving)."""
    odom = Link("odom", "map", (0.5, -0.2, 0.0), (0.05, 0.02, 0.0), (0, 0, 1), 0.3, 0.4)
    table = Link("table", "odom", (1.0, 0.5, 0.75), (0, 0, 0), (0, 0, 1), 0, -0.7, static=True)
    relative, parents, static = tree_stream(
        world, [odom, table], dict.fromkeys(world.objects, 2), 20
    )
    base = Link("base_link", "odom", (0.1, 0, 0.1), (0.1, 0, 0), (0, 0, 1), -0.2, 0.0)
    times = np.arange(world.start_time - 0.5, world.end_time + 0.5, 0.05)
    p, r = base.at(times)
    tracks = (*relative.tracks, ObjectTrack("base_link", times, p, r.as_quat()))
    return PoseStream(tracks), {**parents, "base_link": "odom"}, static


@pytest.fixture(scope="module")
def world() -> PoseStream:
    return stream_from_demonstration(
        SET_TABLE[0], rate_hz=30, noise_m=0.002, rng=2, start_time=10.0
    )


@pytest.fixture(scope="module")
def robot_bag(world: PoseStream, tmp_path_factory: pytest.TempPathFactory) -> Path:
    relative, parents, static = robot_tree(world)
    path = tmp_path_factory.mktemp("robot") / "bag"
    write_bag(relative, path, storage="mcap", parents=parents, static=static)
    return path


def test_a_robot_tree_gives_the_objects_not_the_links(world: PoseStream, robot_bag: Path) -> None:
    """The issue's case: links (odom, base_link) must not come out as moving objects."""
    found = load_stream(robot_bag, objects=None)
    assert "odom" not in found.objects and "table" not in found.objects
    assert set(found.objects) == {*world.objects, "base_link"}  # base_link is a leaf here
    assert_world_poses(world, found, world.objects)
    assert_same_steps(world, found, world.objects)


def test_glob_patterns_choose_objects(robot_bag: Path) -> None:
    assert load_stream(robot_bag, objects=["f*", "spoon"]).objects == ("fork", "spoon", "food")


def test_today_s_world_frame_bags_read_exactly_as_before(tmp_path: Path, world: PoseStream) -> None:
    write_bag(world, tmp_path / "bag", storage="sqlite3")
    back = load_stream(tmp_path / "bag")
    assert back.objects == world.objects
    for want, got in zip(world.tracks, back.tracks, strict=True):
        np.testing.assert_allclose(got.times, want.times, atol=1e-9)
        assert np.array_equal(got.positions, want.positions)
        assert got.orientations is not None
        assert np.array_equal(got.orientations, np.tile(IDENTITY, (len(got), 1)))


def test_a_world_frame_below_the_root(world: PoseStream, robot_bag: Path) -> None:
    """--frame odom: poses relative to odom; --frame base_link: relative to a sibling."""
    odom = Link("odom", "map", (0.5, -0.2, 0.0), (0.05, 0.02, 0.0), (0, 0, 1), 0.3, 0.4)
    base = Link("base_link", "odom", (0.1, 0, 0.1), (0.1, 0, 0), (0, 0, 1), -0.2, 0.0)
    plate = world.track("plate")
    for frame, chain in (("odom", [odom]), ("base_link", [odom, base])):
        found = load_stream(robot_bag, frame=frame, objects=["plate"])
        p, r = chain_pose(chain, plate.times)
        want = r.inv().apply(plate.positions - p)
        np.testing.assert_allclose(found.track("plate").positions, want, atol=1e-6)


def test_a_parent_is_held_outside_its_samples() -> None:
    """Before its first sample a link keeps its first, after its last its last; between,
    linear for translation and slerp for rotation."""
    quarter = Rotation.from_euler("z", [[0], [90]], degrees=True).as_quat()
    parent = FrameLink(
        "map",
        ObjectTrack("odom", np.array([1.0, 2.0]), np.array([[0, 0, 0], [1, 0, 0.0]]), quarter),
    )
    times = np.array([0.0, 1.0, 1.5, 2.0, 3.0])
    positions, quats = interpolate_link(parent, times)
    np.testing.assert_allclose(positions[:, 0], [0, 0, 0.5, 1, 1])
    yaw = Rotation.from_quat(quats).as_euler("xyz", degrees=True)[:, 2]
    np.testing.assert_allclose(yaw, [0, 0, 45, 90, 90], atol=1e-9)
    cup = FrameLink(
        "odom", ObjectTrack("cup", times, np.tile([1.0, 0, 0], (5, 1)), np.tile(IDENTITY, (5, 1)))
    )
    track = TransformTree([parent, cup]).track_in("cup", "map")
    assert track is not None
    np.testing.assert_allclose(
        track.positions[:, :2],
        [[1, 0], [1, 0], [0.5 + 1 / math.sqrt(2), 1 / math.sqrt(2)], [1, 1], [1, 1]],
        atol=1e-12,
    )


def _link(name: str, parent: str, n: int = 3) -> FrameLink:
    times = np.arange(float(n))
    return FrameLink(parent, ObjectTrack(name, times, np.zeros((n, 3)), np.tile(IDENTITY, (n, 1))))


def _tree_bag(path: Path, links: list[tuple[str, str]], static: Sequence[str] = ()) -> Path:
    tracks = tuple(_link(name, parent).track for name, parent in links)
    write_bag(PoseStream(tracks), path, parents=dict(links), static=set(static))
    return path


def test_several_roots_need_a_frame(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    bag = _tree_bag(tmp_path / "two", [("cup", "world"), ("odom", "map"), ("plate", "odom")])
    with pytest.raises(InputError, match=r"several roots \(world, map\).*--frame") as info:
        load_stream(bag)
    assert "\n" not in str(info.value) and info.value.field == "frame"
    with caplog.at_level(logging.WARNING):
        found = load_stream(bag, frame="map")
    assert found.objects == ("plate",)
    assert "'cup' is not connected to the world frame 'map'" in caplog.text


def test_an_unknown_frame_lists_the_frames(tmp_path: Path) -> None:
    bag = _tree_bag(tmp_path / "bag", [("cup", "world")])
    with pytest.raises(InputError, match=r"unknown world frame 'base'.*frames are world, cup"):
        load_stream(bag, frame="base")


def test_objects_matching_nothing_are_named(tmp_path: Path) -> None:
    bag = _tree_bag(tmp_path / "bag", [("odom", "world"), ("cup", "odom"), ("plate", "odom")])
    with pytest.raises(InputError, match=r"'mug', 'obj_\*'; available: odom, cup, plate") as info:
        load_stream(bag, objects=["cup", "mug", "obj_*"])
    assert info.value.field == "objects"


def test_a_cycle_is_refused(tmp_path: Path) -> None:
    bag = _tree_bag(tmp_path / "bag", [("cup", "world"), ("a", "b"), ("b", "a")])
    with pytest.raises(InputError, match=r"cycle a → b → a; a tree expected") as info:
        load_stream(bag)
    assert "\n" not in str(info.value)


def _raw_tf_bag(path: Path, transforms: Sequence[tuple[str, float, str, str]]) -> Path:
    """A bag written with rosbags directly: ``(topic, t, parent, child)`` transforms."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    tf_type = "tf2_msgs/msg/TFMessage"
    with Writer(path, version=9) as writer:
        connections = {
            topic: writer.add_connection(topic, tf_type, typestore=store)
            for topic in dict.fromkeys(topic for topic, *_ in transforms)
        }
        for topic, t, parent, child in transforms:
            ns = round(t * 1e9)
            transform = types["geometry_msgs/msg/TransformStamped"](
                header=types["std_msgs/msg/Header"](
                    stamp=types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9),
                    frame_id=parent,
                ),
                child_frame_id=child,
                transform=types["geometry_msgs/msg/Transform"](
                    translation=types["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.0),
                    rotation=types["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0),
                ),
            )
            message = types[tf_type](transforms=[transform])
            writer.write(connections[topic], ns, store.serialize_cdr(message, tf_type))
    return path


def test_a_frame_with_two_parents_or_on_both_topics_is_refused(tmp_path: Path) -> None:
    two = _raw_tf_bag(tmp_path / "two", [("/tf", 1.0, "world", "cup"), ("/tf", 2.0, "odom", "cup")])
    with pytest.raises(InputError, match="frame 'cup' has parents 'world' and 'odom'"):
        load_stream(two)
    both = _raw_tf_bag(
        tmp_path / "both", [("/tf_static", 1.0, "world", "t"), ("/tf", 2.0, "world", "t")]
    )
    with pytest.raises(InputError, match="on both /tf and /tf_static"):
        load_stream(both)
    loop = _raw_tf_bag(tmp_path / "loop", [("/tf", 1.0, "cup", "cup")])
    with pytest.raises(InputError, match="cycle cup → cup"):
        load_stream(loop)
    empty = _raw_tf_bag(tmp_path / "empty", [("/tf", 1.0, "", "cup")])
    with pytest.raises(InputError, match=r"empty header\.frame_id"):
        load_stream(empty)


def test_a_republished_static_transform_keeps_the_latest(tmp_path: Path) -> None:
    bag = _raw_tf_bag(
        tmp_path / "bag",
        [("/tf_static", 1.0, "world", "table"), ("/tf_static", 1.0, "world", "table"),
         ("/tf", 1.0, "table", "cup"), ("/tf", 2.0, "table", "cup")],
    )  # fmt: skip
    assert load_stream(bag).objects == ("cup",)


def test_static_links_hold_for_all_time(tmp_path: Path) -> None:
    table = ObjectTrack("table", np.array([100.0]), np.array([[1.0, 2.0, 0.5]]), IDENTITY[None])
    cup = _link("cup", "table", 5).track
    write_bag(
        PoseStream((table, cup)), tmp_path / "bag", parents={"cup": "table"}, static={"table"}
    )
    found = load_stream(tmp_path / "bag")
    assert found.objects == ("cup",)
    np.testing.assert_allclose(found.track("cup").positions, np.tile([1.0, 2.0, 0.5], (5, 1)))


def test_csv_streams_take_objects_too(tmp_path: Path, world: PoseStream) -> None:
    write_csv(world, tmp_path / "s.csv")
    assert load_stream(tmp_path / "s.csv", objects=["fork", "kn*"]).objects == ("knife", "fork")
    with pytest.raises(InputError, match="no object matches 'cup'"):
        load_stream(tmp_path / "s.csv", objects=["cup"])


@settings(max_examples=25, deadline=None)
@given(
    parents_of=st.lists(st.integers(0, 100), min_size=2, max_size=12),
    shared_times=st.booleans(),
    seed=st.integers(0, 2**32 - 1),
)
def test_poses_kept_between_frames_change_no_frame(
    parents_of: list[int], shared_times: bool, seed: int
) -> None:
    """Composing every frame of one tree in turn (the poses of ancestors kept
    for the next frame at the same times) gives each frame what a tree of
    its own, composing it alone, gives — with all frames at one set of times
    and with each at its own. (A quaternion may come out negated: a frame's
    own samples are used where the other composes its interpolation.)"""
    rng = np.random.default_rng(seed)
    links = []
    for k, pick in enumerate(parents_of):
        parent = "world" if k == 0 else f"f{pick % k}"
        n = 6 if shared_times else int(rng.integers(2, 9))
        times = np.arange(n) * 0.1 if shared_times else np.sort(rng.uniform(0, 1, n))
        times = np.unique(times)
        quats = Rotation.random(len(times), random_state=int(rng.integers(2**31))).as_quat()
        track = ObjectTrack(f"f{k}", times, rng.normal(size=(len(times), 3)), quats)
        links.append(FrameLink(parent, track))
    names = [link.name for link in links]
    together = TransformTree(links).tracks_in(names, "world")
    for name in names:
        alone = TransformTree(links).track_in(name, "world")
        assert alone is not None
        np.testing.assert_allclose(together[name].positions, alone.positions, atol=1e-9)
        # The same rotations: q and -q (slerp between a link's samples may give either).
        q_together, q_alone = together[name].orientations, alone.orientations
        assert q_together is not None and q_alone is not None
        sign = np.sign(np.sum(q_together * q_alone, axis=1))[:, None]
        np.testing.assert_allclose(q_together, sign * q_alone, atol=1e-9)


class _TickingClock:
    """A stand-in for the ``time`` module of :mod:`demoplan.budget` whose
    monotonic clock moves on a millisecond at every reading: a budget's end
    comes after a fixed number of readings, however fast the machine."""

    def __init__(self) -> None:
        self.now = 0.0

    def monotonic(self) -> float:
        self.now += 0.001
        return self.now


def _deep_chain(depth: int) -> tuple[TransformTree, list[str]]:
    links = [_link(f"f{k}", "world" if k == 1 else f"f{k - 1}") for k in range(1, depth + 1)]
    return TransformTree(links), [f"f{k}" for k in range(1, depth + 1)]


def test_a_deep_chain_reads_the_budget_while_it_composes(monkeypatch: pytest.MonkeyPatch) -> None:
    """Composing a chain 1000 frames deep, every frame an object, reads the
    budget as it goes: with a clock that ticks at each reading, a budget of
    half a second (500 readings) stops it part-way with LimitReachedError
    naming the TF composition; without a budget the same chain is composed
    whole. (The clock is a fake one, so the outcome cannot depend on how
    fast the machine composes; tests/hostile/test_budgets.py checks the
    command's answer.)"""
    clock = _TickingClock()
    monkeypatch.setattr(demoplan.budget, "time", clock)
    tree, frames = _deep_chain(1000)
    assert sorted(tree.tracks_in(frames, "world")) == sorted(frames)  # no budget: all of it
    tree, frames = _deep_chain(1000)
    clock.now = 0.0
    with (
        pytest.raises(LimitReachedError, match=r"^stopped: composing ") as stopped,
        time_budget(0.5, "stopped:{where}"),
    ):
        tree.tracks_in(frames, "world")
    assert 0.5 < clock.now < 0.51, stopped.value  # at the first reading past the budget
