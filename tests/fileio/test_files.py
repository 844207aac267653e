"""File formats (docs/formats.md): demonstration files, model files, atomic writes.

Library-level tests; the command line's handling of the same inputs is in
``test_cli.py``.
"""

from __future__ import annotations

import json
import math
import os
import re
import signal
import stat
import tempfile
from pathlib import Path
from typing import Any

import pytest

from demoplan import TaskModelLearner, load_demonstrations, load_model, save_model
from demoplan.documents.demonstrations import demonstration_to_dict, demonstrations_from_document
from demoplan.errors import InputError
from demoplan.fileio import check_format, read_document, write_atomic
from demoplan.learning import LearningSettings
from demoplan.learning.modelfile import model_from_dict, model_to_dict
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.model import TaskModel
from demoplan.rotations import angle_between
from tests.support.helpers import EXAMPLES, demo, raw, write

SET_TABLE = EXAMPLES / "set_table"


def load_one(tmp_path: Path, data: Any, name: str = "demo.json") -> Any:
    demos = load_demonstrations([write(tmp_path / name, data)])
    assert len(demos) == 1
    return demos[0]


@pytest.fixture(scope="module")
def set_table_model() -> TaskModel:
    """Experiment 1 as the paper learns it (the examples were drawn for PAPER_SETTINGS)."""
    return TaskModelLearner(PAPER_SETTINGS).fit(load_demonstrations([SET_TABLE])).model_


# --- demonstration files: what is accepted --------------------------------------------


@pytest.mark.parametrize(("unit", "scale"), [("m", 1.0), ("cm", 0.01), ("mm", 0.001)])
def test_units_scale_every_length_to_metres(tmp_path: Path, unit: str, scale: float) -> None:
    def written(*metres: float) -> list[float]:  # a tabletop in metres, in the file's unit
        return [round(v / scale, 9) for v in metres]

    data = demo(
        [{"object": "plate", "position": written(0.5, 0.4, 0.02)}],
        units={"length": unit},
        objects={"plate": {"shape": "cylinder", "size": written(0.08, 0.08, 0.02)}},
        landmarks={"board": {"position": written(0.45, 0.4, 0), "yaw": 0}},
        initial={"plate": {"position": written(0.2, 0.1)}},
    )
    d = load_one(tmp_path, data)
    assert d.steps[0].pose.position == pytest.approx((0.5, 0.4, 0.02))
    assert d.geometry()["plate"].size == pytest.approx((0.08, 0.08, 0.02))
    assert d.landmark_poses()["board"].position == pytest.approx((0.45, 0.4, 0))
    assert d.initial_poses()["plate"].position == pytest.approx((0.2, 0.1, 0))


def test_unknown_length_unit_is_refused(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"demo\.json: units\.length"):
        load_one(tmp_path, demo(units={"length": "inch"}))


def test_yaw_rpy_and_quat_give_the_same_rotation(tmp_path: Path) -> None:
    steps = [
        {"object": "a", "position": [0, 0], "yaw": 90},
        {"object": "b", "position": [0, 0], "rpy": [0, 0, 90]},
        {"object": "c", "position": [0, 0], "quat": [0, 0, 0.7071068, 0.7071068]},
        {"object": "d", "position": [0, 0], "yaw": 0},
        {"object": "e", "position": [0, 0]},
    ]
    d = load_one(tmp_path, demo(steps))
    yaw, rpy, quat, zero, none = (s.pose.orientation for s in d.steps)
    assert yaw == pytest.approx((0, 0, math.sqrt(0.5), math.sqrt(0.5)), abs=1e-9)
    assert rpy == pytest.approx(yaw, abs=1e-9)
    assert quat == pytest.approx(yaw, abs=1e-7)
    assert math.isclose(math.hypot(*quat), 1.0)  # normalised
    assert angle_between(zero, yaw) == pytest.approx(90.0)
    assert none is None  # no orientation: unknown


def test_rpy_is_extrinsic_xyz_in_degrees(tmp_path: Path) -> None:
    d = load_one(tmp_path, demo([{"object": "a", "position": [0, 0], "rpy": [90, 0, 90]}]))
    assert d.steps[0].pose.rpy == pytest.approx((90, 0, 90), abs=1e-6)


