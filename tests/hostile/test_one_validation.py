"""One validation of lengths for every door (docs/limits.md "Numbers that no
tabletop holds"): a demonstration made from a recording (``import``), a ROS 2
bag or a CSV stream (``segment``) keeps the limits a demonstration file
keeps — checked by the same function on its file form — so an object carried
50 m, or a 3 m object carried, is refused in one line naming the limit
whichever door it came through (before: imported, exit 0).
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.documents.units import MAX_CARRIED_M, MAX_SPREAD_M
from demoplan.segmentation.types import ObjectTrack, PoseStream
from demoplan.segmentation.writers import write_bag, write_csv
from tests.hostile.harness import check_refused, fingerprint, run
from tests.segmentation.test_import import MODEL, box_states, write_recording

GENERATED = settings(
    max_examples=8,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
DOORS = ["import", "bag", "csv", "learn"]


@contextmanager
def folder() -> Iterator[Path]:
    with tempfile.TemporaryDirectory(prefix="hostile-validation-") as name:
        yield Path(name).resolve()


def carried(times: np.ndarray, distance: float, height: float = 0.0) -> np.ndarray:
    """Positions of a thing resting, carried ``distance`` along x in 1–2 s, resting."""
    share = np.clip(times - 1.0, 0.0, 1.0)
    positions = np.zeros((times.size, 3))
    positions[:, 0] = distance * share
    positions[:, 2] = height + 0.1 * np.sin(np.pi * share)
    return positions


def made(
    door: str, cwd: Path, distance: float, half: float = 0.05, quat_length: float = 1.0
) -> list[str]:
    """The input of ``door`` in ``cwd`` (a box of half extent ``half`` carried
    ``distance`` m, its quaternion ``quat_length`` long) and the command reading it."""
    if door == "file":
        quat = [0.0, 0.0, 0.0, quat_length]
        steps = [{"object": "box", "position": [distance, 0.0], "quat": quat}]
        document = {"format": "demoplan/demonstration-1", "steps": steps}
        (cwd / "demo.json").write_text(json.dumps(document))
        return ["learn", "demo.json", "-o", "out"]
    if door == "import":
        states = box_states()
        states[:, 5:8] = carried(states[:, 0], distance, 0.8 + half) + [0.1, 0.2, 0.0]
        states[:, 8] = quat_length
        model = MODEL.replace('size="0.05 0.05 0.05"', f'size="{half} {half} {half}"')
        write_recording(cwd / "rec.hdf5", states, model)
        return ["import", "rec.hdf5", "-o", "out"]
    times = np.arange(1, 401) * 0.01
    stream = PoseStream(
        (
            ObjectTrack(
                "box",
                times,
                carried(times, distance),
                np.tile([0.0, 0.0, 0.0, quat_length], (400, 1)),
            ),
        )
    )
    (cwd / "objects.json").write_text(
        json.dumps({"objects": {"box": {"shape": "box", "size": [2 * half] * 3}}})
    )
    geometry = ["--objects-file", "objects.json"]
    if door == "bag":
        write_bag(stream, cwd / "rec")
        return ["segment", "rec", *geometry, "-o", "out"]
    write_csv(stream, cwd / "rec.csv")
    if door == "csv":
        return ["segment", "rec.csv", "--units", "m", *geometry, "-o", "out"]
    return ["learn", "rec.csv", "--units", "m", *geometry, "-o", "out"]


def refused(args: list[str], cwd: Path, wanted: str) -> None:
    before = fingerprint(cwd)
    answer = run(args, cwd)
    check_refused(answer, [args[1]], codes={1})
    assert wanted in answer.stderr, answer
    assert "docs/limits.md" in answer.stderr, answer
    assert not (cwd / "out").exists(), answer
    assert fingerprint(cwd) == before, answer


@GENERATED
@given(door=st.sampled_from(DOORS), distance=st.floats(MAX_SPREAD_M * 1.05, 900.0))
def test_positions_spread_beyond_a_tabletop_are_refused_at_every_door(
    door: str, distance: float
) -> None:
    with folder() as cwd:
        refused(made(door, cwd, distance), cwd, f"less than {MAX_SPREAD_M:g} m")


@GENERATED
@given(door=st.sampled_from(DOORS), extent=st.floats(MAX_CARRIED_M * 1.05, 9.9))
def test_an_object_too_large_to_carry_is_refused_at_every_door(door: str, extent: float) -> None:
    with folder() as cwd:
        refused(made(door, cwd, 0.3, extent / 2), cwd, f"under {MAX_CARRIED_M:g} m")


def test_a_carried_box_within_the_limits_passes_every_door(tmp_path: Path) -> None:
    """The same inputs within the limits (0.3 m, a 10 cm box) are read: the
    refusals above are the limits', not the inputs' making."""
    for door in DOORS:
        cwd = tmp_path / door
        cwd.mkdir()
        answer = run(made(door, cwd, 0.3), cwd)
        assert answer.code == 0, answer
        assert (cwd / "out").exists(), answer


QUATERNION_DOORS = [*DOORS, "file"]


@GENERATED
@given(
    door=st.sampled_from(QUATERNION_DOORS),
    length=st.one_of(st.floats(0.0, 0.89), st.floats(1.11, 1e200)),
)
def test_a_quaternion_far_from_unit_length_is_refused_at_every_door(
    door: str, length: float
) -> None:
    """One rule for quaternions (docs/limits.md): a recording's states, a bag,
    a CSV stream and a demonstration file alike refuse one whose length is
    not within 0.1 of 1 — zero, scaled, overflowing."""
    with folder() as cwd:
        refused(made(door, cwd, 0.3, quat_length=length), cwd, "a unit quaternion expected")


@GENERATED
@given(door=st.sampled_from(QUATERNION_DOORS), length=st.floats(0.91, 1.09))
def test_a_quaternion_near_unit_length_is_read_at_every_door(door: str, length: float) -> None:
    """Rounding and noise pass every door: the quaternion is normalised."""
    with folder() as cwd:
        answer = run(made(door, cwd, 0.3, quat_length=length), cwd)
        assert answer.code == 0, answer
        assert (cwd / "out").exists(), answer
