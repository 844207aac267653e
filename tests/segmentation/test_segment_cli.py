"""`demoplan segment` and `demoplan learn` on pose streams (CSV, ROS 2 bags)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from demoplan.commands.inputs import load_inputs
from demoplan.documents.demonstrations import load_demonstrations
from demoplan.segmentation import write_bag, write_csv
from demoplan.segmentation.synthetic import stream_from_demonstration
from tests.segmentation.test_tf_tree import SET_TABLE, robot_tree
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES


@pytest.fixture(scope="module")
def streams(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Experiment 1's three demonstrations as 60 Hz streams with 2 mm noise."""
    folder = tmp_path_factory.mktemp("streams")
    paths = []
    for k, demo in enumerate(load_demonstrations([EXAMPLES / "set_table"])):
        stream = stream_from_demonstration(demo, rate_hz=60, noise_m=0.002, rng=k)
        path = folder / f"set-table-{k + 1}.csv"
        write_csv(stream, path)
        paths.append(path)
    return paths


def test_segment_writes_a_demonstration_and_a_plot(streams: list[Path], tmp_path: Path) -> None:
    result = invoke(
        "segment", streams[0], "-o", tmp_path / "demo.json", "--plot", tmp_path / "speed.png"
    )
    assert result.exit_code == 0, result.stderr
    (demo,) = load_demonstrations([tmp_path / "demo.json"])
    (original,) = load_demonstrations([EXAMPLES / "set_table" / "demonstration-1.json"])
    assert [s.object for s in demo.steps] == [s.object for s in original.steps]
    assert (tmp_path / "speed.png").read_bytes().startswith(b"\x89PNG")
    assert "7 steps" in result.stderr


def test_segment_json(streams: list[Path], tmp_path: Path) -> None:
    result = invoke("segment", streams[1], "-o", tmp_path / "demo.json", "--json", "--name", "two")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["format"] == "demoplan/demonstration-1" and data["name"] == "two"
    assert len(data["steps"]) == 7


def test_learn_from_streams_reproduces_table_iii(streams: list[Path], tmp_path: Path) -> None:
    """The paper's Experiment 1 learned straight from recordings: Table III's
    sequences and 32 constraints (with the paper's reading the data were drawn for)."""
    result = invoke("learn", *streams, "-o", tmp_path / "model.json", "--json", "--paper")
    assert result.exit_code == 0, result.stderr
    model = json.loads(result.stdout)
    assert ["-".join(s) for s in model["sequences"]] == [
        "A-B-C-D-E-F-G",
        "A-E-H-I-J-F-G",
        "A-C-B-F-E-D-G",
    ]
    assert len(model["constraints"]) == 32


def test_learn_from_a_bag(tmp_path: Path) -> None:
    (demo,) = load_demonstrations([EXAMPLES / "set_table" / "demonstration-1.json"])
    write_bag(
        stream_from_demonstration(demo, rate_hz=60, noise_m=0.002, rng=4),
        tmp_path / "bag",
        kind="tf",
        storage="mcap",
    )
    (found,) = load_inputs([tmp_path / "bag"])
    assert [s.object for s in found.steps] == [s.object for s in demo.steps]
    assert found.name == "bag"


def test_segment_bad_stream_exits_1(tmp_path: Path) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("t,object,x,y,z\n0,plate,0.1,nan,0\n")
    result = invoke("segment", path, "-o", tmp_path / "out.json")
    assert result.exit_code == 1
    assert str(path) in result.stderr and not (tmp_path / "out.json").exists()


# --------------------------------------------------------------------------- TF trees


def _robot_bag(folder: Path, seed: int) -> Path:
    """A demonstration's objects under a static table on a moving odom (map → odom →
    table), its 2 mm noise drawn from ``seed``."""
    world = stream_from_demonstration(
        SET_TABLE[0], rate_hz=30, noise_m=0.002, start_time=10.0, rng=seed
    )
    relative, parents, static = robot_tree(world)
    path = folder / "bag"
    write_bag(relative, path, storage="mcap", parents=parents, static=static)
    return path