@pytest.mark.parametrize(
    "orientation",
    [
        {"yaw": 90, "rpy": [0, 0, 90]},
        {"yaw": 90, "quat": [0, 0, 0, 1]},
        {"rpy": [0, 0, 0], "quat": [0, 0, 0, 1]},
    ],
)
def test_more_than_one_orientation_is_refused(tmp_path: Path, orientation: dict[str, Any]) -> None:
    with pytest.raises(InputError, match=r"demo\.json: steps\[0\]: give one orientation"):
        load_one(tmp_path, demo([{"object": "a", "position": [0, 0], **orientation}]))


def test_more_than_one_orientation_in_a_landmark_is_refused(tmp_path: Path) -> None:
    data = demo(landmarks={"board": {"position": [0, 0], "yaw": 0, "quat": [0, 0, 0, 1]}})
    with pytest.raises(InputError, match=r"landmarks\.board: give one orientation"):
        load_one(tmp_path, data)


def test_missing_z_is_zero_and_landmarks_and_initial_are_read(tmp_path: Path) -> None:
    data = demo(
        [
            {"object": "plate", "position": [0.5, 0.4]},
            {"object": "cup", "position": [0.6, 0.4, 0.02]},
        ],
        landmarks={"board": {"position": [0.4, 0.1], "yaw": 30}},
        initial={
            "plate": {"position": [0.2, 0.1], "yaw": 10},
            "cup": {"position": [0.1, 0.1, 0.0]},
        },
    )
    d = load_one(tmp_path, data)
    assert [s.object for s in d.steps] == ["plate", "cup"]
    assert d.steps[0].pose.position == (0.5, 0.4, 0.0)
    assert d.steps[1].pose.position == (0.6, 0.4, 0.02)
    board = d.landmark_poses()["board"]
    assert board.position == (0.4, 0.1, 0.0)
    assert board.rpy == pytest.approx((0, 0, 30))
    assert set(d.initial_poses()) == {"plate", "cup"}
    assert d.initial_poses()["plate"].position == (0.2, 0.1, 0.0)
    assert d.name == "demo"  # no "name": the file's stem
    assert d.source == str(tmp_path / "demo.json")


def test_several_demonstrations_per_file(tmp_path: Path) -> None:
    data = {
        "format": "demoplan/demonstrations-1",
        "units": {"length": "cm"},
        "demonstrations": [
            {"name": "first", "steps": [{"object": "a", "position": [10, 20]}]},
            {"steps": [{"object": "a", "position": [30, 40]}]},
            {"units": {"length": "mm"}, "steps": [{"object": "a", "position": [500, 600]}]},
        ],
    }
    demos = load_demonstrations([write(tmp_path / "many.json", data)])
    assert [d.name for d in demos] == ["first", "many-2", "many-3"]
    assert demos[0].steps[0].pose.position == pytest.approx((0.1, 0.2, 0))  # top-level cm
    assert demos[1].steps[0].pose.position == pytest.approx((0.3, 0.4, 0))
    assert demos[2].steps[0].pose.position == pytest.approx((0.5, 0.6, 0))  # its own mm


def test_error_in_one_of_several_demonstrations_names_it(tmp_path: Path) -> None:
    data = {
        "format": "demoplan/demonstrations-1",
        "demonstrations": [demo(), {"steps": [{"object": "a"}]}],
    }
    with pytest.raises(InputError, match=r"many\.json: demonstrations\[1\]\.steps\[0\]\.position"):
        load_demonstrations([write(tmp_path / "many.json", data)])


def test_shipped_multi_demonstration_files_load() -> None:
    blocks = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    assert [d.name for d in blocks] == ["pyramid-1", "pyramid-2"]
    cucumber = load_demonstrations([EXAMPLES / "cucumber" / "demonstrations.json"])
    # Lengths there are in cm: a 40 cm board.
    assert cucumber[0].geometry()["board"].size == pytest.approx((0.4, 0.25, 0.02))


def test_folder_is_read_in_name_order(tmp_path: Path) -> None:
    folder = tmp_path / "demos"
    folder.mkdir()
    for name, x in [("b.json", 0.2), ("c.yaml", 0.3), ("a.json", 0.1)]:
        data = demo([{"object": "plate", "position": [x, 0.0]}])
        text = json.dumps(data)  # JSON is valid YAML
        write(folder / name, text)
    write(folder / "notes.txt", "not a demonstration")
    write(folder / ".hidden.json", "{ broken")  # editor back-ups and the like are skipped
    demos = load_demonstrations([folder])
    assert [d.name for d in demos] == ["a", "b", "c"]
    assert [d.steps[0].pose.position[0] for d in demos] == [0.1, 0.2, 0.3]


