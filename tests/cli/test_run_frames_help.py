"""``run --frames``'s help says what each simulator's frames show (docs/execution.md)."""

from __future__ import annotations

import re

from typer.testing import CliRunner

from demoplan.cli import app


def frames_help() -> str:
    """The ``--frames`` line of ``demoplan run --help``, its wrapping undone."""
    result = CliRunner().invoke(app, ["run", "--help"], env={"COLUMNS": "400", "NO_COLOR": "1"})
    assert result.exit_code == 0, result.output
    lines = [re.sub(r"[│╭╮╰╯─]", " ", line).strip() for line in result.output.splitlines()]
    start = next(k for k, line in enumerate(lines) if line.startswith("--frames"))
    block = [lines[start]]
    for line in lines[start + 1 :]:
        if line.startswith("-"):
            break
        block.append(line)
    return " ".join(" ".join(block).split())


def test_frames_help_names_what_each_simulator_draws() -> None:
    """The arm's and MuJoCo's frames are perspective renders, not top views."""
    text = frames_help()
    assert "top-view" not in text
    assert "kinematic draws the table from above" in text
    assert "mujoco and arm render the simulator's 3-D view" in text
    assert "robosuite:ENV" in text
