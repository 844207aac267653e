"""``demoplan run MODEL --sim robosuite:ENV`` (docs/execution.md "robosuite"): tasks
learned from robosuite's recordings, carried out by its Panda in its own
environments and judged by its ``_check_success()``.

The runs need the ``robosuite`` extra (its own environment: robosuite 1.5.2
pins mink 0.0.5 and fails on MuJoCo 4); where it is not installed they are
skipped with that reason (failed with ``DEMOPLAN_REQUIRE_ROBOSUITE=1``), and
what demoplan says instead is tested.
"""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path

import pytest

from demoplan.learning.modelfile import model_to_dict
from demoplan.model import TaskModel
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES
from tests.support.robosuite_data import RobosuiteDataError, skip_or_fail

INSTALLED = importlib.util.find_spec("robosuite") is not None
MISSING = (
    "robosuite is not installed: pip install 'demoplan[robosuite]' in its own "
    "environment (docs/execution.md)"
)


@pytest.fixture
def robosuite_installed() -> None:
    """Skip a run where robosuite is not installed — unless
    ``DEMOPLAN_REQUIRE_ROBOSUITE=1`` (CI's robosuite environment), where that fails."""
    if not INSTALLED:
        if os.environ.get("DEMOPLAN_REQUIRE_ROBOSUITE") == "1":
            pytest.fail(MISSING)
        pytest.skip(MISSING)


@pytest.fixture(scope="module")
def blocks_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Any model: the blocks example's (the refusals come before robosuite)."""
    path = tmp_path_factory.mktemp("blocks") / "model.json"
    result = invoke("learn", EXAMPLES / "blocks" / "demonstrations.json", "-o", path)
    assert result.exit_code == 0, result.stderr
    return path


def _learned(env: str, folder: Path) -> TaskModel:
    from tests.support.robosuite_tasks import task_model

    try:
        return task_model(env, folder)
    except RobosuiteDataError as exc:
        skip_or_fail(exc)
        raise


def test_an_unknown_environment_is_a_usage_error(blocks_model: Path) -> None:
    result = invoke("run", blocks_model, "--sim", "robosuite:Lift")
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert "robosuite:Lift" in result.stderr and "Stack" in result.stderr


def test_a_scene_is_refused_and_other_worlds_still_need_one(blocks_model: Path) -> None:
    scene = EXAMPLES / "blocks" / "demonstrations.json"
    given = invoke("run", blocks_model, scene, "--sim", "robosuite:Stack")
    assert given.exit_code == 2
    assert "no SCENE expected" in given.stderr
    missing = invoke("run", blocks_model)
    assert missing.exit_code == 2
    assert "a SCENE is needed" in missing.stderr


@pytest.mark.skipif(INSTALLED, reason="robosuite is installed here")
def test_without_robosuite_the_error_says_what_to_install(blocks_model: Path) -> None:
    result = invoke("run", blocks_model, "--sim", "robosuite:Stack")
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert "pip install 'demoplan[robosuite]'" in result.stderr


@pytest.mark.usefixtures("robosuite_installed")
def test_stack_learned_from_the_recordings_succeeds_by_robosuites_check(
    tmp_path: Path,
) -> None:
    model = tmp_path / "stack.json"
    model.write_text(json.dumps(model_to_dict(_learned("Stack", tmp_path))))
    result = invoke("run", model, "--sim", "robosuite:Stack", "--seed", "0", "--json")
    report = json.loads(result.stdout)
    assert result.exit_code == 0, result.stderr
    assert report["env_success"] is True
    assert report["success"] is True
    assert report["world"] == "robosuite:Stack"
    assert [a[:2] for a in report["actions"]] == [["GRASP", "cubeA"], ["PUT_DOWN", "cubeA"]]


@pytest.mark.usefixtures("robosuite_installed")
def test_both_nuts_go_on_their_pegs(tmp_path: Path) -> None:
    from demoplan.execution.robosuite_run import run_in_robosuite

    report = run_in_robosuite(_learned("NutAssembly", tmp_path), "robosuite:NutAssembly", seed=0)
    assert report.env_success
    assert report.success
    placed = {a.action.object for a in report.actions if a.action.kind == "PUT_DOWN" and a.ok}
    assert placed == {"SquareNut", "RoundNut"}


@pytest.mark.usefixtures("robosuite_installed")
def test_the_square_nut_alone(tmp_path: Path) -> None:
    from demoplan.execution.robosuite_run import run_in_robosuite

    model = _learned("NutAssemblySquare", tmp_path)
    report = run_in_robosuite(model, "robosuite:NutAssemblySquare", seed=0)
    assert report.env_success and report.success


@pytest.mark.usefixtures("robosuite_installed")
def test_the_can_goes_into_its_bin(tmp_path: Path) -> None:
    """PickPlaceCan: the bins are landmarks without a size (references: the
    can's target is learned relative to bin2, anywhere in its compartment),
    their walls and dividers box landmarks of their own."""
    from demoplan.execution.robosuite_run import run_in_robosuite

    model = _learned("PickPlaceCan", tmp_path)
    (can,) = model.states
    assert can.position.reference == "bin2" and can.position.region is not None
    report = run_in_robosuite(model, "robosuite:PickPlaceCan", seed=0)
    assert report.env_success and report.success
    shapes = dict(report.scene.landmark_geometry)
    assert "bin1" not in shapes and "bin2" not in shapes  # hollow: no solid box to stand in
    walls = {name for name, _ in report.scene.landmarks} - {"bin1", "bin2"}
    assert walls == set(shapes)
    assert sum(name.startswith("bin1_wall") for name in walls) == 4
    assert sum(name.startswith("bin2_wall") for name in walls) == 6  # and its two dividers
