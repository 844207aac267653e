"""Pose streams as first-class input: tracked landmarks (``--landmarks``), an
objects file for ``segment``, ``learn`` and ``import`` (``--objects-file``),
and the unit of a CSV stream's positions (``--units``, ``# units:``)."""

from __future__ import annotations

import csv
import json
import math
import random
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.model import Demonstration, Pose, Step
from demoplan.rotations import quat_from_rpy
from demoplan.segmentation import write_csv
from demoplan.segmentation.synthetic import stream_from_demonstration
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES

KITTING = load_demonstrations([EXAMPLES / "kitting" / "demonstrations.json"])
SET_TABLE = load_demonstrations([EXAMPLES / "set_table"])
FOLDER_SETTINGS = settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)


def write_scaled(source: Path, target: Path, factor: float, comment: str | None = None) -> None:
    """``source`` with x, y, z multiplied by ``factor`` (metres → cm or mm)."""
    with source.open(newline="") as handle:
        rows = list(csv.reader(handle))
    header = rows[0]
    columns = [header.index(c) for c in ("x", "y", "z")]
    with target.open("w", newline="") as handle:
        if comment is not None:
            handle.write(comment + "\n")
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(header)
        for row in rows[1:]:
            writer.writerow(
                [repr(float(v) * factor) if i in columns else v for i, v in enumerate(row)]
            )


# --------------------------------------------------------------------------- landmarks


@FOLDER_SETTINGS
@given(index=st.integers(0, len(KITTING) - 1), seed=st.integers(0, 2**16), glob=st.booleans())
def test_a_tracked_tray_segments_as_the_landmark(
    tmp_path: Path, index: int, seed: int, glob: bool
) -> None:
    """The kitting tray tracked with the objects: with ``--landmarks tray`` it is
    the demonstration's landmark at its tracked pose, never an object."""
    demo = KITTING[index]
    stream = stream_from_demonstration(demo, rate_hz=60, noise_m=0.002, rng=seed)
    assert "tray" in stream.objects
    path = tmp_path / f"kit-{seed}.csv"
    write_csv(stream, path)
    out = tmp_path / f"kit-{seed}.json"
    result = invoke("segment", path, "-o", out, "--landmarks", "tr*" if glob else "tray")
    assert result.exit_code == 0, result.output
    (found,) = load_demonstrations([out])
    assert [name for name, _ in found.landmarks] == ["tray"]
    assert "tray" not in dict(found.initial)
    assert [s.object for s in found.steps] == [s.object for s in demo.steps]
    tracked, given_pose = dict(found.landmarks)["tray"], dict(demo.landmarks)["tray"]
    assert math.dist(tracked.position, given_pose.position) < 0.005  # 2 mm noise, averaged


def test_without_landmarks_the_tray_is_an_object(tmp_path: Path) -> None:
    stream = stream_from_demonstration(KITTING[0], rate_hz=60, noise_m=0.002, rng=1)
    write_csv(stream, tmp_path / "kit.csv")
    result = invoke("segment", tmp_path / "kit.csv", "-o", tmp_path / "kit.json")
    assert result.exit_code == 0, result.output
    (found,) = load_demonstrations([tmp_path / "kit.json"])
    assert not found.landmarks and "tray" in dict(found.initial)


def test_learn_takes_tracked_landmarks(tmp_path: Path) -> None:
    """``learn`` on the streams with ``--landmarks tray`` places the kit relative to
    the tray, as from the demonstration file."""
    paths = []
    for k, demo in enumerate(KITTING):
        paths.append(tmp_path / f"kit-{k + 1}.csv")
        write_csv(stream_from_demonstration(demo, rate_hz=60, noise_m=0.0015, rng=k), paths[-1])
    result = invoke("learn", *paths, "--landmarks", "tray", "--json")
    assert result.exit_code == 0, result.output
    model = json.loads(result.stdout)
    assert all(d.get("landmarks", {}).keys() == {"tray"} for d in model["demonstrations"])
    references = {s["object"]: s["position"]["reference"] for s in model["states"]}
    assert references["motor"] == "tray" and references["cable"] == "tray"


@pytest.mark.parametrize(
    ("landmarks", "message"),
    [
        ("bin", "landmarks: no object matches 'bin'; available:"),
        ("motor", "landmarks: landmark 'motor' moved; landmarks must stay in place"),
    ],
)
def test_bad_landmarks_are_refused_in_one_line(
    tmp_path: Path, landmarks: str, message: str
) -> None:
    write_csv(stream_from_demonstration(KITTING[0], rng=2), tmp_path / "kit.csv")
    result = invoke(
        "segment", tmp_path / "kit.csv", "-o", tmp_path / "o.json", "--landmarks", landmarks
    )
    assert result.exit_code == 1
    assert result.stderr.count("\n") == 1 and message in result.stderr
    assert not (tmp_path / "o.json").exists()