@pytest.mark.parametrize("inside", [True, False], ids=["link inside", "link leading out"])
def test_a_link_in_a_folder_is_read_only_if_it_stays_in_the_folder(
    tmp_path: Path, inside: bool
) -> None:
    folder = tmp_path / "demos"
    folder.mkdir()
    write(folder / "a.json", json.dumps(demo([{"object": "plate", "position": [0.1, 0.0]}])))
    target = (folder if inside else tmp_path) / "target.data"
    write(target, json.dumps(demo([{"object": "plate", "position": [0.2, 0.0]}])))
    (folder / "b.json").symlink_to(target)
    if inside:
        assert [d.steps[0].pose.position[0] for d in load_demonstrations([folder])] == [0.1, 0.2]
        return
    with pytest.raises(InputError) as error:
        load_demonstrations([folder])
    assert error.value.source == str(folder / "b.json")
    assert "a link leading out of the folder" in str(error.value) and str(target) in str(
        error.value
    )
    assert load_demonstrations([folder / "b.json"])[0].steps[0].pose.position[0] == 0.2  # named


def test_set_table_folder_is_in_order() -> None:
    demos = load_demonstrations([SET_TABLE])
    assert [d.name for d in demos] == ["set-table-1", "set-table-2", "set-table-3"]


def test_yaml_demonstration(tmp_path: Path) -> None:
    text = """
format: demoplan/demonstration-1
name: yaml-demo
units: {length: cm}
objects:
  plate: {shape: cylinder, size: [26, 26, 2]}
steps:
  - {object: plate, position: [52, 44], yaw: 90}
"""
    d = load_one(tmp_path, text, "demo.yaml")
    assert d.name == "yaml-demo"
    assert d.steps[0].pose.position == pytest.approx((0.52, 0.44, 0.0))
    assert d.steps[0].pose.rpy == pytest.approx((0, 0, 90))


@pytest.mark.parametrize("value", [".nan", ".inf", "-.inf"])
def test_yaml_non_finite_is_refused(tmp_path: Path, value: str) -> None:
    text = f"format: demoplan/demonstration-1\nsteps:\n  - object: a\n    position: [{value}, 0]\n"
    with pytest.raises(InputError, match=r"demo\.yaml: steps\[0\]\.position\[0\]: .*finite"):
        load_one(tmp_path, text, "demo.yaml")


def test_malformed_yaml_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"demo\.yaml: malformed YAML at line \d+") as info:
        load_one(tmp_path, "format: [unclosed\nsteps: 1\n", "demo.yaml")
    assert "\n" not in str(info.value)


def test_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(demo()).encode())
    assert load_demonstrations([path])[0].steps[0].object == "plate"


def test_round_trip_through_demonstration_to_dict(tmp_path: Path) -> None:
    original = load_demonstrations([EXAMPLES / "cucumber" / "demonstrations.json"])
    again = [demonstrations_from_document(demonstration_to_dict(d), "x.json")[0] for d in original]
    assert again == original


# --- demonstration files: what is refused ---------------------------------------------

