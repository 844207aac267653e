"""`demoplan segment` and `demoplan learn` on pose streams (CSV, ROS 2 bags)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.demonstrations import load_demonstrations
from demoplan.segmentation import write_bag, write_csv
from demoplan.segmentation.synthetic import stream_from_demonstration
from tests.helpers import EXAMPLES


def invoke(*args: Any) -> Any:
    return CliRunner().invoke(app, [str(a) for a in args])


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
    sequences and 32 constraints."""
    result = invoke("learn", *streams, "-o", tmp_path / "model.json", "--json")
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
    (found,) = load_demonstrations([tmp_path / "bag"])
    assert [s.object for s in found.steps] == [s.object for s in demo.steps]
    assert found.name == "bag"


def test_segment_bad_stream_exits_1(tmp_path: Path) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("t,object,x,y,z\n0,plate,0.1,nan,0\n")
    result = invoke("segment", path, "-o", tmp_path / "out.json")
    assert result.exit_code == 1
    assert str(path) in result.stderr and not (tmp_path / "out.json").exists()
