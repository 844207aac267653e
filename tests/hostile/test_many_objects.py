"""Streams and recordings of thousands of objects (docs/limits.md "Numbers
that no tabletop holds", "Recordings"): a recording's model of 20,000 free
bodies, a TF tree of thousands of frames under ``--objects '*'``, a CSV of
thousands of objects. Segmenting costs milliseconds an object and reading a
bag's TF tree grows with its frames, so each is refused up front in one line
naming the limit (exit 1), nothing written — or, within the limit, answered.

No timing is asserted (the machine is shared): the harness's hang guard is
the only clock (before the limit, the 20,000 bodies took a minute and the
5,000 frames two).
"""

from __future__ import annotations

import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.segmentation.types import MAX_OBJECTS, ObjectTrack, PoseStream
from demoplan.segmentation.writers import write_bag, write_csv
from tests.hostile.harness import check_clean, check_refused, fingerprint, run

GENERATED = settings(
    max_examples=4,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
SAMPLES = 20
TIMES = np.arange(1, SAMPLES + 1) * 0.2  # 4 s


@contextmanager
def folder() -> Iterator[Path]:
    with tempfile.TemporaryDirectory(prefix="hostile-many-") as name:
        yield Path(name).resolve()


def many_body_recording(path: Path, count: int, joint: str) -> Path:
    """A recording whose model has ``count`` free bodies (2 mm cubes 5 mm
    apart on a table), the first carried 0.3 m; ``joint``: how each is made free."""
    free = "<freejoint/>" if joint == "freejoint" else '<joint type="free"/>'
    bodies = "".join(
        f'<body name="b{i}" pos="{(i % 100) * 0.005:.3f} {(i // 100) * 0.005:.3f} 0.802">'
        f'{free}<geom type="box" size="0.002 0.002 0.002"/></body>'
        for i in range(count)
    )
    model = (
        '<mujoco><worldbody><body name="table" pos="0 0 0.4"><geom type="box" '
        f'size="0.5 0.5 0.4"/></body>{bodies}</worldbody></mujoco>'
    )
    states = np.zeros((SAMPLES, 1 + 13 * count))
    states[:, 0] = TIMES
    qpos = states[:, 1 : 1 + 7 * count].reshape(SAMPLES, count, 7)
    qpos[:, :, 0] = (np.arange(count) % 100) * 0.005
    qpos[:, :, 1] = (np.arange(count) // 100) * 0.005
    qpos[:, :, 2] = 0.802
    qpos[:, :, 3] = 1.0
    carried = np.clip(TIMES - 1.0, 0.0, 1.0)
    qpos[:, 0, 0] = 0.3 * carried
    qpos[:, 0, 1] = -0.2
    qpos[:, 0, 2] = 0.802 + 0.1 * np.sin(np.pi * carried)
    states[:, 1 : 1 + 7 * count] = qpos.reshape(SAMPLES, 7 * count)
    with h5py.File(path, "w") as handle:
        data = handle.create_group("data")
        data.attrs["env"] = "Toy"
        demo = data.create_group("demo_1")
        demo.create_dataset("states", data=states, compression="gzip")
        demo.attrs["model_file"] = model
    return path


def frames(count: int, shape: str) -> PoseStream:
    """``count`` TF frames (or CSV objects), the last carried 0.3 m."""
    tracks = []
    for k in range(1, count + 1):
        positions = np.zeros((SAMPLES, 3))
        if shape == "wide":
            positions[:, 0], positions[:, 1] = 0.01 * (k % 50), 0.01 * (k // 50)
        if k == count:
            positions[:, 0] += 0.3 * np.clip(TIMES - 1.0, 0.0, 1.0)
        quats = np.tile([0.0, 0.0, 0.0, 1.0], (SAMPLES, 1))
        tracks.append(ObjectTrack(f"f{k}", TIMES.copy(), positions, quats))
    return PoseStream(tuple(tracks))


def parents(count: int, shape: str) -> dict[str, str]:
    return {
        f"f{k}": "world" if k == 1 or shape == "wide" else f"f{k - 1}" for k in range(1, count + 1)
    }


def refused(args: list[str | Path], cwd: Path, source: str, output: str) -> None:
    """One error line naming ``source`` and the limit, exit 1, ``output`` not
    made and nothing else changed under ``cwd``."""
    before = fingerprint(cwd)
    answer = run(args, cwd)
    check_refused(answer, [source], codes={1})
    assert f"at most {MAX_OBJECTS:,}" in answer.stderr, answer
    assert not (cwd / output).exists(), answer
    assert fingerprint(cwd) == before, answer


@GENERATED
@given(
    count=st.integers(MAX_OBJECTS + 1, 3 * MAX_OBJECTS),
    joint=st.sampled_from(["freejoint", "joint"]),
)
def test_a_model_of_thousands_of_free_bodies_is_refused_before_its_states_are_read(
    count: int, joint: str
) -> None:
    with folder() as cwd:
        many_body_recording(cwd / "many.hdf5", count, joint)
        refused(["import", "many.hdf5", "-o", "out"], cwd, "many.hdf5", "out")


def test_the_issues_twenty_thousand_free_bodies_are_refused(tmp_path: Path) -> None:
    """The issue's case: before the limit, a minute and 800 MB, then exit 0."""
    many_body_recording(tmp_path / "many.hdf5", 20_000, "freejoint")
    before = fingerprint(tmp_path)
    answer = run(["import", "many.hdf5", "-o", "out"], tmp_path)
    check_refused(answer, ["many.hdf5"], codes={1})
    assert "10,000 expected" in answer.stderr or f"at most {MAX_OBJECTS:,}" in answer.stderr
    assert fingerprint(tmp_path) == before


def test_a_model_of_as_many_free_bodies_as_the_limit_is_imported(tmp_path: Path) -> None:
    many_body_recording(tmp_path / "many.hdf5", MAX_OBJECTS, "freejoint")
    answer = run(["import", "many.hdf5", "-o", "out", "--json"], tmp_path)
    check_clean(answer)
    assert answer.code == 0, answer
    assert len(list((tmp_path / "out").glob("*.json"))) == 1


@GENERATED
@given(
    count=st.integers(MAX_OBJECTS + 1, 3 * MAX_OBJECTS),
    shape=st.sampled_from(["wide", "deep"]),
    command=st.sampled_from(["segment", "learn"]),
)
def test_a_tf_tree_of_thousands_of_frames_is_refused_as_it_is_read(
    count: int, shape: str, command: str
) -> None:
    with folder() as cwd:
        write_bag(frames(count, shape), cwd / "tree", parents=parents(count, shape))
        refused([command, "tree", "--objects", "*", "-o", "o.json"], cwd, "tree", "o.json")


@GENERATED
@given(count=st.integers(MAX_OBJECTS + 1, 3 * MAX_OBJECTS))
def test_a_csv_stream_of_thousands_of_objects_is_refused(count: int) -> None:
    with folder() as cwd:
        write_csv(frames(count, "wide"), cwd / "many.csv")
        refused(["segment", "many.csv", "-o", "o.json"], cwd, "many.csv", "o.json")


def test_a_chain_as_deep_as_the_limit_is_composed_once(tmp_path: Path) -> None:
    """A TF chain of 1000 frames, every one an object, under segment (which has
    no time budget): each frame is composed from its parent's pose at the same
    times (before: d²/2 link compositions, 580 s at 200 samples a frame)."""
    write_bag(frames(MAX_OBJECTS, "deep"), tmp_path / "deep", parents=parents(MAX_OBJECTS, "deep"))
    answer = run(["segment", "deep", "--objects", "*", "-o", "o.json"], tmp_path)
    check_clean(answer)