BAD_DEMONSTRATIONS: list[tuple[str, Any, str]] = [
    (
        "malformed JSON",
        '{"format": "demoplan/demonstration-1", "steps": [',
        r"malformed JSON at line 1",
    ),
    ("empty file", "", r"malformed JSON"),
    ("top-level list", "[]", r"an array at top level; an object"),
    ("missing position", demo([{"object": "plate"}]), r"steps\[0\]\.position: missing"),
    ("missing object", demo([{"position": [0, 0]}]), r"steps\[0\]\.object: missing"),
    ("missing steps", {"format": "demoplan/demonstration-1"}, r"steps: missing"),
    ("empty demonstration", demo([]), r"steps: empty demonstration"),
    ("unknown kind", demo(format="demoplan/scene-1"), r"format: unknown format 'demoplan/scene-1'"),
    ("nonsense kind", demo(format="hello"), r"format: unknown format 'hello'"),
    ("newer version", demo(format="demoplan/demonstration-2"), r"format: .*version 2, newer"),
    ("no format", {"steps": [{"object": "a", "position": [0, 0]}]}, r"format: missing format"),
    ("format not a string", demo(format=1), r"format: expected a string"),
    (
        "position of one",
        demo([{"object": "a", "position": [0]}]),
        r"steps\[0\]\.position: .*at least 2",
    ),
    (
        "position of four",
        demo([{"object": "a", "position": [0, 0, 0, 0]}]),
        r"steps\[0\]\.position: .*at most 3",
    ),
    (
        "position as text",
        demo([{"object": "a", "position": ["1", "2"]}]),
        r"steps\[0\]\.position\[0\]: .*number",
    ),
    (
        "boolean coordinate",
        demo([{"object": "a", "position": [True, 0]}]),
        r"steps\[0\]\.position\[0\]: .*number",
    ),
    (
        "zero quaternion",
        demo([{"object": "a", "position": [0, 0], "quat": [0, 0, 0, 0]}]),
        r"steps\[0\]: quat \[x, y, z, w\]: a unit quaternion expected",
    ),
    (
        "short quaternion",
        demo([{"object": "a", "position": [0, 0], "quat": [0, 0, 1]}]),
        r"steps\[0\]\.quat",
    ),
    ("short rpy", demo([{"object": "a", "position": [0, 0], "rpy": [0, 0]}]), r"steps\[0\]\.rpy"),
    (
        "unknown step field",
        demo([{"object": "a", "position": [0, 0], "yaww": 3}]),
        r"steps\[0\]\.yaww: unknown field",
    ),
    (
        "step object not in objects",
        demo([{"object": "cup", "position": [0, 0]}], objects={"plate": {"size": [0.1, 0.1, 0.1]}}),
        r"steps\[0\]\.object: unknown object 'cup'",
    ),
    (
        "negative size",
        demo(objects={"plate": {"size": [0.1, -0.1, 0.1]}}),
        r"objects\.plate\.size: size must be three positive",
    ),
    (
        "moving a landmark",
        demo([{"object": "board", "position": [0, 0]}], landmarks={"board": {"position": [0, 0]}}),
        r"steps\[0\]\.object: 'board' is a landmark",
    ),
    (
        "NaN literal",
        raw('{"object": "a", "position": [NaN, 0]}'),
        r"steps\[0\]\.position\[0\]: NaN is not a number",
    ),
    (
        "Infinity literal",
        raw('{"object": "a", "position": [0, Infinity]}'),
        r"steps\[0\]\.position\[1\]: Infinity is not a number",
    ),
    (
        "-Infinity literal",
        raw('{"object": "a", "position": [0, 0], "yaw": -Infinity}'),
        r"steps\[0\]\.yaw: -Infinity is not a number",
    ),
    (
        "overflowing number",
        raw('{"object": "a", "position": [1e999, 0]}'),
        r"steps\[0\]\.position\[0\]: Infinity is not a number",
    ),
    (
        "huge integer literal",
        raw('{"object": "a", "position": [' + "9" * 5000 + ", 0]}"),
        r"malformed JSON",
    ),
    (
        "collection of none",
        {"format": "demoplan/demonstrations-1", "demonstrations": []},
        r"demonstrations: no demonstrations",
    ),
    (
        "collection of a list",
        {"format": "demoplan/demonstrations-1", "demonstrations": [[1]]},
        r"demonstrations\[0\]",
    ),
    (
        "collection holding a newer demonstration",
        {
            "format": "demoplan/demonstrations-1",
            "demonstrations": [demo(format="demoplan/demonstration-2")],
        },
        r"demonstrations\[0\]: format: .*newer",
    ),
]


@pytest.mark.parametrize(
    ("text", "pattern"), [c[1:] for c in BAD_DEMONSTRATIONS], ids=[c[0] for c in BAD_DEMONSTRATIONS]
)
def test_bad_demonstration_is_one_clear_input_error(
    tmp_path: Path, text: Any, pattern: str
) -> None:
    path = write(tmp_path / "bad.json", text)
    with pytest.raises(InputError) as info:
        load_demonstrations([path])
    message = str(info.value)
    assert message.startswith(f"{path}: "), message  # names the file first
    assert "\n" not in message
    assert info.value.exit_code == 1
    assert re.search(pattern, message), message


def test_missing_file_and_empty_folder(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"nope\.json: no such file; a JSON or YAML document"):
        load_demonstrations([tmp_path / "nope.json"])
    (tmp_path / "empty").mkdir()
    write(tmp_path / "empty" / "readme.txt", "hello")
    with pytest.raises(InputError, match=r"empty: folder holds no \.json or \.yaml"):
        load_demonstrations([tmp_path / "empty"])
    with pytest.raises(InputError, match="at least one expected"):
        load_demonstrations([])


