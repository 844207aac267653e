"""The lean ``demoplan solve`` path (demoplan.cli.launcher) against the typer command.

Both must print the same plan, JSON and one-line errors with the same exit
codes; whatever the lean parser does not accept must be left to typer.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import typer.main
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.cli.launcher import SOLVE_OPTIONS, SolveOptions, parse_solve_options, run_solve
from demoplan.planning.xml import save_problem
from tests.planning.test_problem_xml import BOMB
from tests.planning.test_solve_cli import PAPER, two_objects
from tests.support.planning_families import PARKING_FAMILIES, parking_problem


def through_typer(args: list[str]) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, ["solve", *args])
    return result.exit_code, result.stdout, result.stderr


def through_launcher(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    options = parse_solve_options(args)
    assert options is not None, args
    code = run_solve(options)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def comparable(text: str) -> str:
    """Timings differ from run to run; everything else must not."""
    text = re.sub(r'"(read_)?seconds": [0-9.e-]+', '"seconds": T', text)
    return re.sub(r"\d+\.\d\d s\b", "T s", text)


@pytest.fixture(scope="module")
def problems(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("launcher")
    paths = {"paper": PAPER, "missing": folder / "nope.xml"}
    paths["swap"] = folder / "swap.xml"  # no plan: exhausted
    save_problem(two_objects([("a", "l2"), ("b", "l1")]), paths["swap"])
    paths["shared"] = folder / "shared.xml"  # no plan: found statically
    save_problem(two_objects([("a", "l3"), ("b", "l3")], locations=["l3"]), paths["shared"])
    paths["hard"] = folder / "hard.xml"  # not proved in two expansions
    save_problem(parking_problem(20, 0, **PARKING_FAMILIES["parking-crowded"]), paths["hard"])
    paths["bomb"] = folder / "bomb.xml"
    paths["bomb"].write_text(BOMB)
    return paths


@pytest.mark.parametrize(
    ("name", "extra", "code"),
    # No case depends on the clock but the two --timeout 0 ones (the time floor
    # of the fast plan): the others run with no time limit, so both entry
    # points reach the same answer however loaded the machine. (With the
    # default 2 s, "hard --max-nodes 2 --optimal" stopped at the clock here,
    # its plan and bound wherever the time-shared phases had got.)
    [
        ("paper", ["--timeout", "inf"], 0),
        ("paper", ["--json", "--timeout", "inf"], 0),
        ("paper", ["--search", "bfs", "--json", "--timeout", "inf"], 0),
        ("paper", ["--search=bfs", "--timeout=inf"], 0),
        ("hard", ["--max-nodes", "2", "--optimal", "--search", "bfs", "--timeout", "inf"], 4),
        ("hard", ["--max-nodes", "2", "--search", "bfs", "--timeout", "inf"], 4),
        ("paper", ["--timeout", "0"], 0),  # the fast plan comes anyway, unproved
        ("paper", ["--timeout", "0", "--optimal"], 4),
        ("swap", ["--search", "bfs", "--timeout", "inf"], 3),
        ("swap", ["--timeout", "inf"], 3),
        ("shared", ["--json", "--timeout", "inf"], 3),
        ("missing", [], 1),
        ("bomb", [], 1),
    ],
)
def test_same_output_and_exit_code(
    problems: dict[str, Path],
    capsys: pytest.CaptureFixture[str],
    name: str,
    extra: list[str],
    code: int,
) -> None:
    args = [str(problems[name]), *extra]
    expected = through_typer(args)
    assert expected[0] == code, expected
    actual = through_launcher(args, capsys)
    assert tuple(map(comparable, map(str, actual))) == tuple(map(comparable, map(str, expected)))


@pytest.mark.parametrize(
    "args",
    [
        ["--help"],
        [str(PAPER), "-h"],
        [],
        [str(PAPER), "--search", "dfs"],
        [str(PAPER), "--max-nodes", "0"],
        [str(PAPER), "--max-nodes", "many"],
        [str(PAPER), "--timeout", "-1"],
        [str(PAPER), "--timeout", "nan"],
        [str(PAPER), "--unknown"],
        [str(PAPER), "--js"],  # click does not expand abbreviations
        [str(PAPER), str(PAPER)],
    ],
)
def test_everything_else_is_left_to_typer(args: list[str]) -> None:
    assert parse_solve_options(args) is None
    assert through_typer(args)[0] in (0, 2)  # help or a usage error, worded by click


def test_parsed_options() -> None:
    options = parse_solve_options(["--timeout", "1.5", "p.xml", "--max-nodes=7", "--json"])
    assert options == SolveOptions(Path("p.xml"), True, "astar", 7, 1.5)


def test_the_lean_parser_knows_every_option_of_the_command() -> None:
    command = typer.main.get_command(app)
    solve = command.commands["solve"]  # type: ignore[attr-defined]
    typer_options = {name for p in solve.params for name in p.opts if name.startswith("--")}
    assert typer_options == set(SOLVE_OPTIONS)


def test_the_executable_takes_the_lean_path() -> None:
    """``python -m demoplan solve`` with stderr piped: the plan, and typer never imported."""
    probe = (
        # --timeout inf: the proof must not race start-up on a loaded machine
        "import runpy, sys; sys.argv = ['demoplan', 'solve', sys.argv[1], '--timeout', 'inf']\n"
        "try:\n    runpy.run_module('demoplan', run_name='__main__')\n"
        "finally:\n    print('typer' in sys.modules, file=sys.stderr)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe, str(PAPER)],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONWARNINGS": "ignore"},
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert len(done.stdout.splitlines()) == 8
    assert done.stderr.splitlines() == ["demoplan: 8 actions, proved shortest", "False"]
    help_text = subprocess.run(
        [sys.executable, "-m", "demoplan", "solve", "--help"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert help_text.returncode == 0 and "--max-nodes" in help_text.stdout
    assert (
        json.loads(
            subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "demoplan",
                    "solve",
                    str(PAPER),
                    "--json",
                    "--timeout",
                    "inf",
                ],
                capture_output=True,
                text=True,
                check=True,
            ).stdout
        )["length"]
        == 8
    )


def test_the_cli_does_not_import_the_launcher_back() -> None:
    """launcher → cli only (at dispatch): the typer application reaches the
    command clock and the signal state through demoplan.commands and
    demoplan.frontends.interrupts, never through the launcher."""
    code = (
        "import sys, demoplan.cli\n"
        "print('demoplan.cli.launcher' in sys.modules)\n"
        "import demoplan.cli.launcher\n"
        "print(sorted(m for m in sys.modules if m.startswith('demoplan.cli.launcher')))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.splitlines() == ["False", "['demoplan.cli.launcher']"]
