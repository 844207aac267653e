"""A landmark with a size is a body in the physics: a block put on a board
(a landmark turned differently in every demonstration) stands on it in
MuJoCo, with the floating gripper and with the arm — where without the board
it would fall to the table, 2 cm below its target."""

from __future__ import annotations

import importlib.util
import math
from typing import Any

import pytest

from demoplan.documents.demonstrations import demonstrations_from_document
from demoplan.execution.faults import Faults
from demoplan.execution.runner import run_task
from demoplan.learning import learn
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import scene_from_document
from tests.support.helpers import UNTIMED

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("mujoco") is None, reason="MuJoCo not installed"
)
BOARD = [0.24, 0.16, 0.02]
ON_BOARD = (0.05, 0.03)  # the block's place in the board's frame


def _demonstration(index: int, x: float, y: float, yaw: float) -> dict[str, Any]:
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    dx, dy = ON_BOARD
    return {
        "format": "demoplan/demonstration-1",
        "name": f"board-{index}",
        "objects": {"red": {"shape": "box", "size": [0.04, 0.04, 0.04]}},
        "landmarks": {"board": {"position": [x, y, 0], "yaw": yaw, "shape": "box", "size": BOARD}},
        "initial": {"red": {"position": [0.3, -0.25, 0]}},
        "steps": [
            {
                "object": "red",
                "position": [x + c * dx - s * dy + 0.001 * index, y + s * dx + c * dy, BOARD[2]],
                "yaw": yaw + 10,
            }
        ],
    }


@pytest.fixture(scope="module")
def model() -> Any:
    boards = [(0.45, 0.05, 0.0), (0.5, 0.12, 40.0), (0.4, 0.0, -30.0)]
    demos = [
        d
        for i, board in enumerate(boards)
        for d in demonstrations_from_document(_demonstration(i, *board), f"d{i}")
    ]
    return learn(demos)


def _scene(yaw: float) -> Any:
    return scene_from_document(
        {
            "format": "demoplan/scene-1",
            "objects": {"red": {"position": [0.3, -0.25, 0]}},
            "landmarks": {
                "board": {"position": [0.45, 0.1, 0], "yaw": yaw, "shape": "box", "size": BOARD}
            },
        },
        "scene.json",
    )


@pytest.mark.parametrize(
    ("sim", "seed", "faults"),
    [("mujoco", 0, Faults()), ("arm", 2, Faults(drop=0.5)), ("arm", 3, Faults(drop=0.5))],
    ids=["mujoco", "arm-drops-seed-2", "arm-drops-seed-3"],
)
def test_a_block_stands_on_the_turned_board(
    model: Any, sim: str, seed: int, faults: Faults
) -> None:
    report = run_task(
        model, prepare(model, _scene(75.0)), sim=sim, seed=seed, faults=faults, settings=UNTIMED
    )
    assert report.success, report.reason
    assert bool(report.injected) == faults.any(), report.injected  # the seed injects one
    red = report.final.poses["red"]
    assert red.position[2] == pytest.approx(BOARD[2], abs=0.003)  # on the board, not the table
    c, s = math.cos(math.radians(75.0)), math.sin(math.radians(75.0))
    dx, dy = ON_BOARD
    assert math.dist(red.position[:2], (0.45 + c * dx - s * dy, 0.1 + s * dx + c * dy)) < 0.01