@pytest.fixture(scope="module")
def robot_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The robot bag of one fixed draw: a run of the suite passes or fails on the
    code, not on the noise (unseeded, it failed one of three fresh-clone runs: the
    napkin's step missed, as with seed 27's noise below)."""
    return _robot_bag(tmp_path_factory.mktemp("robot"), seed=0)


@pytest.mark.slow
def test_a_robot_bag_of_seed_27_is_segmented_whole(tmp_path: Path) -> None:
    """Found by a fresh-clone run whose bag drew its noise unseeded: with seed 27's
    2 mm noise the napkin's step, the last, was lost (1 of seeds 0-29). The napkin
    rests on the plate at 14.9 mm; the plate's height was read from its last
    sample alone, 6.5 mm high (3.2 σ), so with the objects file's 2 cm plate its
    top was 26.5 mm, 11.6 mm above the napkin, beyond support_tolerance (10 mm):
    the rest was taken for a pause in the air. The family: test_robot_bag_families."""
    _segmented_as_the_demonstration(_robot_bag(tmp_path, seed=27), tmp_path)


def _segmented_as_the_demonstration(bag: Path, tmp_path: Path) -> None:
    geometry = tmp_path / "objects.yaml"
    geometry.write_text(
        "units: {length: cm}\nobjects:\n"
        + "".join(
            f"  {n}: {{size: [5, 5, 2]}}\n" for n in SET_TABLE[0].moved_objects if n != "plate"
        )
        + "  plate: {shape: cylinder, size: [26, 26, 2]}\n"
    )
    result = invoke(
        "segment", bag, "-o", tmp_path / "demo.json", "--frame", "map",
        "--objects", "plate,knife,fork,spoon,glass,food,napkin", "--objects-file", geometry,
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    (demo,) = load_demonstrations([tmp_path / "demo.json"])
    assert [s.object for s in demo.steps] == [s.object for s in SET_TABLE[0].steps]
    assert dict(demo.objects)["plate"].shape == "cylinder"
    assert dict(demo.objects)["plate"].size == pytest.approx((0.26, 0.26, 0.02))


def test_segment_and_learn_a_robot_bag(robot_bag: Path, tmp_path: Path) -> None:
    _segmented_as_the_demonstration(robot_bag, tmp_path)
    result = invoke("learn", robot_bag, "--objects", "[!b]*", "-o", tmp_path / "m.json", "--json")
    assert result.exit_code == 0, result.stderr


def test_segment_errors_are_one_line(robot_bag: Path, tmp_path: Path) -> None:
    geometry = tmp_path / "objects.json"
    geometry.write_text('{"objects": {"mug": {"shape": "box", "size": [0.1, 0.1, 0.1]}}}')
    partial = tmp_path / "partial.json"
    partial.write_text('{"objects": {"plate": {"size": [0.2, 0.2, 0.02]}}}')
    for options, message in (
        (["--frame", "nowhere"], "unknown world frame 'nowhere'"),
        (["--objects", "mug"], "no object matches 'mug'"),
        (["--objects-file", geometry], "unknown object 'mug'; the stream's objects are"),
        (["--objects-file", partial], "no geometry for 'food', 'fork'"),
    ):
        result = invoke("segment", robot_bag, "-o", tmp_path / "d.json", *options)
        assert result.exit_code == 1
        (error,) = [line for line in result.stderr.splitlines() if "error:" in line]
        assert message in error, result.stderr


def test_segment_reports_pushes_and_takes_thresholds(tmp_path: Path) -> None:
    from demoplan.model import Demonstration, Pose, Step
    from demoplan.segmentation import stream_from_demonstration, write_csv

    demo = Demonstration(
        "push", (Step("a", Pose((0.5, 0.5, 0.0))),), initial=(("a", Pose((0.1, 0.1, 0.0))),)
    )
    stream_path = tmp_path / "push.csv"
    write_csv(
        stream_from_demonstration(demo, rate_hz=60, noise_m=0.001, nudges=1, nudge_m=0.05, rng=0),
        stream_path,
    )
    out = tmp_path / "push.json"
    done = subprocess.run(
        [sys.executable, "-m", "demoplan", "segment", str(stream_path), "-o", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "push (not a step): a slid 5.0 cm" in done.stderr
    assert "1 step (1 push and 0 nudges left out)" in done.stderr
    # With min_distance above the push, the push is a nudge; a bad name is exit 1.
    bigger = subprocess.run(
        [
            sys.executable,
            "-m",
            "demoplan",
            "segment",
            str(stream_path),
            "-o",
            str(out),
            "--set",
            "min_distance=0.08",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert "0 pushes and 1 nudge left out" in bigger.stderr
    bad = subprocess.run(
        [
            sys.executable,
            "-m",
            "demoplan",
            "segment",
            str(stream_path),
            "-o",
            str(tmp_path / "x.json"),
            "--set",
            "speed=1",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "--set" in bad.stderr
    assert not (tmp_path / "x.json").exists()


@pytest.mark.parametrize("command", ["segment", "import", "learn"])
def test_a_pipe_or_device_as_input_is_one_line_not_a_hang(tmp_path: Path, command: str) -> None:
    """A FIFO blocks on open and /dev/zero never ends: both are refused at once."""
    import os

    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for source in (fifo, Path("/dev/zero")):
        out = tmp_path / ("out" if command == "import" else "out.json")
        done = subprocess.run(
            [sys.executable, "-m", "demoplan", command, str(source), "-o", str(out)],
            capture_output=True,
            text=True,
            timeout=60,
            check=False,
        )
        assert done.returncode == 1, done.stderr
        assert done.stderr.count("\n") == 1 and "not a regular file" in done.stderr
        assert str(source) in done.stderr and not out.exists()
