"""The README's tour runs as written (a new user's first commands)."""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMAND = re.compile(r"^\$ (demoplan .*?)(?:\s+#.*)?$")


def tour_commands() -> list[str]:
    return [
        m.group(1)
        for line in (ROOT / "README.md").read_text().splitlines()
        if (m := COMMAND.match(line))
    ]


def test_the_tour_has_commands() -> None:
    assert len(tour_commands()) >= 12


def test_tour_commands_run(tmp_path: Path) -> None:
    """Every `$ demoplan …` line of the README, in order (later ones use what earlier
    ones wrote), in one working folder holding the examples, exits 0."""
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    has_mujoco = importlib.util.find_spec("mujoco") is not None
    ran = 0
    for command in tour_commands():
        if "mujoco" in command and not has_mujoco:
            continue
        done = subprocess.run(
            [sys.executable, "-m", "demoplan", *shlex.split(command)[1:]],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")},
            timeout=300,
            check=False,
        )
        assert done.returncode == 0, (command, done.stderr[-2000:])
        ran += 1
    assert ran >= 12
