"""The command line (docs/cli.md): learn / show, exit codes, one-line errors, outputs."""

from __future__ import annotations

import json
import math
import os
import subprocess
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.learning.modelfile import load_model, model_to_dict
from tests.support import forkserver
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES, demo, raw, write
from tests.support.learning_families import PAPER_TABLE_II, PAPER_TABLE_III

SET_TABLE = EXAMPLES / "set_table"


def assert_one_line_error(result: Any, *fragments: str) -> str:
    """Exit 1, exactly one line on stderr naming every fragment, no traceback."""
    assert result.exit_code == 1, (result.exit_code, result.stdout, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    line: str = lines[0]
    assert line.startswith("demoplan: error: ")
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in line, (fragment, line)
    return line


@pytest.fixture(scope="module")
def model_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Experiment 1 learned with the paper's reading (the examples were drawn for it)."""
    path = tmp_path_factory.mktemp("model") / "set_table.json"
    result = invoke("learn", SET_TABLE, "-o", path, "--paper")
    assert result.exit_code == 0, result.stderr
    return path


# --- bad input: exit 1, one line naming file, field and expectation --------------------

BAD_INPUTS: list[tuple[str, Any, list[str]]] = [
    (
        "malformed JSON",
        '{"format": "demoplan/demonstration-1", "steps": [',
        ["malformed JSON at line 1"],
    ),
    ("missing position", demo([{"object": "plate"}]), ["steps[0].position", "required"]),
    (
        "NaN",
        raw('{"object": "a", "position": [NaN, 0]}'),
        ["steps[0].position[0]", "NaN", "finite number expected"],
    ),
    (
        "Infinity",
        raw('{"object": "a", "position": [0, Infinity]}'),
        ["steps[0].position[1]", "Infinity", "finite number expected"],
    ),
    (
        "-Infinity",
        raw('{"object": "a", "position": [0, 0], "yaw": -Infinity}'),
        ["steps[0].yaw", "-Infinity", "finite number expected"],
    ),
    (
        "unknown kind",
        demo(format="demoplan/recipe-1"),
        ["format", "unknown format 'demoplan/recipe-1'", "expected 'demoplan/demonstration-1'"],
    ),
    ("newer version", demo(format="demoplan/demonstration-2"), ["format", "version 2", "newer"]),
    ("empty demonstration", demo([]), ["steps", "at least one step expected"]),
    (
        "zero quaternion",
        demo([{"object": "a", "position": [0, 0], "quat": [0, 0, 0, 0]}]),
        ["steps[0]", "a unit quaternion expected"],
    ),
    (
        "wrong-length position",
        demo([{"object": "a", "position": [0, 0, 0, 0]}]),
        ["steps[0].position", "at most 3"],
    ),
    (
        "two orientations",
        demo([{"object": "a", "position": [0, 0], "yaw": 90, "rpy": [0, 0, 90]}]),
        ["steps[0]", "give one orientation"],
    ),
    (
        "step object not in objects",
        demo([{"object": "cup", "position": [0, 0]}], objects={"plate": {"size": [0.1, 0.1, 0.1]}}),
        ["steps[0].object", "unknown object 'cup'", "expected one of ['plate']"],
    ),
]


@pytest.mark.parametrize(
    ("text", "fragments"), [b[1:] for b in BAD_INPUTS], ids=[b[0] for b in BAD_INPUTS]
)
@pytest.mark.parametrize("json_flag", [False, True], ids=["text", "json"])
def test_bad_demonstration_exits_1_with_one_line(
    tmp_path: Path, text: Any, fragments: list[str], json_flag: bool
) -> None:
    bad = write(tmp_path / "bad.json", text)
    out = tmp_path / "model.json"
    result = invoke("learn", bad, "-o", out, *(["--json"] if json_flag else []))
    assert_one_line_error(result, str(bad), *fragments)
    assert result.stdout == ""
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json"]  # no temp file either


def test_inconsistent_geometry_across_two_files(tmp_path: Path) -> None:
    one = write(
        tmp_path / "one.json",
        demo(objects={"plate": {"shape": "cylinder", "size": [0.26, 0.26, 0.02]}}),
    )
    two = write(
        tmp_path / "two.json",
        demo(objects={"plate": {"shape": "cylinder", "size": [0.3, 0.3, 0.02]}}),
    )
    result = invoke("learn", one, two, "-o", tmp_path / "m.json", "--json")
    assert_one_line_error(
        result, str(two), "objects.plate", str(one), "one geometry per object expected"
    )
    assert result.stdout == ""


def test_missing_file_and_empty_folder(tmp_path: Path) -> None:
    result = invoke("learn", tmp_path / "nope.json", "-o", tmp_path / "m.json", "--json")
    assert_one_line_error(result, "nope.json", "no such file")
    assert result.stdout == ""
    (tmp_path / "empty").mkdir()
    result = invoke("learn", tmp_path / "empty", "-o", tmp_path / "m.json", "--json")
    assert_one_line_error(result, str(tmp_path / "empty"), "no .json or .yaml demonstration files")
    assert result.stdout == ""
    assert not (tmp_path / "m.json").exists()


def test_output_onto_a_folder_is_bad_input(tmp_path: Path) -> None:
    (tmp_path / "out").mkdir()
    result = invoke("learn", SET_TABLE / "demonstration-1.json", "-o", tmp_path / "out", "--json")
    assert result.exit_code == 1
    assert "is a folder" in result.stderr
    assert result.stdout == ""
    assert list((tmp_path / "out").iterdir()) == []


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["learn"], "Missing argument"),
        (["learn", str(SET_TABLE)], "-o"),
        (["learn", str(SET_TABLE), "-o", "m.json", "--no-such-option"], "No such option"),
        (["show"], "Missing argument"),
        (["frobnicate"], "No such command"),
    ],
)
def test_usage_errors_exit_2(
    tmp_path: Path, args: list[str], message: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    result = invoke(*args)
    assert result.exit_code == 2, (result.stdout, result.stderr)
    assert message in result.stderr
    assert result.stdout == ""
    assert list(tmp_path.iterdir()) == []


# --- the same through a real process -----------------------------------------------------


def run(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``demoplan ARGS`` in a process of its own, forked from the tests' fork
    server (tests/support/forkserver.py): its own exit code and streams."""
    done = forkserver.run([os.fsencode(a) for a in args], cwd, forkserver.command_env(), timeout=60)
    return subprocess.CompletedProcess(
        done.args, done.returncode, done.stdout.decode(), done.stderr.decode()
    )


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        (
            raw('{"object": "a", "position": [NaN, 0]}'),
            ["steps[0].position[0]", "NaN"],
        ),
        (demo([{"object": "plate"}]), ["steps[0].position", "required"]),
        (
            raw('{"object": "a", "position": [' + "9" * 5000 + ", 0]}"),
            ["malformed JSON"],
        ),
    ],
    ids=["nan", "missing-position", "huge-integer"],
)
def test_process_prints_one_line_and_no_traceback(
    tmp_path: Path, text: Any, fragments: list[str]
) -> None:
    bad = write(tmp_path / "bad.json", text)
    done = run("learn", "bad.json", "-o", "model.json", "--json", cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stdout == ""
    assert "Traceback" not in done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith("demoplan: error: bad.json: ")
    for fragment in fragments:
        assert fragment in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == [bad.name]


def test_process_usage_error_and_model_error(tmp_path: Path) -> None:
    done = run("learn", cwd=tmp_path)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    model = write(tmp_path / "model.json", {"format": "demoplan/model-2"})
    done = run("show", model.name, "--json", cwd=tmp_path)
    assert done.returncode == 1
    assert done.stdout == ""
    assert done.stderr.splitlines() == [
        "demoplan: error: model.json: format: 'demoplan/model-2' is version 2, newer than this "
        "demoplan reads (up to 1); upgrade demoplan"
    ]


# --- outputs are never half-written ------------------------------------------------------


def test_failed_learn_leaves_the_existing_model_unchanged(tmp_path: Path) -> None:
    good = write(tmp_path / "good.json", demo())
    bad = write(tmp_path / "bad.json", demo([{"object": "plate", "position": [0, float("nan")]}]))
    model = tmp_path / "model.json"
    model.write_text("precious\n")
    result = invoke("learn", good, bad, "-o", model)
    assert_one_line_error(result, "bad.json", "steps[0].position[1]")
    assert model.read_text() == "precious\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json", "good.json", "model.json"]


def test_failed_update_leaves_the_model_unchanged(tmp_path: Path, model_file: Path) -> None:
    model = tmp_path / "model.json"
    model.write_bytes(model_file.read_bytes())
    bad = write(tmp_path / "bad.json", demo([]))
    result = invoke("learn", "--update", model, bad)
    assert_one_line_error(result, "bad.json", "steps")
    assert model.read_bytes() == model_file.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json", "model.json"]


def test_learn_writes_atomically_and_replaces(tmp_path: Path) -> None:
    model = tmp_path / "model.json"
    model.write_text("old\n")
    result = invoke("learn", SET_TABLE, "-o", model)
    assert result.exit_code == 0, result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.json"]  # no temp files left
    data = json.loads(model.read_text())
    assert data["format"] == "demoplan/model-1"
    assert "Learned from 3 demonstrations" in result.stdout


# --- learn and show ------------------------------------------------------------------------


def test_learn_writes_the_spec_model(model_file: Path) -> None:
    data = json.loads(model_file.read_text())
    assert data["format"] == "demoplan/model-1"
    assert [s["id"] for s in data["states"]] == list("ABCDEFGHIJ")
    for state in data["states"]:
        assert set(state) >= {"id", "object", "position", "orientation"}
        assert set(state["position"]) >= {"reference", "value"}
        assert set(state["orientation"]) >= {"reference", "value"}
    assert data["states"][0]["object"] == "plate"
    assert data["states"][0]["position"]["reference"] is None
    assert data["sequences"] == [
        ["A", "B", "C", "D", "E", "F", "G"],
        ["A", "E", "H", "I", "J", "F", "G"],
        ["A", "C", "B", "F", "E", "D", "G"],
    ]
    assert len(data["constraints"]) == 32
    assert ["A", "B"] in data["constraints"]
    assert ["B", "C"] not in data["constraints"]  # seen both ways
    assert data["goals"][0] == ["A", "B", "C", "D", "E", "F", "G"]


def test_learn_json_prints_only_json(tmp_path: Path) -> None:
    result = invoke("learn", SET_TABLE, "-o", tmp_path / "m.json", "--json", "--paper")
    assert result.exit_code == 0
    data = json.loads(result.stdout)
    assert data["format"] == "demoplan/model-1"
    assert len(data["constraints"]) == 32


def test_show_json_is_valid_json_only(model_file: Path) -> None:
    result = invoke("show", model_file, "--json")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)  # nothing but JSON on stdout
    assert {"states", "sequences", "constraints", "goals"} <= set(data)
    saved = json.loads(model_file.read_text())
    for key in ("states", "sequences", "constraints", "goals"):
        assert data[key] == saved[key]


def test_show_prints_tables(model_file: Path) -> None:
    result = invoke("show", model_file)
    assert result.exit_code == 0, result.stderr
    assert "Constraints (32)" in result.stdout
    assert "States" in result.stdout
    assert "A-E-H-I-J-F-G" in result.stdout
    for obj in ("plate", "knife", "fork", "spoon", "glass", "food", "napkin"):
        assert f"│ {obj} " in result.stdout  # as the demonstrations name it


BAD_MODELS = [
    (
        "unknown state in a constraint",
        lambda d: d["constraints"].append(["A", "ZZ"]),
        ["constraints[32]", "'ZZ' is not a state"],
    ),
    (
        "wrong format",
        lambda d: d.update(format="demoplan/demonstration-1"),
        ["format", "expected 'demoplan/model-1'"],
    ),
    (
        "newer version",
        lambda d: d.update(format="demoplan/model-2"),
        ["format", "version 2", "newer"],
    ),
    (
        "violation without pair",
        lambda d: d.update(violations=[{"demonstration": 0}]),
        ["violations[0].required"],
    ),
    (
        "two-number orientation",
        lambda d: d["states"][0].update(orientation={"reference": None, "value": [1, 2]}),
        ["states[0].orientation.value"],
    ),
]


@pytest.mark.parametrize(
    ("edit", "fragments"), [b[1:] for b in BAD_MODELS], ids=[b[0] for b in BAD_MODELS]
)
@pytest.mark.parametrize("command", ["show", "show-json", "update"])
def test_bad_model_file_exits_1(
    tmp_path: Path, model_file: Path, edit: Any, fragments: list[str], command: str
) -> None:
    data = json.loads(model_file.read_text())
    edit(data)
    bad = write(tmp_path / "model.json", data)
    before = bad.read_bytes()
    if command == "update":
        result = invoke("learn", "--update", bad, SET_TABLE / "demonstration-3.json", "--json")
    else:
        result = invoke("show", bad, *(["--json"] if command == "show-json" else []))
    assert_one_line_error(result, str(bad), *fragments)
    assert result.stdout == ""
    assert bad.read_bytes() == before


def test_show_of_a_demonstration_or_garbage(tmp_path: Path) -> None:
    result = invoke("show", SET_TABLE / "demonstration-1.json")
    assert_one_line_error(result, "demonstration-1.json", "format", "expected 'demoplan/model-1'")
    result = invoke("show", write(tmp_path / "m.json", "{"), "--json")
    assert_one_line_error(result, "m.json", "malformed JSON")
    assert result.stdout == ""


# --- learn --update ------------------------------------------------------------------------


def test_update_equals_learning_all_at_once(tmp_path: Path, model_file: Path) -> None:
    partial = tmp_path / "partial.json"
    first = invoke(
        "learn",
        SET_TABLE / "demonstration-1.json",
        SET_TABLE / "demonstration-2.json",
        "-o",
        partial,
        "--paper",
    )
    assert first.exit_code == 0, first.stderr
    assert len(load_model(partial).sequences) == 2
    updated = invoke("learn", "--update", partial, SET_TABLE / "demonstration-3.json")
    assert updated.exit_code == 0, updated.stderr
    assert "Constraints (32)" in updated.stdout
    incremental = model_to_dict(load_model(partial))
    at_once = model_to_dict(load_model(model_file))
    for key in ("states", "sequences", "constraints", "goals", "settings", "demonstrations"):
        assert incremental[key] == at_once[key], key


def test_update_to_another_output_keeps_the_input(tmp_path: Path) -> None:
    partial = tmp_path / "partial.json"
    assert invoke("learn", SET_TABLE / "demonstration-1.json", "-o", partial).exit_code == 0
    before = partial.read_bytes()
    result = invoke(
        "learn",
        "--update",
        partial,
        SET_TABLE / "demonstration-2.json",
        "-o",
        tmp_path / "two.json",
    )
    assert result.exit_code == 0, result.stderr
    assert partial.read_bytes() == before
    assert len(load_model(tmp_path / "two.json").demonstrations) == 2


# --- teacher constraints -------------------------------------------------------------------


def test_require_state_ids(tmp_path: Path) -> None:
    out = tmp_path / "m.json"
    result = invoke("learn", SET_TABLE, "-o", out, "--require", "B<A", "--paper")
    assert result.exit_code == 0, result.stderr
    model = load_model(out)
    assert ("B", "A") in model.teacher_constraints
    assert ("B", "A") in model.constraints
    assert ("A", "B") not in model.constraints  # the teacher wins over the demonstrations
    # Demonstrations 1 and 3 put the plate (A) before the knife (B).
    assert {(d, x, y) for d, x, y in model.violations} == {(0, "B", "A"), (2, "B", "A")}
    assert "Demonstration 1 contradicts the teacher's B<A" in result.stdout
    assert "Demonstration 3 contradicts the teacher's B<A" in result.stdout
    saved = json.loads(out.read_text())
    assert {"demonstration": 0, "required": ["B", "A"]} in saved["violations"]


def test_require_holding_constraint_has_no_violation(tmp_path: Path) -> None:
    out = tmp_path / "m.json"
    result = invoke("learn", SET_TABLE, "-o", out, "--require", "plate<napkin", "--json")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["teacher_constraints"] == [["A", "G"]]  # plate is A, napkin G
    assert ["A", "G"] in data["constraints"]
    assert data["violations"] == []


def test_require_object_names_contradicted(tmp_path: Path) -> None:
    """napkin<plate against every demonstration (plate first, napkin last): with the
    learned orders in between it closes a cycle within each goal — exit 1 naming
    the cycle, no model written (docs/learning.md, Teacher constraints)."""
    out = tmp_path / "m.json"
    result = invoke("learn", SET_TABLE, "--paper", "-o", out, "--require", "napkin<plate")
    assert_one_line_error(result, "require", "close a precedence cycle A <")
    assert "G < A" in result.stderr and "demonstration 1 (set-table-1)" in result.stderr
    assert not out.exists()


def test_require_object_names_contradicted_without_a_cycle(tmp_path: Path) -> None:
    out = tmp_path / "m.json"
    blocks = EXAMPLES / "blocks" / "demonstrations.json"
    result = invoke("learn", blocks, "--paper", "-o", out, "--require", "wood<green")
    assert result.exit_code == 0, result.stderr
    model = load_model(out)
    assert model.teacher_constraints == (("A", "B"), ("A", "D"))
    assert [(d, x, y) for d, x, y in model.violations] == [(1, "A", "D")]
    assert "Demonstration 2 contradicts the teacher's A<D" in result.stdout


@pytest.mark.parametrize(
    ("requirement", "fragment"),
    [
        ("nonsense", "expected a requirement like 'A<B'"),
        ("plate<teapot", "'teapot' is neither"),
        ("A<A", "before itself"),
    ],
)
def test_bad_require_exits_1(tmp_path: Path, requirement: str, fragment: str) -> None:
    out = tmp_path / "m.json"
    result = invoke("learn", SET_TABLE, "-o", out, "--require", requirement, "--json")
    assert_one_line_error(result, "require", fragment)
    assert result.stdout == ""
    assert not out.exists()


def test_update_keeps_the_teacher_constraints(tmp_path: Path) -> None:
    partial = tmp_path / "partial.json"
    args = ["learn", SET_TABLE / "demonstration-1.json", SET_TABLE / "demonstration-2.json"]
    assert invoke(*args, "-o", partial, "--require", "plate<napkin").exit_code == 0
    assert invoke("learn", "--update", partial, SET_TABLE / "demonstration-3.json").exit_code == 0
    assert load_model(partial).teacher_constraints == (("A", "G"),)


# --- learn --paper, --significance and the precision ------------------------------------


def _states(data: dict[str, Any]) -> list[tuple[str, str, str | None]]:
    return [(s["id"], s["object"], s["position"]["reference"]) for s in data["states"]]


def test_learn_paper_gives_table_ii(tmp_path: Path) -> None:
    """The shipped Experiment 1 was drawn for the paper's reading: Table II's 10 states."""
    result = invoke("learn", SET_TABLE, "-o", tmp_path / "m.json", "--paper", "--json")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert _states(data) == [(i, o, r) for i, o, r, _ in PAPER_TABLE_II]
    for state, (_, _, _, xy) in zip(data["states"], PAPER_TABLE_II, strict=True):
        assert [round(v, 2) for v in state["position"]["value"][:2]] == list(xy)
    assert ["".join(s) for s in data["sequences"]] == PAPER_TABLE_III
    assert len(data["constraints"]) == 32
    assert data["settings"]["position_noise"] == 0.003
    assert data["settings"]["orientation_noise"] == 0.5
    assert data["settings"]["significance"] == 0.0
    assert data["precision"] == {"position": 0.003, "orientation": 0.5, "estimated": False}


def test_learn_defaults_give_one_state_per_object_on_set_table(tmp_path: Path) -> None:
    """At the defaults (precision estimated from three demonstrations, F test) the
    set-table data support no second state of any object: every object once,
    absolute, except the napkin, which lies on the plate in every demonstration."""
    result = invoke("learn", SET_TABLE, "-o", tmp_path / "m.json", "--json")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert _states(data) == [
        ("A", "plate", None),
        ("B", "knife", None),
        ("C", "fork", None),
        ("D", "spoon", None),
        ("E", "glass", None),
        ("F", "food", None),
        ("G", "napkin", "plate"),
    ]
    napkin = data["states"][6]["position"]["value"]
    assert [round(v, 2) for v in napkin[:2]] == [-0.01, -0.02]
    assert data["sequences"] == [list("ABCDEFG"), list("AEDBCFG"), list("ACBFEDG")]
    assert data["settings"]["position_noise"] is None
    assert data["settings"]["significance"] == 0.05
    precision = data["precision"]
    assert set(precision) == {"position", "orientation", "estimated"}
    assert precision["estimated"] is True
    assert 0.003 < precision["position"] < 0.03  # hand-drawn deviations: about a centimetre


def test_paper_is_its_four_settings(tmp_path: Path) -> None:
    """--paper is --significance 0 --position-noise 0.003 --orientation-noise 0.5
    --orientation-ties world."""
    paper = invoke("learn", SET_TABLE, "-o", tmp_path / "paper.json", "--paper", "--json")
    spelled = invoke(
        "learn",
        SET_TABLE,
        "-o",
        tmp_path / "spelled.json",
        "--significance",
        "0",
        "--position-noise",
        "0.003",
        "--orientation-noise",
        "0.5",
        "--orientation-ties",
        "world",
        "--json",
    )
    assert paper.exit_code == 0 and spelled.exit_code == 0, (paper.stderr, spelled.stderr)
    assert json.loads(paper.stdout) == json.loads(spelled.stdout)
    assert (tmp_path / "paper.json").read_bytes() == (tmp_path / "spelled.json").read_bytes()


def test_paper_with_another_option_keeps_that_option(tmp_path: Path) -> None:
    """Other options still apply over --paper."""
    result = invoke(
        "learn", SET_TABLE, "-o", tmp_path / "m.json", "--paper", "--position-noise", "0.002"
    )
    assert result.exit_code == 0, result.stderr
    model = load_model(tmp_path / "m.json")
    assert model.settings.position_noise == 0.002
    assert model.settings.significance == 0.0
    assert model.precision == (0.002, 0.5)


@pytest.mark.parametrize("paper", [False, True], ids=["estimated", "paper"])
def test_model_precision_is_written_and_read_back(tmp_path: Path, paper: bool) -> None:
    out = tmp_path / "m.json"
    result = invoke("learn", SET_TABLE, "-o", out, *(["--paper"] if paper else []))
    assert result.exit_code == 0, result.stderr
    written = json.loads(out.read_text())["precision"]
    assert set(written) == {"position", "orientation", "estimated"}
    assert written["estimated"] is not paper
    model = load_model(out)
    assert model.precision == (written["position"], written["orientation"])
    assert model.precision_estimated is written["estimated"]
    assert model_to_dict(model)["precision"] == written
    shown = invoke("show", out, "--json")
    assert shown.exit_code == 0, shown.stderr
    assert json.loads(shown.stdout)["precision"] == written


@pytest.mark.parametrize("level", ["1", "1.5", "-0.1"])
def test_significance_out_of_range_is_a_usage_error(tmp_path: Path, level: str) -> None:
    out = tmp_path / "m.json"
    result = invoke("learn", SET_TABLE, "-o", out, "--significance", level, "--json")
    assert result.exit_code == 2, (result.exit_code, result.stdout, result.stderr)
    assert "--significance" in result.stderr
    assert "Traceback" not in result.stderr
    assert result.stdout == ""
    assert not out.exists()


# --- YAML ----------------------------------------------------------------------------------


def test_yaml_demonstrations_are_accepted(tmp_path: Path) -> None:
    import yaml

    folder = tmp_path / "demos"
    folder.mkdir()
    for source in sorted(SET_TABLE.glob("*.json")):
        data = json.loads(source.read_text())
        (folder / f"{source.stem}.yaml").write_text(yaml.safe_dump(data), encoding="utf-8")
    result = invoke("learn", folder, "-o", tmp_path / "m.json", "--json")
    assert result.exit_code == 0, result.stderr
    from_yaml = json.loads(result.stdout)
    from_json = json.loads(invoke("learn", SET_TABLE, "-o", tmp_path / "j.json", "--json").stdout)
    for key in ("states", "sequences", "constraints", "goals"):
        assert from_yaml[key] == from_json[key]


def test_bad_yaml_exits_1(tmp_path: Path) -> None:
    bad = write(tmp_path / "bad.yaml", "format: demoplan/demonstration-1\nsteps: [\n")
    result = invoke("learn", bad, "-o", tmp_path / "m.json", "--json")
    assert_one_line_error(result, "bad.yaml", "malformed YAML")
    assert result.stdout == ""


def test_show_prints_the_column_units(tmp_path: Path) -> None:
    """Headers such as "Position [m]" are text, not rich markup."""
    model = EXAMPLES / "blocks" / "demonstrations.json"
    result = invoke("learn", model, "-o", tmp_path / "model.json")
    assert result.exit_code == 0
    assert "Position [m]" in result.stdout and "Orientation [deg]" in result.stdout


def test_learn_json_in_a_real_process_prints_only_json(tmp_path: Path) -> None:
    out = run(
        "learn",
        EXAMPLES / "set_table",
        "-o",
        tmp_path / "m.json",
        "--json",
        "--paper",
        cwd=tmp_path,
    )
    assert out.returncode == 0
    assert out.stderr == ""
    model = json.loads(out.stdout)
    assert len(model["constraints"]) == 32
    # The JSON is the model itself: it loads back.
    (tmp_path / "again.json").write_text(out.stdout)
    assert invoke("show", tmp_path / "again.json").exit_code == 0


def test_noise_of_zero_is_bad_input_and_negative_a_usage_error(tmp_path: Path) -> None:
    demo_file = EXAMPLES / "blocks" / "demonstrations.json"
    zero = invoke("learn", demo_file, "-o", tmp_path / "m.json", "--position-noise", "0")
    assert_one_line_error(zero, "position_noise", "positive")
    negative = invoke("learn", demo_file, "-o", tmp_path / "m.json", "--position-noise", "-1")
    assert negative.exit_code == 2
    assert not (tmp_path / "m.json").exists()


def test_the_model_may_not_overwrite_an_input(tmp_path: Path) -> None:
    demo_file = write(tmp_path / "demo.json", demo())
    original = demo_file.read_text()
    assert_one_line_error(invoke("learn", demo_file, "-o", demo_file), "demo.json", "input")
    assert demo_file.read_text() == original
    assert_one_line_error(
        invoke("learn", tmp_path, "-o", tmp_path / "model.json"), "model.json", "folder"
    )


def test_yaml_aliases_and_huge_coordinates_are_refused(tmp_path: Path) -> None:
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text(
        "format: demoplan/demonstration-1\na: &a [x, x]\nb: &b [*a, *a]\n"
        "steps: [{object: p, position: [0, 0]}]\n"
    )
    assert_one_line_error(invoke("learn", bomb, "-o", tmp_path / "m.json"), "bomb.yaml", "alias")
    huge = write(tmp_path / "huge.json", demo([{"object": "p", "position": [1e300, 0]}]))
    assert_one_line_error(
        invoke("learn", huge, "-o", tmp_path / "m.json"), "huge.json", "steps[0].position[0]"
    )


def test_learn_json_without_output_prints_the_model_and_writes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`learn --json` alone is a dry run: the model on stdout, no file; without
    --json a model file (-o or --update) is still required (usage error 2)."""
    monkeypatch.chdir(tmp_path)
    result = invoke("learn", SET_TABLE, "--paper", "--json")
    assert result.exit_code == 0, result.stderr
    assert len(json.loads(result.stdout)["states"]) == 10
    assert list(tmp_path.iterdir()) == []
    missing = invoke("learn", SET_TABLE)
    assert missing.exit_code == 2 and "-o" in missing.stderr


def test_warnings_follow_a_success_and_give_way_to_an_error(tmp_path: Path) -> None:
    """A stream whose object is still moving at its end: segmentation warns.
    With a step found the warning is printed after the result; with none the
    command fails with its one line and the warning is dropped."""

    def lifted(progress: float) -> str:  # x along a move of 30 cm, lifted 5 cm midway
        return f"{0.3 * progress:.4f},0,{0.05 * math.sin(math.pi * progress):.4f}"

    rows = ["t,object,x,y,z"]
    rows += [f"{t / 20:.2f},cup,{lifted(min(1.0, max(0.0, (t - 10) / 20)))}" for t in range(80)]
    rows += [f"{4 + t / 20:.2f},cup,{0.3 + 0.05 * t / 20:.4f},0,0.03" for t in range(1, 20)]
    moving = tmp_path / "moving.csv"
    moving.write_text("\n".join(rows) + "\n")
    result = CliRunner().invoke(app, ["segment", str(moving), "-o", str(tmp_path / "d.json")])
    assert result.exit_code == 0, result.stderr
    lines = result.stderr.splitlines()
    assert lines[-1].startswith("demoplan: WARNING: cup: still moving at the end")
    still = tmp_path / "still.csv"
    still.write_text("\n".join([rows[0], *rows[60:]]) + "\n")  # at rest, then the unfinished move
    result = CliRunner().invoke(app, ["segment", str(still), "-o", str(tmp_path / "e.json")])
    assert result.exit_code == 1
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("demoplan: error: ")