def test_inconsistent_geometry_across_files_is_refused(tmp_path: Path) -> None:
    one = write(
        tmp_path / "one.json",
        demo(objects={"plate": {"shape": "cylinder", "size": [0.26, 0.26, 0.02]}}),
    )
    two = write(
        tmp_path / "two.json",
        demo(objects={"plate": {"shape": "cylinder", "size": [0.30, 0.30, 0.02]}}),
    )
    with pytest.raises(InputError) as info:
        load_demonstrations([one, two])
    message = str(info.value)
    assert message.startswith(f"{two}: objects.plate: ")
    assert str(one) in message  # says where the other geometry came from
    assert "one geometry per object expected" in message


def test_same_geometry_in_other_units_is_consistent(tmp_path: Path) -> None:
    one = write(
        tmp_path / "one.json",
        demo(objects={"plate": {"shape": "cylinder", "size": [0.26, 0.26, 0.02]}}),
    )
    two = write(
        tmp_path / "two.json",
        demo(units={"length": "cm"}, objects={"plate": {"shape": "cylinder", "size": [26, 26, 2]}}),
    )
    assert len(load_demonstrations([one, two])) == 2


def test_different_shape_is_inconsistent(tmp_path: Path) -> None:
    one = write(
        tmp_path / "one.json",
        demo(objects={"plate": {"shape": "cylinder", "size": [0.2, 0.2, 0.02]}}),
    )
    two = write(
        tmp_path / "two.json", demo(objects={"plate": {"shape": "box", "size": [0.2, 0.2, 0.02]}})
    )
    with pytest.raises(InputError, match=r"two\.json: objects\.plate: box"):
        load_demonstrations([one, two])


def test_landmark_in_one_file_moved_in_another(tmp_path: Path) -> None:
    one = write(tmp_path / "one.json", demo(landmarks={"board": {"position": [0, 0]}}))
    two = write(
        tmp_path / "two.json",
        demo([{"object": "plate", "position": [0, 0]}, {"object": "board", "position": [1, 0]}]),
    )
    with pytest.raises(
        InputError, match=r"two\.json: steps\[1\]\.object: 'board' is moved here but is a landmark"
    ):
        load_demonstrations([one, two])


# --- format tags -----------------------------------------------------------------------


def test_check_format() -> None:
    assert check_format({"format": "demoplan/model-1"}, {"model"}, "m.json") == ("model", 1)
    assert check_format({"format": "demoplan/model-1.3"}, {"model"}, "m.json") == ("model", 1)
    with pytest.raises(InputError, match=r"m\.json: format: .*version 2, newer .*upgrade"):
        check_format({"format": "demoplan/model-2"}, {"model"}, "m.json")
    with pytest.raises(
        InputError,
        match=r"m\.json: format: unknown format 'demoplan/scene-1'; expected 'demoplan/model-1'",
    ):
        check_format({"format": "demoplan/scene-1"}, {"model"}, "m.json")
    with pytest.raises(InputError, match="unknown format version"):
        check_format({"format": "demoplan/model-0"}, {"model"}, "m.json")


# --- atomic writes ---------------------------------------------------------------------


def test_write_atomic_replaces_and_leaves_no_temporary_file(tmp_path: Path) -> None:
    target = tmp_path / "sub" / "out.json"
    write_atomic(target, "one\n")
    write_atomic(target, "two\n")
    assert target.read_text() == "two\n"
    assert sorted(p.name for p in target.parent.iterdir()) == ["out.json"]


def test_write_atomic_gives_a_new_file_the_usual_permissions(tmp_path: Path) -> None:
    umask = os.umask(0o027)
    try:
        write_atomic(tmp_path / "new.json", "{}\n")
    finally:
        os.umask(umask)
    assert stat.S_IMODE((tmp_path / "new.json").stat().st_mode) == 0o640  # not mkstemp's 0600


def test_write_atomic_keeps_an_existing_files_permissions(tmp_path: Path) -> None:
    target = tmp_path / "old.json"
    target.write_text("old")
    target.chmod(0o640)
    write_atomic(target, "new")
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    assert target.read_text() == "new"


