"""Budgets that hold for every size of input (docs/limits.md "Budgets of long
computations"): floods of unknown objects, thousands of free-space spots, a
deep TF chain. Each command, given a small budget, answers exit 4 in one line
naming the option that raises it (and where the time went), or refuses the
input's size up front (exit 1 / 2) — never a hang or a traceback. A goal
proved unreachable in a few states is exit 3 however small the budget.

No timing is asserted (the machine is shared): the harness's hang guard
(HANG_SECONDS, far above any budget here) is the only clock. The floods are
sized so that no machine builds their planning problems within the budget.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from typing import Any

import pytest

from tests.helpers import EXAMPLES
from tests.hostile.harness import check_clean, check_refused, run

CUBE = [0.04, 0.04, 0.04]
PLAN = ["plan", "model.json"]
RUN = ["run", "model.json"]
ARM = ["--sim", "arm"]


def _fig4() -> dict[str, Any]:
    scene: dict[str, Any] = json.loads((EXAMPLES / "scenes" / "pyramid-fig4.json").read_text())
    return scene


def _clutter(count: int) -> dict[str, Any]:
    """The Fig. 4 scene with ``count`` cubes the model never saw, on a grid
    beside it (6 cm apart: none touches another)."""
    scene = _fig4()
    side = math.ceil(math.sqrt(count))
    for k in range(count):
        i, j = divmod(k, side)
        scene["objects"][f"c{k}"] = {
            "position": [0.5 + 0.06 * i, -0.6 + 0.06 * j, 0.0],
            "size": CUBE,
        }
    return scene


def _spots(count: int) -> dict[str, Any]:
    """The Fig. 4 scene with ``count`` free-space spots, 5 cm apart."""
    scene = _fig4()
    side = math.ceil(math.sqrt(count))
    scene["freespace"] = [
        [-0.1 - 0.05 * (k // side), -0.1 - 0.05 * (k % side)] for k in range(count)
    ]
    return scene


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("budgets")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    assert run(["learn", "demos.json", "--paper", "-o", "model.json"], folder).code == 0
    for count in (200, 500, 1000):
        (folder / f"clutter-{count}.json").write_text(json.dumps(_clutter(count)))
    for count in (2000, 10000):
        (folder / f"spots-{count}.json").write_text(json.dumps(_spots(count)))
    return folder


def check_out_of_time(answer: Any, option: str = "--timeout") -> None:
    """Exit 4, one line naming the option that raises the budget."""
    check_refused(answer, [option], codes={4})


@pytest.mark.parametrize(
    "args",
    [
        pytest.param([*PLAN, "clutter-1000.json", "--clutter"], id="plan-1000-unknown"),
        pytest.param([*RUN, "clutter-1000.json", "--clutter"], id="run-1000-unknown"),
        pytest.param(
            [*RUN, "clutter-1000.json", "--clutter", *ARM],
            id="run-arm-1000-unknown",
        ),
        pytest.param([*PLAN, "spots-10000.json"], id="plan-10000-spots"),
    ],
)
def test_a_flood_stops_at_the_budget(workspace: Path, args: list[str]) -> None:
    """Far more than a budget of 1 s builds: exit 4, naming --timeout and where
    the time went (the planning problems, before any search)."""
    answer = run([*args, "--timeout", "1"], workspace)
    check_out_of_time(answer)
    assert "building the planning problems" in answer.stderr, answer


@pytest.mark.parametrize(
    "args",
    [
        pytest.param(
            [*PLAN, "clutter-200.json", "--clutter", "--timeout", "2"],
            id="plan-200-unknown",
        ),
        pytest.param(
            [*RUN, "clutter-500.json", "--clutter", "--timeout", "2"],
            id="run-500-unknown",
        ),
        pytest.param(
            [*RUN, "clutter-500.json", "--clutter", *ARM, "--timeout", "2"],
            id="run-arm-500-unknown",
        ),
        pytest.param([*PLAN, "spots-2000.json", "--timeout", "2"], id="plan-2000-spots"),
    ],
)
def test_the_floods_of_the_issue_answer(workspace: Path, args: list[str]) -> None:
    """The sizes that hung (issue 27): a plan (a fast machine may find one), or
    exit 4 naming --timeout; within the hang guard either way."""
    answer = run(args, workspace)
    check_clean(answer)
    if answer.code:
        check_out_of_time(answer)


def test_a_goal_proved_unreachable_in_a_few_states_is_exit_3_with_no_time(
    tmp_path: Path,
) -> None:
    """The kit on a table too small to park the manual: the search runs out of
    states at once, so even a budget of zero says there is no plan (exit 3)."""
    shutil.copy(EXAMPLES / "kitting" / "demonstrations.json", tmp_path / "kit.json")
    assert run(["learn", "kit.json", "-o", "model.json"], tmp_path).code == 0
    scene = json.loads((EXAMPLES / "kitting" / "scene-manual-on-motor.json").read_text())
    scene["table"] = {"min": [0.1, -0.15], "max": [0.5, 0.25]}
    (tmp_path / "tight.json").write_text(json.dumps(scene))
    for timeout in ("0", "0.001"):
        answer = run([*PLAN, "tight.json", "--timeout", timeout], tmp_path)
        check_refused(answer, ["no free space for manual"], codes={3})


def test_a_deep_tf_chain_stops_at_the_learning_budget(tmp_path: Path) -> None:
    """A TF chain 1000 frames deep with every frame an object: composing them
    takes minutes; learn --timeout 1 stops with exit 4, naming --timeout and
    the TF composition."""
    import numpy as np

    from demoplan.segmentation import PoseStream
    from demoplan.segmentation.types import ObjectTrack
    from demoplan.segmentation.writers import write_bag

    times = np.arange(3.0) * 0.1
    tracks, parents = [], {}
    for k in range(1, 1001):
        positions = np.zeros((3, 3))
        positions[:, 0] = 0.0001
        tracks.append(ObjectTrack(f"f{k}", times, positions, np.tile([0.0, 0.0, 0.0, 1.0], (3, 1))))
        parents[f"f{k}"] = "world" if k == 1 else f"f{k - 1}"
    write_bag(PoseStream(tuple(tracks)), tmp_path / "deep", parents=parents)
    answer = run(["learn", "deep", "--objects", "*", "--timeout", "1", "-o", "m.json"], tmp_path)
    check_out_of_time(answer)
    assert "TF" in answer.stderr, answer
    assert not (tmp_path / "m.json").exists()
