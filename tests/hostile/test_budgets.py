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

from tests.hostile.harness import check_clean, check_refused, run
from tests.support.helpers import EXAMPLES

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
    for count in (200, 500, 990, 1000):
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
            [*RUN, "clutter-990.json", "--clutter", *ARM],  # within the arm's 1000 objects
            id="run-arm-990-unknown",
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
    """A TF chain 1000 frames deep with every frame an object: learn with a
    budget spent before it starts (--timeout 0) stops with exit 4 in one line,
    naming --timeout and the TF composition, and writes no model. (The chain
    is composed in a few seconds now: a budget of 1 s was no longer sure to
    run out first. That the budget is read all through the composition is
    tests/segmentation/test_tf_tree.py's, with a fake clock.)"""
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
    answer = run(["learn", "deep", "--objects", "*", "--timeout", "0", "-o", "m.json"], tmp_path)
    check_out_of_time(answer)
    assert "TF" in answer.stderr, answer
    assert not (tmp_path / "m.json").exists()


def test_k_means_restarts_beyond_the_limit_are_refused(workspace: Path, tmp_path: Path) -> None:
    """A model whose settings ask for 10⁹ K-means restarts (45 GB side by
    side): learn --update refuses the field in one line, naming the limit."""
    model = json.loads((workspace / "model.json").read_text())
    model["settings"]["n_init"] = 10**9
    (tmp_path / "model.json").write_text(json.dumps(model))
    shutil.copy(workspace / "demos.json", tmp_path / "demos.json")
    answer = run(["learn", "demos.json", "--update", "model.json"], tmp_path)
    check_refused(answer, ["settings.n_init"], codes={1})
    assert "1000" in answer.stderr, answer


@pytest.mark.parametrize("side", ["1e300", "11"])
def test_a_block_side_beyond_ten_metres_is_refused(tmp_path: Path, side: str) -> None:
    """--side 1e300 overflowed into a traceback; a side beyond an object's
    largest extent (10 m) is a usage error naming --side."""
    shutil.copy(EXAMPLES / "perception" / "blocks-top.png", tmp_path / "top.png")
    args = ["perceive", "top.png", "--px-per-m", "1000", "--origin", "0", "0", "--side", side]
    check_refused(run(args, tmp_path), ["--side"], codes={2})


@pytest.mark.parametrize("scale", [1e-6, 1e-300])
def test_samples_nanoseconds_apart_are_refused(tmp_path: Path, scale: float) -> None:
    """The set-table stream with its times scaled down: segment ran for minutes
    (windows of billions of samples) or asked for 400 GB; now one line naming
    the track and the sample rate."""
    lines = (EXAMPLES / "streams" / "set-table-1.csv").read_text().splitlines()
    scaled = [lines[0]]
    for line in lines[1:]:
        t, rest = line.split(",", 1)
        scaled.append(f"{float(t) * scale!r},{rest}")
    (tmp_path / "fast.csv").write_text("\n".join(scaled) + "\n")
    answer = run(["segment", "fast.csv", "-o", "steps.json"], tmp_path)
    check_refused(answer, ["fast.csv"], codes={1})
    assert "a second" in answer.stderr and "seconds expected" in answer.stderr, answer
    assert not (tmp_path / "steps.json").exists()


def test_a_large_yaml_document_is_refused_before_parsing(tmp_path: Path) -> None:
    """A 3 MB YAML list (a 50 MB one parsed for half an hour): refused by its
    size in one line that says to write JSON."""
    scene = _fig4()
    header = "format: demoplan/scene-1\nobjects:\n"
    objects = "".join(
        f"  {name}: {{position: {obj['position']}, size: {obj['size']}}}\n"
        for name, obj in scene["objects"].items()
    )
    spot = "- [0.123456, 0.654321]\n"
    spots = "freespace:\n" + spot * (3 * 1024 * 1024 // len(spot))
    (tmp_path / "scene.yaml").write_text(header + objects + spots)
    answer = run(["show", "scene.yaml"], tmp_path)
    check_refused(answer, ["scene.yaml"], codes={1})
    assert "YAML" in answer.stderr and "JSON" in answer.stderr, answer


@pytest.mark.parametrize("sim", ["mujoco", "arm"])
def test_a_physics_world_of_thousands_of_bodies_is_refused(
    workspace: Path, tmp_path: Path, sim: str
) -> None:
    """2000 objects would be 2000 free bodies settled before the run (20 s;
    20,000: minutes, outside any budget): refused up front, naming the field
    and the limit."""
    (tmp_path / "scene.json").write_text(json.dumps(_clutter(2000)))
    shutil.copy(workspace / "model.json", tmp_path / "model.json")
    answer = run(["run", "model.json", "scene.json", "--clutter", "--sim", sim], tmp_path)
    check_refused(answer, ["scene.json: objects"], codes={1})
    assert "1,000" in answer.stderr, answer