def test_failed_write_keeps_the_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "model.json"
    target.write_text("old content")

    def broken_fsync(fd: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", broken_fsync)
    no_space = r"model\.json: cannot write \(no space left on the device\)"
    with pytest.raises(InputError, match=no_space):
        write_atomic(target, "new content")
    assert target.read_text() == "old content"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.json"]


def test_writing_onto_a_folder_is_an_input_error(tmp_path: Path) -> None:
    (tmp_path / "out").mkdir()
    with pytest.raises(InputError, match=r"out: is a folder"):
        write_atomic(tmp_path / "out", "x")
    assert list((tmp_path / "out").iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


# --- model files -----------------------------------------------------------------------


def test_model_file_has_the_spec_fields(tmp_path: Path, set_table_model: TaskModel) -> None:
    path = tmp_path / "model.json"
    save_model(set_table_model, path)
    data = json.loads(path.read_text())
    assert data["format"] == "demoplan/model-1"
    assert [s["id"] for s in data["states"]] == list("ABCDEFGHIJ")
    first = data["states"][0]
    assert first["object"] == "plate"
    assert first["position"]["reference"] is None
    assert first["position"]["value"] == pytest.approx([0.52, 0.44, 0.0], abs=0.01)
    assert set(first["orientation"]) >= {"reference", "value"}
    assert data["sequences"][0] == ["A", "B", "C", "D", "E", "F", "G"]
    assert len(data["sequences"]) == len(data["goals"]) == 3
    assert len(data["constraints"]) == 32
    assert all(len(c) == 2 for c in data["constraints"])
    ids = {s["id"] for s in data["states"]}
    assert {x for pair in data["constraints"] for x in pair} <= ids
    assert data["goals"][0] == ["A", "B", "C", "D", "E", "F", "G"]


@pytest.mark.parametrize(
    "example",
    [
        "set_table",
        "blocks/demonstrations.json",
        "cucumber/demonstrations.json",
        "two_placements/demonstrations.json",
    ],
)
def test_model_round_trip(tmp_path: Path, example: str) -> None:
    model = TaskModelLearner(require=()).fit(load_demonstrations([EXAMPLES / example])).model_
    path = tmp_path / "model.json"
    save_model(model, path)
    again = load_model(path)
    assert again.states == model.states
    assert again.sequences == model.sequences
    assert again.constraints == model.constraints
    assert again.goals == model.goals
    assert again.demonstrations == model.demonstrations
    assert again.settings == model.settings
    assert again == model
    assert model_to_dict(again) == model_to_dict(model)


def test_model_files_with_requirements_joined_by_semicolons_still_load(tmp_path: Path) -> None:
    """Before settings were one schema, ``require`` was written as one ';'-joined text."""
    model = TaskModelLearner(require=["B<A", "plate<napkin"]).fit(load_demonstrations([SET_TABLE]))
    data = _model_document(model.model_)
    assert data["settings"]["require"] == ["B<A", "plate<napkin"]
    data["settings"]["require"] = "B<A;plate<napkin"
    again = model_from_dict(data, "old.json")
    assert again.settings == model.settings
    del data["settings"]
    assert model_from_dict(data, "older.json").settings == LearningSettings()


def test_model_round_trip_keeps_teacher_constraints_and_violations(tmp_path: Path) -> None:
    model = TaskModelLearner(require=["B<A"]).fit(load_demonstrations([SET_TABLE])).model_
    assert ("B", "A") in model.teacher_constraints
    assert model.violations  # demonstration 1 puts A (plate) before B (knife)
    save_model(model, tmp_path / "m.json")
    again = load_model(tmp_path / "m.json")
    assert again.teacher_constraints == model.teacher_constraints
    assert again.violations == model.violations


def _model_document(model: TaskModel) -> dict[str, Any]:
    return json.loads(json.dumps(model_to_dict(model)))


def _edit(data: dict[str, Any], edit: str) -> None:
    if edit == "unknown constraint state":
        data["constraints"].append(["A", "ZZ"])
    elif edit == "malformed constraint label":
        data["constraints"].append(["A", "B#x"])
    elif edit == "constraint of three":
        data["constraints"].append(["A", "B", "C"])
    elif edit == "wrong format":
        data["format"] = "demoplan/demonstration-1"
    elif edit == "newer version":
        data["format"] = "demoplan/model-2"
    elif edit == "unknown sequence state":
        data["sequences"][0].append("Q")
    elif edit == "unknown goal state":
        data["goals"][1].append("Q")
    elif edit == "goals missing":
        del data["goals"]
    elif edit == "fewer goals than sequences":
        data["goals"].pop()
    elif edit == "two-number orientation":
        data["states"][0]["orientation"] = {"reference": None, "value": [0, 0]}
    elif edit == "zero quaternion":
        data["states"][0]["orientation"] = {"reference": None, "quat": [0, 0, 0, 0]}
    elif edit == "duplicate state":
        data["states"][1]["id"] = "A"
    elif edit == "lowercase id":
        data["states"][0]["id"] = "a"
    elif edit == "position as text":
        data["states"][0]["position"]["value"] = ["0.5", "0.4"]
    elif edit == "unknown reference":
        data["states"][1]["position"]["reference"] = "teapot"
    elif edit == "violation of nothing":
        data["violations"] = [{"demonstration": 0}]
    elif edit == "violation of unknown demonstration":
        data["violations"] = [{"demonstration": 7, "required": ["A", "B"]}]
    elif edit == "settings of the wrong type":
        data["settings"]["position_noise"] = "loud"
    elif edit == "setting of a list":
        data["settings"]["colour"] = [1]
    elif edit == "setting out of range":
        data["settings"]["n_init"] = 0
    elif edit == "bad member":
        data["states"][0]["members"] = [[0]]
    elif edit == "bad demonstration inside":
        data["demonstrations"][0]["steps"] = []
    else:  # pragma: no cover
        raise AssertionError(edit)


BAD_MODELS = [
    ("unknown constraint state", r"constraints\[\d+\]: 'ZZ' is not a state"),
    ("malformed constraint label", r"constraints\[\d+\]: 'B#x' is not a state"),
    ("constraint of three", r"constraints\[\d+\]: expected a pair"),
    (
        "wrong format",
        r"format: unknown format 'demoplan/demonstration-1'; expected 'demoplan/model-1'",
    ),
    ("newer version", r"format: 'demoplan/model-2' is version 2, newer"),
    ("unknown sequence state", r"sequences\[0\]: 'Q' is not a state"),
    ("unknown goal state", r"goals\[1\]: 'Q' is not a state"),
    ("goals missing", r"goals: missing"),
    ("fewer goals than sequences", r"goals: 2 goals for 3 sequences"),
    (
        "two-number orientation",
        r"states\[0\]\.orientation\.value: expected \[yaw\] or \[roll, pitch, yaw\]",
    ),
    (
        "zero quaternion",
        r"states\[0\]\.orientation\.quat: quat \[x, y, z, w\]: a unit quaternion expected",
    ),
    ("duplicate state", r"states: state id 'A' appears twice"),
    ("lowercase id", r"states\[0\]\.id"),
    ("position as text", r"states\[0\]\.position\.value\[0\]"),
    ("unknown reference", r"states\[1\]\.position\.reference: unknown reference 'teapot'"),
    ("violation of nothing", r"violations\[0\]\.required: missing"),
    (
        "violation of unknown demonstration",
        r"violations\[0\]\.demonstration: demonstration 7 does not exist",
    ),
    ("settings of the wrong type", r"settings\.position_noise: Input should be a valid number"),
    ("setting of a list", r"settings\.colour: unknown field"),
    ("setting out of range", r"settings\.n_init: expected a whole number ≥ 1, got 0"),
    ("bad member", r"states\[0\]\.members\[0\]"),
    ("bad demonstration inside", r"demonstrations\[0\]\.steps: empty demonstration"),
]


@pytest.mark.parametrize(("edit", "pattern"), BAD_MODELS, ids=[b[0] for b in BAD_MODELS])
def test_bad_model_file_is_one_clear_input_error(
    tmp_path: Path, set_table_model: TaskModel, edit: str, pattern: str
) -> None:
    data = _model_document(set_table_model)
    _edit(data, edit)
    path = write(tmp_path / "model.json", data)
    with pytest.raises(InputError) as info:
        load_model(path)
    message = str(info.value)
    assert message.startswith(f"{path}: "), message
    assert "\n" not in message
    assert re.search(pattern, message), message


def test_minimal_spec_model_loads() -> None:
    """The example model of docs/formats.md (no statistics, no demonstrations) is readable."""
    data = {
        "format": "demoplan/model-1",
        "states": [
            {
                "id": "A",
                "object": "plate",
                "position": {"reference": None, "value": [0.52, 0.44, 0.0]},
                "orientation": {"reference": None, "value": [0, 0, 0]},
            },
            {
                "id": "B",
                "object": "knife",
                "position": {"reference": "plate", "value": [0.10, 0.0, 0.0]},
                "orientation": {"reference": None, "value": None},
            },
            {
                "id": "C",
                "object": "fork",
                "position": {"reference": "plate", "value": [-0.08, 0.0]},
            },
        ],
        "sequences": [["A", "B", "C"], ["A", "C", "B"]],
        "constraints": [["A", "B"], ["A", "C"]],
        "goals": [["A", "B", "C"]] * 2,
        "provenance": {"by": "hand"},  # more fields are welcome
    }
    model = model_from_dict(data, "spec.json")
    assert [s.id for s in model.states] == ["A", "B", "C"]
    assert model.state("A").orientation.value == pytest.approx((0, 0, 0, 1))
    assert model.state("B").orientation.value is None
    assert model.state("C").position.value == (-0.08, 0.0, 0.0)
    assert model.constraints == (("A", "B"), ("A", "C"))
    assert model.demonstrations == ()


def test_read_document_refuses_non_objects(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="at top level expected"):
        read_document(write(tmp_path / "x.yaml", "- 1\n- 2\n"))
    assert read_document(write(tmp_path / "x.json", '{"a": 1.5}')) == {"a": 1.5}


def test_write_atomic_writes_into_a_pipe_instead_of_replacing_it(tmp_path: Path) -> None:
    """-o on a device or FIFO writes into it; renaming over it would replace it."""
    import threading

    from demoplan.fileio import write_atomic

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received: list[str] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_text()))
    reader.start()
    write_atomic(fifo, "hello\n")
    reader.join(timeout=120)  # returns as soon as the writer closes: a hang guard
    assert received == ["hello\n"]
    assert stat.S_ISFIFO(fifo.stat().st_mode)