# --------------------------------------------------------------------------- objects file


def turned(demo: Demonstration, seed: int) -> Demonstration:
    """``demo`` with every object placed at 30° ± 1° of yaw (as a tracker reports a
    plate's yaw, whichever way round it lies: a consistent, meaningless angle)."""
    rng = random.Random(seed)
    steps = tuple(
        Step(s.object, Pose(s.pose.position, quat_from_rpy([0.0, 0.0, 30.0 + rng.uniform(-1, 1)])))
        for s in demo.steps
    )
    initial = tuple((n, Pose(p.position, quat_from_rpy([0.0, 0.0, 0.0]))) for n, p in demo.initial)
    return replace(demo, steps=steps, initial=initial)


def test_learn_from_streams_with_an_objects_file_knows_a_plate_is_round(tmp_path: Path) -> None:
    """A CSV-only model learns the plate's tracked yaw as if it mattered; with the
    objects file the plate is a cylinder, its yaw taken modulo any turn (0°, the
    representative) and written as a cylinder into the model's demonstrations.
    The knife, a box, keeps its yaw either way."""
    paths = []
    for k, demo in enumerate(SET_TABLE):
        paths.append(tmp_path / f"set-table-{k + 1}.csv")
        write_csv(stream_from_demonstration(turned(demo, k), rng=k), paths[-1])
    geometry = tmp_path / "objects.json"
    shapes = {n: {"shape": g.shape, "size": list(g.size)} for n, g in SET_TABLE[0].objects}
    geometry.write_text(json.dumps({"objects": shapes}))

    def learned(*options: Any) -> dict[str, Any]:
        result = invoke("learn", *paths, "--json", "--paper", *options)
        assert result.exit_code == 0, result.output
        model: dict[str, Any] = json.loads(result.stdout)
        return model

    def yaws(model: dict[str, Any], name: str) -> list[float]:
        states = [s for s in model["states"] if s["object"] == name]
        return [float(s["orientation"]["value"][-1]) for s in states]

    csv_only, with_shapes = learned(), learned("--objects-file", geometry)
    assert yaws(csv_only, "plate") == pytest.approx([30.0], abs=1.5)
    assert yaws(with_shapes, "plate") == pytest.approx([0.0], abs=0.5)
    for model in (csv_only, with_shapes):
        assert yaws(model, "knife") == pytest.approx([30.0] * len(yaws(model, "knife")), abs=1.5)
    assert all("objects" not in d for d in csv_only["demonstrations"])
    assert all(d["objects"]["plate"]["shape"] == "cylinder" for d in with_shapes["demonstrations"])


def test_an_objects_file_needs_a_stream_and_known_names(tmp_path: Path) -> None:
    geometry = tmp_path / "objects.json"
    geometry.write_text(
        json.dumps({"objects": {"mug": {"shape": "cylinder", "size": [0.08, 0.08, 0.1]}}})
    )
    result = invoke("learn", EXAMPLES / "set_table", "--json", "--objects-file", geometry)
    assert result.exit_code == 1 and "no pose stream is given" in result.stderr
    write_csv(stream_from_demonstration(SET_TABLE[0], rng=3), tmp_path / "s.csv")
    shapes = {n: {"shape": g.shape, "size": list(g.size)} for n, g in SET_TABLE[0].objects}
    shapes["mug"] = {"shape": "cylinder", "size": [0.08, 0.08, 0.1]}
    geometry.write_text(json.dumps({"objects": shapes}))
    result = invoke("learn", tmp_path / "s.csv", "--json", "--objects-file", geometry)
    assert result.exit_code == 1
    assert "objects.mug: unknown object 'mug'; the stream's objects are" in result.stderr


# --------------------------------------------------------------------------- units


