"""A newcomer's own task on the arm: a plate into a tray that stands
elsewhere, turned, each time, and a mug onto the plate. Refusals before the
arm moves must read right for a task whose things have names of their own:
a task with a ``mug`` reads "the cup reaches" as the mug's reach."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from demoplan.cli import app

pytestmark = pytest.mark.skipif(
    any(importlib.util.find_spec(name) is None for name in ("mujoco", "mink")),
    reason="the arm needs MuJoCo and mink (the sim extra)",
)  # looked up, not imported: MuJoCo imported here, at collection, fixes its GL too early

OBJECTS = {
    "plate": {"shape": "cylinder", "size": [0.16, 0.16, 0.015], "mass": 0.1},
    "mug": {"shape": "cylinder", "size": [0.08, 0.08, 0.1], "mass": 0.12},
}
TRAY = {"shape": "box", "size": [0.36, 0.26, 0.015]}
IN_TRAY = (-0.08, 0.03)


def on_tray(x: float, y: float, yaw: float) -> list[float]:
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    u, v = IN_TRAY
    return [round(x + c * u - s * v, 4), round(y + s * u + c * v, 4)]


def demonstration(k: int, tray: tuple[float, float, float]) -> dict[str, Any]:
    x, y = on_tray(*tray)
    return {
        "format": "demoplan/demonstration-1",
        "name": f"tea-{k}",
        "objects": OBJECTS,
        "landmarks": {"tray": {"position": [tray[0], tray[1], 0.0], "yaw": tray[2], **TRAY}},
        "initial": {"plate": {"position": [0.12, 0.12]}, "mug": {"position": [0.30, 0.12]}},
        "steps": [
            {"object": "plate", "position": [x, y, 0.015]},
            {"object": "mug", "position": [x, y, 0.03]},
        ],
    }


def test_a_tray_out_of_reach_names_the_suction_cup_not_the_mug(tmp_path: Path) -> None:
    files = []
    for k, tray in enumerate([(0.55, 0.42, 0.0), (0.45, 0.45, 40.0), (0.60, 0.40, -25.0)]):
        files.append(tmp_path / f"tea-{k}.json")
        files[-1].write_text(json.dumps(demonstration(k, tray)))
    model = tmp_path / "model.json"
    runner = CliRunner()
    learned = runner.invoke(app, ["learn", *map(str, files), "-o", str(model)])
    assert learned.exit_code == 0, learned.output
    scene = tmp_path / "far.json"
    scene.write_text(
        json.dumps(
            {
                "format": "demoplan/scene-1",
                "objects": {
                    "plate": {"position": [0.12, 0.12, 0.0], **OBJECTS["plate"]},
                    "mug": {"position": [0.30, 0.12, 0.0], **OBJECTS["mug"]},
                },
                "landmarks": {"tray": {"position": [1.6, 0.45, 0.0], "yaw": 120, **TRAY}},
            }
        )
    )
    result = runner.invoke(app, ["run", str(model), str(scene), "--sim", "arm"])
    assert result.exit_code == 1, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, lines
    # the one thing to change: the tray 1.3 m from where the plate and mug start
    assert "standing at (0.120, 0.120) and " in lines[0] and " put down at (1.6" in lines[0]
    assert " m apart; the suction cup reaches" in lines[0]
    assert "the cup reaches" not in lines[0]
    assert "the suction cup reaches 0.22–0.60 m" in lines[0]
