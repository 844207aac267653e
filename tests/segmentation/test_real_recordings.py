"""Segmentation on real recordings: robosuite's human teleoperated demonstrations.

The same trajectories are also written as 20 Hz CSV files and ROS 2 bags
(sqlite3 and mcap; world-frame TF, and a TF tree with the objects published
relative to a static, turned ``table`` frame) and must give the same steps.

Six files from the ``robosuite==0.3.0`` and ``==1.0.0`` source distributions on
PyPI (``tests/support/robosuite_data.py`` downloads and caches them): PickPlace,
NutAssembly and Stack, two Sawyer demonstrations each in 0.3 and one Panda
demonstration each in 1.0.

The expected steps (``EXPECTED`` in ``tests/support/robosuite_data.py``, shared with
``benchmarks/segmentation.py``) were written down by hand from plots of every
object's height over time (``docs/segmentation.md`` shows one): the order in
which the objects are carried is the order of their lifts; where each ends
up is the task's own goal (PickPlace: bin2, each object in its compartment;
NutAssembly: the square nut on the square peg ``peg1``, the round one on the
round peg ``peg2``; Stack: cubeA on cubeB). What was seen besides: in the
first 0.3 PickPlace demonstration the Bread is pushed about 5 cm along the
floor of bin1 (at 46 s) before it is carried; the nuts and cubes are held
still 2–17 cm above their targets before the final lowering; every
recording stops within 0.1 s after the last release.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from demoplan.rotations import quat_from_yaw, quat_inverse, quat_multiply, rotate_vectors
from demoplan.segmentation import (
    ObjectTrack,
    PoseStream,
    load_stream,
    segment,
    write_bag,
    write_csv,
)
from demoplan.segmentation.importing import import_recording_details
from tests.support.robosuite_data import (
    EXPECTED,
    PEG,
    PUSHED,
    RobosuiteDataError,
    resampled,
    robosuite_demonstrations,
    skip_or_fail,
)


@pytest.fixture(scope="module")
def imported() -> dict[tuple[str, str], object]:
    try:
        files = robosuite_demonstrations()
    except RobosuiteDataError as exc:
        skip_or_fail(exc)
    out: dict[tuple[str, str], object] = {}
    for name in {n for n, _ in EXPECTED}:
        for item in import_recording_details(files[name]):
            out[(name, item.key)] = item
    return out


def final_position(stream: PoseStream, name: str) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in stream.track(name).positions[-1])
    return x, y, z


@pytest.mark.parametrize("case", list(EXPECTED), ids=lambda c: f"{c[0]}-{c[1]}")
def test_every_demonstration_gives_its_steps_where_the_objects_end_up(
    imported: dict[tuple[str, str], object], case: tuple[str, str]
) -> None:
    item = imported[case]
    found = item.segmentation  # type: ignore[attr-defined]
    recorded = item.recorded  # type: ignore[attr-defined]
    assert [m.object for m in found.moves] == EXPECTED[case]
    for move in found.moves:
        end = final_position(recorded.stream, move.object)
        assert math.dist(move.pose.position, end) < 0.01, move.object
        x, y, z = move.pose.position
        if case[0].endswith("PickPlace"):
            bin2 = dict(recorded.landmarks)["bin2"].position
            assert abs(x - bin2[0]) < 0.2 and abs(y - bin2[1]) < 0.25, move.object
            assert abs(z) < 0.01
        elif case[0].endswith("NutAssembly"):
            peg = dict(recorded.landmarks)[PEG[move.object]].position
            assert math.dist((x, y), peg[:2]) < 0.02, move.object  # the hole has 1 cm of play
            assert abs(z) < 0.01
        else:
            cube_b = final_position(recorded.stream, "cubeB")
            assert math.dist((x, y), cube_b[:2]) < 0.01
            assert z == pytest.approx(cube_b[2] + 0.05, abs=0.005)
    assert [m.object for m in found.pushes] == PUSHED.get(case, [])
    for push in found.pushes:
        assert 0.04 < push.distance < 0.07 and push.lift < 0.01


def under_a_turned_table(stream: PoseStream) -> PoseStream:
    """The objects' poses relative to a static ``table`` frame 0.8 m up and turned by
    30° in the world (a robot's TF tree), plus that frame's own track."""
    turn = np.tile(quat_from_yaw(30.0), (1, 1))
    origin = np.array([0.3, -0.2, 0.8])
    tracks = []
    for track in stream.tracks:
        quats = np.tile(turn, (len(track), 1))
        inverse = quat_inverse(quats)
        local = rotate_vectors(inverse, track.positions - origin)
        orientations = None
        if track.orientations is not None:
            orientations = quat_multiply(inverse, track.orientations)
        tracks.append(ObjectTrack(track.name, track.times, local, orientations))
    times = stream.tracks[0].times[:1]
    tracks.append(ObjectTrack("table", times, origin[None, :], turn.copy()))
    return PoseStream(tuple(tracks), stream.source)


@pytest.mark.parametrize("rest_s", [0.0, 1.0])
@pytest.mark.parametrize("kind", ["csv", "sqlite3", "mcap", "tf-tree-sqlite3", "tf-tree-mcap"])
def test_the_same_trajectories_as_csv_or_bags_give_the_same_steps(
    imported: dict[tuple[str, str], object], tmp_path: Path, kind: str, rest_s: float
) -> None:
    for case, item in imported.items():
        stream = resampled(item.recorded.stream, 20.0, rest_s)  # type: ignore[attr-defined]
        path = tmp_path / f"{case[0]}-{case[1]}-{kind}"
        if kind == "csv":
            path = path.with_suffix(".csv")
            write_csv(stream, path)
        elif kind.startswith("tf-tree"):
            parents = {t.name: "table" for t in stream.tracks} | {"table": "world"}
            tree = under_a_turned_table(stream)
            write_bag(tree, path, storage=kind.split("-")[-1], parents=parents, static={"table"})
        else:
            write_bag(stream, path, kind="tf", storage=kind)
        found = segment(load_stream(path))
        assert [m.object for m in found.moves] == EXPECTED[case], case
        direct = item.segmentation.moves  # type: ignore[attr-defined]
        for move, reference in zip(found.moves, direct, strict=True):
            assert math.dist(move.pose.position, reference.pose.position) < 0.01, case


def test_imported_files_of_every_recording_are_read_back_and_learned(tmp_path: Path) -> None:
    """What ``demoplan import`` writes, ``demoplan learn`` reads (PickPlace's mesh
    objects have no geometry: their files carry none)."""
    from demoplan.documents.demonstrations import load_demonstrations
    from demoplan.learning import learn
    from demoplan.segmentation import write_demonstration

    try:
        files = robosuite_demonstrations()
    except RobosuiteDataError as exc:
        skip_or_fail(exc)
    for name in ("SawyerPickPlace", "SawyerStack", "SawyerNutAssembly"):
        folder = tmp_path / name
        folder.mkdir()
        for item in import_recording_details(files[name]):
            assert item.demonstration is not None
            write_demonstration(item.demonstration, folder / f"{item.key}.json")
        demos = load_demonstrations([folder])
        assert len(demos) == 2
        assert learn(demos).states