@pytest.fixture(scope="module")
def metre_stream(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("units") / "set-table-1.csv"
    write_csv(stream_from_demonstration(SET_TABLE[0], rate_hz=60, noise_m=0.002, rng=5), path)
    return path


@FOLDER_SETTINGS
@given(unit=st.sampled_from(["cm", "mm"]), declared=st.sampled_from(["option", "comment", "both"]))
def test_a_stream_in_cm_or_mm_segments_as_the_metre_file(
    metre_stream: Path, tmp_path: Path, unit: str, declared: str
) -> None:
    factor = {"cm": 100.0, "mm": 1000.0}[unit]
    scaled = tmp_path / f"scaled-{unit}-{declared}.csv"
    comment = f"# units: {unit}" if declared in {"comment", "both"} else None
    write_scaled(metre_stream, scaled, factor, comment)
    options = ["--units", unit] if declared in {"option", "both"} else []
    reference = invoke("segment", metre_stream, "-o", tmp_path / "m.json", "--json", "--name", "d")
    converted = invoke(
        "segment", scaled, "-o", tmp_path / "u.json", "--json", "--name", "d", *options
    )
    assert reference.exit_code == 0 and converted.exit_code == 0, converted.output
    expected, found = json.loads(reference.stdout), json.loads(converted.stdout)
    assert [s["object"] for s in found["steps"]] == [s["object"] for s in expected["steps"]]
    for a, b in zip(found["steps"], expected["steps"], strict=True):
        assert a["position"] == pytest.approx(b["position"], abs=1e-9)


@pytest.mark.parametrize("unit", ["cm", "mm"])
def test_a_stream_in_cm_or_mm_without_units_is_refused_naming_units(
    metre_stream: Path, tmp_path: Path, unit: str
) -> None:
    scaled = tmp_path / "scaled.csv"
    write_scaled(metre_stream, scaled, {"cm": 100.0, "mm": 1000.0}[unit])
    for command in (["segment", scaled, "-o", tmp_path / "o.json"], ["learn", scaled, "--json"]):
        result = invoke(*command)
        assert result.exit_code == 1
        assert result.stderr.count("\n") == 1, result.stderr
        assert f"{scaled}: units: positions reach" in result.stderr
        assert "--units" in result.stderr and "# units: mm" in result.stderr
        assert "no pick-and-place step" not in result.stderr


def test_units_option_and_comment_must_agree(metre_stream: Path, tmp_path: Path) -> None:
    scaled = tmp_path / "mm.csv"
    write_scaled(metre_stream, scaled, 1000.0, "# units: mm")
    result = invoke("segment", scaled, "-o", tmp_path / "o.json", "--units", "cm")
    assert result.exit_code == 1
    assert "units: the file says '# units: mm', --units says cm; they must agree" in result.stderr


def test_an_unknown_unit_comment_is_refused(metre_stream: Path, tmp_path: Path) -> None:
    scaled = tmp_path / "in.csv"
    write_scaled(metre_stream, scaled, 39.37, "# units: inch")
    result = invoke("segment", scaled, "-o", tmp_path / "o.json")
    assert result.exit_code == 1
    assert "line 1: '# units: inch' names no unit of length; m, cm or mm expected" in result.stderr


def test_metres_declared_are_not_second_guessed(tmp_path: Path) -> None:
    """A hall 30 m across, declared in metres, is read as it is."""
    stream = stream_from_demonstration(SET_TABLE[0], rng=6)
    write_csv(stream, tmp_path / "m.csv")
    write_scaled(tmp_path / "m.csv", tmp_path / "hall.csv", 1.0, "# units: m")
    rows = (tmp_path / "hall.csv").read_text().splitlines()
    header = rows[1].split(",")
    x = header.index("x")
    shifted = [rows[0], rows[1]] + [
        ",".join(repr(float(c) + 30.0) if i == x else c for i, c in enumerate(r.split(",")))
        for r in rows[2:]
    ]
    (tmp_path / "hall.csv").write_text("\n".join(shifted) + "\n")
    result = invoke("segment", tmp_path / "hall.csv", "-o", tmp_path / "o.json")
    assert result.exit_code == 0, result.output
    undeclared = tmp_path / "undeclared.csv"
    undeclared.write_text("\n".join(shifted[1:]) + "\n")
    assert invoke("segment", undeclared, "-o", tmp_path / "o.json").exit_code == 1


# --------------------------------------------------------------------------- import


def test_import_takes_an_objects_file(tmp_path: Path) -> None:
    """The toy recording's box gets the file's cylinder geometry (replacing the
    model's box); the post landmark keeps the recording's; an unknown name is refused."""
    from tests.segmentation.test_import import box_states, write_recording

    recording = write_recording(tmp_path / "toy.hdf5", box_states())
    geometry = tmp_path / "objects.yaml"
    geometry.write_text(
        "units: {length: cm}\nobjects:\n  box: {shape: cylinder, size: [10, 10, 10]}\n"
    )
    result = invoke("import", recording, "-o", tmp_path / "out", "--objects-file", geometry)
    assert result.exit_code == 0, result.output
    (demo,) = load_demonstrations([tmp_path / "out"])
    shapes = dict(demo.objects)
    assert shapes["box"].shape == "cylinder" and shapes["box"].size == pytest.approx((0.1,) * 3)
    assert shapes["post"].shape == "cylinder"  # the recording's own
    geometry.write_text("objects:\n  mug: {shape: cylinder, size: [0.1, 0.1, 0.1]}\n")
    result = invoke("import", recording, "-o", tmp_path / "again", "--objects-file", geometry)
    assert result.exit_code == 1 and "objects.mug: unknown object 'mug'" in result.stderr
    assert not (tmp_path / "again").exists()


def test_an_objects_file_must_agree_with_the_demonstration_files(tmp_path: Path) -> None:
    """Streams and demonstration files learned together: one geometry per object."""
    write_csv(stream_from_demonstration(SET_TABLE[0], rng=7), tmp_path / "s.csv")
    shapes = {n: {"shape": g.shape, "size": list(g.size)} for n, g in SET_TABLE[0].objects}
    shapes["plate"] = {"shape": "box", "size": [0.26, 0.26, 0.02]}
    geometry = tmp_path / "objects.json"
    geometry.write_text(json.dumps({"objects": shapes}))
    demo_file = EXAMPLES / "set_table" / "demonstration-2.json"
    result = invoke("learn", tmp_path / "s.csv", demo_file, "--json", "--objects-file", geometry)
    assert result.exit_code == 1
    assert "objects.plate: cylinder" in result.stderr and "differs from box" in result.stderr


def test_a_bag_is_in_metres(tmp_path: Path) -> None:
    from demoplan.segmentation import write_bag

    write_bag(stream_from_demonstration(SET_TABLE[0], rng=8), tmp_path / "bag")
    result = invoke("segment", tmp_path / "bag", "-o", tmp_path / "o.json", "--units", "mm")
    assert result.exit_code == 1
    assert "units: a ROS 2 bag is in metres (REP 103)" in result.stderr
    assert (
        invoke("segment", tmp_path / "bag", "-o", tmp_path / "o.json", "--units", "m").exit_code
        == 0
    )


def test_an_objects_files_colours_are_written_into_the_demonstrations(tmp_path: Path) -> None:
    """An objects file's ``colour`` (as a demonstration file's) is written into
    what ``segment`` and ``import`` make, for an object and a landmark alike,
    as its ``type`` is; it was read, checked and left out."""
    from tests.segmentation.test_import import box_states, write_recording

    geometry = tmp_path / "objects.json"
    shapes = {n: {"shape": g.shape, "size": list(g.size)} for n, g in SET_TABLE[0].objects}
    shapes["plate"]["colour"] = [1.0, 0.0, 0.0]
    geometry.write_text(json.dumps({"objects": shapes}))
    stream = EXAMPLES / "streams" / "set-table-1.csv"
    result = invoke("segment", stream, "--objects-file", geometry, "-o", tmp_path / "seg.json")
    assert result.exit_code == 0, result.output
    (demo,) = load_demonstrations([tmp_path / "seg.json"])
    assert demo.given_colours == {"plate": "#ff0000"}

    recording = write_recording(tmp_path / "toy.hdf5", box_states())
    geometry.write_text(
        json.dumps(
            {
                "objects": {
                    "box": {"shape": "box", "size": [0.1, 0.1, 0.1], "colour": "#1F5FBF"},
                    "post": {"shape": "cylinder", "size": [0.04, 0.04, 0.2], "colour": "#27ae60"},
                }
            }
        )
    )
    result = invoke("import", recording, "-o", tmp_path / "out", "--objects-file", geometry)
    assert result.exit_code == 0, result.output
    (imported,) = load_demonstrations([tmp_path / "out"])
    assert "post" in dict(imported.landmarks)
    assert imported.given_colours == {"box": "#1f5fbf", "post": "#27ae60"}


@pytest.mark.parametrize(
    ("change", "span"),
    [
        ("one row at t = 1e300", "1e+300 s"),
        ("one row in ns", "s, from t = 0 s"),
        ("every time in ns", "s, from t = 0 s"),
    ],
)
def test_a_stream_whose_times_span_more_than_a_week_is_refused_in_one_line(
    tmp_path: Path, change: str, span: str
) -> None:
    """A lone absurd time was read as it is: the glass's sample at t = 1e300 s
    became its last pose, and ``segment`` found 8 steps in the set-table
    stream of 7. A span beyond a week (docs/limits.md) is refused, naming the
    first and the last sample; nothing is written."""
    lines = (EXAMPLES / "streams" / "set-table-1.csv").read_text().splitlines()
    rows = [line.split(",") for line in lines[1:]]
    if change == "one row at t = 1e300":
        rows[4][0] = "1e300"
    elif change == "one row in ns":
        rows[4][0] = str(round(float(rows[4][0]) * 1e9) + 10**9)
    else:
        rows = [[str(round(float(row[0]) * 1e9)), *row[1:]] for row in rows]
    stream = tmp_path / "stream.csv"
    stream.write_text("\n".join([lines[0], *(",".join(row) for row in rows)]) + "\n")
    for command in ("segment", "learn"):
        result = invoke(command, stream, "-o", tmp_path / "out.json")
        assert result.exit_code == 1, result.output
        assert result.stderr.count("\n") == 1, result.stderr
        assert f"{stream}: t: its times span" in result.stderr, result.stderr
        assert span in result.stderr and "at most 7 days" in result.stderr, result.stderr
        assert not (tmp_path / "out.json").exists()