def test_write_atomic_through_a_link_replaces_the_file_and_keeps_the_link(tmp_path: Path) -> None:
    from demoplan.fileio import write_atomic

    (tmp_path / "real.json").write_text("old\n")
    link = tmp_path / "link.json"
    link.symlink_to("real.json")
    write_atomic(link, "new\n")
    assert link.is_symlink() and str(link.readlink()) == "real.json"
    assert (tmp_path / "real.json").read_text() == "new\n"


@pytest.mark.parametrize("kind", ["socket", "block-device"])
def test_write_atomic_refuses_a_socket_or_a_block_device(tmp_path: Path, kind: str) -> None:
    """Neither can take a file: refused in one error, and the node is left as it was."""
    import socket
    import tempfile

    from demoplan.fileio import write_atomic

    node = tmp_path / "node"
    if kind == "socket":
        with tempfile.TemporaryDirectory() as short:  # a socket's path is limited to ~107 bytes
            server = socket.socket(socket.AF_UNIX)
            server.bind(str(Path(short) / "s"))
            (Path(short) / "s").rename(node)
            server.close()
        is_kind = stat.S_ISSOCK
    else:
        try:
            os.mknod(node, stat.S_IFBLK | 0o600, os.makedev(7, 0))  # a loop device, never opened
        except PermissionError:
            pytest.skip("making a device node is not permitted here")
        is_kind = stat.S_ISBLK
    with pytest.raises(InputError, match="not a regular file") as caught:
        write_atomic(node, "data\n")
    assert str(node) in str(caught.value)
    assert is_kind(node.lstat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["node"]  # no temporary left


def test_ctrl_c_as_a_staged_file_is_made_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ctrl_c_raises: None
) -> None:
    """Ctrl-C between mkstemp's open and its return (a run of `perceive -o` found
    ``.p.json.XXXX.tmp`` left behind so) leaves no temporary file: the signal is
    held back until the block that removes the file is entered."""
    real_mkstemp = tempfile.mkstemp

    def mkstemp_then_ctrl_c(*args: Any, **kwargs: Any) -> tuple[int, str]:
        made = real_mkstemp(*args, **kwargs)
        signal.raise_signal(signal.SIGINT)  # lands before mkstemp has returned
        return made

    monkeypatch.setattr(tempfile, "mkstemp", mkstemp_then_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        write_atomic(tmp_path / "scene.json", "{}")
    assert sorted(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("name", "text", "said"),
    [
        ("empty.yaml", "", "an empty document (or null)"),
        ("comment.yaml", "# nothing yet\n", "an empty document (or null)"),
        ("null.json", "null", "an empty document (or null)"),
        ("list.json", "[1, 2]", "an array at top level"),
        ("list.yaml", "- a\n- b\n", "an array at top level"),
        ("text.yaml", "just words\n", "a string at top level"),
        ("number.json", "3.5", "a number at top level"),
        ("true.json", "true", "true at top level"),
    ],
)
def test_a_document_that_is_not_an_object_is_named_in_json_s_words(
    tmp_path: Path, name: str, text: str, said: str
) -> None:
    """An empty YAML file said ``got NoneType``, a list ``got list``: Python's
    words. Now what the document holds, and that an object is expected."""
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError) as refused:
        read_document(path)
    message = str(refused.value)
    assert said in message and "object" in message and "NoneType" not in message, message
