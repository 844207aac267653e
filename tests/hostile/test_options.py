"""Hostile option values and outputs, hand-written (issue 14): every one is
refused in one line naming the option (or the file), with an exit code of
docs/cli.md, quickly, and no file in the working folder changes — a command with
several outputs writes none of them when one fails."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.hostile.harness import check_refused, fingerprint, run
from tests.support.helpers import EXAMPLES

PERCEIVE = ["perceive", "top.png", "--px-per-m", "1000", "--origin", "0.05", "-0.21"]
# (arguments, a name the error line must contain)
CASES: list[tuple[list[str], str]] = (
    [
        (["solve", "problem.xml", "--timeout", value], "--timeout")
        for value in ("-1", "nan", "abc", "")
    ]
    + [
        (["solve", "problem.xml", "--max-nodes", value], "--max-nodes")
        for value in ("-1", "abc", "1e3")
    ]
    + [
        (["solve", "problem.xml", "--search", "dfs"], "--search"),
        (["plan", "model.json", "scene.json", "--plot", "bad.xyz"], "--plot"),
        (["plan", "model.json", "scene.json", "--plot", "folder"], "--plot"),
        (["plan", "model.json", "scene.json", "--freespace", "-1"], "--freespace"),
        (["plan", "model.json", "scene.json", "--freespace", "100000000"], "--freespace"),
        (["problem", "model.json", "scene.json", "--goal", "999", "-o", "p.xml"], "--goal"),
        (["problem", "model.json", "scene.json", "--goal", "-1", "-o", "p.xml"], "--goal"),
        (["problem", "model.json", "scene.json", "-o", "folder"], "folder"),
        (["run", "model.json", "scene.json", "--seed", "-1"], "--seed"),
        (["run", "model.json", "scene.json", "--faults", "garbage"], "--faults"),
        (["run", "model.json", "scene.json", "--faults", "drop=2"], "--faults"),
        (["run", "model.json", "scene.json", "--faults", "drop=nan"], "--faults"),
        (["run", "model.json", "scene.json", "--faults", "teleport=0.1"], "--faults"),
        (["run", "model.json", "scene.json", "--sim", "unreal"], "--sim"),
        (["run", "model.json", "scene.json", "--frames", "others"], "others"),
        ([*PERCEIVE[:2], "--px-per-m", "0.001", "--origin", "0", "0"], "is --px-per-m right?"),
        ([*PERCEIVE[:2], "--px-per-m", "1e7", "--origin", "0", "0"], "is --px-per-m right?"),
        ([*PERCEIVE, "--side", "0.0001"], "--side too strict?"),
        ([*PERCEIVE, "-o", "folder"], "folder"),
        ([*PERCEIVE, "--timeout", "0.0001"], "--timeout"),
        (["learn", "demos.json", "-o", "out.json", "--max-clusters", "-1"], "max"),
        (["learn", "demos.json", "-o", "out.json", "--significance", "2"], "significance"),
        (["learn", "demos.json", "-o", "out.json", "--require", "A<"], "require"),
        (["learn", "demos.json", "-o", "out.json", "--require", "A<A"], "require"),
        (["learn", "demos.json", "-o", "out.json", "--require", "nothing<wood"], "require"),
        (["learn", "demos.json", "-o", "folder"], "folder"),
        (["learn", "demos.json", "-o", "demos.json"], "demos.json"),
        (["learn", "demos.json"], "-o"),
        (["learn", "demos.json", "-o", "out.json", "--timeout", "0.0001"], "--timeout"),
        (["segment", "stream.csv", "-o", "d.json", "--plot", "bad.xyz"], "--plot"),
        (["segment", "stream.csv", "-o", "d.json", "--plot", "folder"], "--plot"),
        (["segment", "stream.csv", "-o", "d.json", "--plot", "/proc/no/such.png"], "such.png"),
        (["segment", "stream.csv", "-o", "/proc/no/d.json", "--plot", "d.png"], "d.json"),
        (["segment", "stream.csv", "-o", "d.json", "--set", "bogus=1"], "bogus"),
        (["segment", "stream.csv", "-o", "d.json", "--set", "start_speed=nan"], "start_speed"),
        (["segment", "stream.csv", "-o", "d.json", "--set", "start_speed=-1"], "start_speed"),
        (["segment", "stream.csv", "-o", "stream.csv"], "stream.csv"),
        (["pddl", "problem.xml", "-o", "problem.xml"], "problem.xml"),
        (["pddl", "problem.pddl", "-o", "."], "problem.pddl"),  # the input named like an output
        (["experiments", "--out", "demos.json"], "demos.json"),
        (["experiments", "--out", "others"], "others"),  # a folder of someone's files
        (["show", "model.json", "--decimals", "-1"], "--decimals"),
        (["perceive", "strip.png", "--px-per-m", "1000", "--origin", "0", "0"], "strip.png"),
        (["run", "model.json", "tiny-scene.json", "--sim", "mujoco"], "objects.wood.size"),
        # a model whose states refer to each other in a cycle: found while planning
        (["plan", "cycle-model.json", "scene.json"], "cycle-model.json"),
        (["run", "cycle-model.json", "scene.json"], "cycle-model.json"),
        (["problem", "cycle-model.json", "scene.json", "-o", "p.xml"], "cycle-model.json"),
        (["nosuchcommand"], "nosuchcommand"),
        (["learn", "--no-such-option", "demos.json"], "--no-such-option"),
    ]
)


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("options")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", folder / "scene.json")
    shutil.copy(EXAMPLES / "planning" / "paper-example.xml", folder / "problem.xml")
    shutil.copy(EXAMPLES / "streams" / "set-table-1.csv", folder / "stream.csv")
    shutil.copy(EXAMPLES / "perception" / "blocks-top.png", folder / "top.png")
    (folder / "folder").mkdir()
    shutil.copy(folder / "problem.xml", folder / "problem.pddl")
    (folder / "others").mkdir()
    (folder / "others" / "thesis.tex").write_text("\\documentclass{article}\n")
    import json

    import numpy as np
    from PIL import Image

    # a 1 × 40,000-pixel strip: under the pixel count, over the side limit
    Image.fromarray(np.zeros((1, 40_000, 3), np.uint8)).save(folder / "strip.png")
    scene = json.loads((folder / "scene.json").read_text())
    scene["objects"]["wood"]["size"] = [0.0001, 0.0001, 0.0001]  # 0.1 mm: in bounds
    (folder / "tiny-scene.json").write_text(json.dumps(scene))
    assert run(["learn", "demos.json", "--paper", "-o", "model.json"], folder).code == 0
    model = json.loads((folder / "model.json").read_text())
    wood = next(s for s in model["states"] if s["object"] == "wood")
    wood["position"]["reference"] = "red"  # and red's is wood
    (folder / "cycle-model.json").write_text(json.dumps(model))
    return folder


@pytest.mark.parametrize(("args", "name"), CASES, ids=[" ".join(a) for a, _ in CASES])
def test_a_hostile_option_is_refused_in_one_line(
    workspace: Path, tmp_path: Path, args: list[str], name: str
) -> None:
    folder = tmp_path / "case"
    shutil.copytree(workspace, folder)
    before = fingerprint(folder)
    answer = run(args, folder)
    check_refused(answer, [name])
    assert fingerprint(folder) == before, f"files changed: {answer}"


HOSTILE_NUMBERS = ("nan", "inf", "-inf", "0", "-1", "1e308")
NUMBER_COMMANDS: dict[str, list[str]] = {
    # a command whose float options the table gives: its arguments but the option
    "run": ["run", "model.json", "scene.json"],
    "perceive": PERCEIVE,
    "export": ["export", "bt", "model.json", "scene.json", "-o", "t.xml"],
    "learn": ["learn", "demos.json", "-o", "out.json"],
    "solve": ["solve", "problem.xml"],
    "plan": ["plan", "model.json", "scene.json"],
}
ACCEPTED = {
    # values of HOSTILE_NUMBERS an option takes (the others are refused)
    "--timeout": {"inf", "0", "1e308"},  # inf: no limit; 0: the least work
    "--origin": {"0", "-1"},
    "--significance": {"0"},  # the paper's plain comparison
}


def _float_options() -> list[tuple[str, str, int]]:
    """(command, option, values it takes) of every float option of every command."""
    import typer.main

    from demoplan.cli.application import app

    def walk(command: object, path: list[str]) -> Iterator[tuple[str, object]]:
        for name, sub in getattr(command, "commands", {}).items():
            yield from walk(sub, [*path, name])
        if not hasattr(command, "commands"):
            yield " ".join(path), command

    return [
        (path, param.opts[0], param.nargs)
        for path, command in walk(typer.main.get_command(app), [])
        for param in command.params  # type: ignore[attr-defined]
        if "float" in str(param.type_descriptor.annotation) and param.opts[0].startswith("--")
    ]


FLOAT_OPTIONS = _float_options()
NUMBER_CASES = [
    (command, option, nargs, value)
    for command, option, nargs in FLOAT_OPTIONS
    for value in HOSTILE_NUMBERS
    if value not in ACCEPTED.get(option, set())
]


def test_the_number_table_has_every_float_option() -> None:
    assert {command for command, _, _ in FLOAT_OPTIONS} <= set(NUMBER_COMMANDS)
    assert len(FLOAT_OPTIONS) >= 14  # the walk found them


@pytest.mark.parametrize(
    ("command", "option", "nargs", "value"),
    NUMBER_CASES,
    ids=[f"{c} {o} {v}" for c, o, _, v in NUMBER_CASES],
)
def test_a_number_an_option_does_not_take_says_what_was_given_and_what_is_expected(
    workspace: Path, tmp_path: Path, command: str, option: str, nargs: int, value: str
) -> None:
    """``--px-per-m nan`` answered "Input should be less than or equal to
    10000000": NaN, an infinity, zero, a negative or a huge number is named
    as given, with what the option takes."""
    folder = tmp_path / "case"
    shutil.copytree(workspace, folder)
    before = fingerprint(folder)
    args = [*NUMBER_COMMANDS[command], option, value, *["0"] * (nargs - 1)]
    answer = run(args, folder)
    check_refused(answer, [option, option.lstrip("-").replace("-", "_")], codes={1, 2})
    line = answer.stderr
    assert value in line or f"{float(value):g}" in line, f"{value} not named: {line}"
    assert "expected" in line, line
    assert "Input should be" not in line, line
    assert fingerprint(folder) == before, f"files changed: {answer}"
