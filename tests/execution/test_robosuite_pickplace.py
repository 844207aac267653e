"""robosuite's PickPlace (docs/execution.md "robosuite"): the bins as landmarks
with their geometry, the four objects learned into bin2's compartments as
region goals, one seed run end to end, and robosuite's verdict overriding
demoplan's.

The runs need the ``robosuite`` extra (its own environment); where it is not
installed they are skipped with that reason (failed with
``DEMOPLAN_REQUIRE_ROBOSUITE=1``).
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import pytest

from demoplan.learning.regions import in_compartment, local_point
from demoplan.model import TaskModel
from tests.support.robosuite_data import RobosuiteDataError, skip_or_fail

INSTALLED = importlib.util.find_spec("robosuite") is not None
MISSING = (
    "robosuite is not installed: pip install 'demoplan[robosuite]' in its own "
    "environment (docs/execution.md)"
)


@pytest.fixture(autouse=True)
def robosuite_installed() -> None:
    if not INSTALLED:
        if os.environ.get("DEMOPLAN_REQUIRE_ROBOSUITE") == "1":
            pytest.fail(MISSING)
        pytest.skip(MISSING)


def _learned(env: str, folder: Path) -> TaskModel:
    from tests.support.robosuite_tasks import task_model

    try:
        return task_model(env, folder)
    except RobosuiteDataError as exc:
        skip_or_fail(exc)
        raise


def test_the_four_objects_are_learned_into_bin2s_four_compartments(tmp_path: Path) -> None:
    model = _learned("PickPlace", tmp_path)
    assert {s.object for s in model.states} == {"Milk", "Bread", "Cereal", "Can"}
    assert all(s.position.reference == "bin2" for s in model.states)
    regions = [s.position.region for s in model.states]
    assert all(r is not None for r in regions) and len(set(regions)) == 4


def test_the_bins_walls_and_dividers_are_landmarks_with_their_geometry() -> None:
    """bin2's compartments are robosuite's own four quarters (its check's
    bounds, less the divider's half thickness), and every wall stands where
    robosuite's bins have theirs."""
    from demoplan.execution.robosuite_scene import landmarks, make_environment, table_top

    env = make_environment("PickPlace", 0)
    try:
        found = landmarks(env)
        poses, shapes = dict(found.poses), dict(found.shapes)
        (boxes,) = [b for name, b in found.compartments if name == "bin2"]
        assert len(boxes) == 4
        for index in range(4):  # robosuite's compartment of object index (its not_in_bin)
            x0 = env.bin2_pos[0] - (env.bin_size[0] / 2 if index in (0, 2) else 0.0)
            y0 = env.bin2_pos[1] - (env.bin_size[1] / 2 if index < 2 else 0.0)
            middle = (x0 + env.bin_size[0] / 4, y0 + env.bin_size[1] / 4, 0.0)
            local = local_point(middle, poses["bin2"])
            local[2] = boxes[0][2]  # on its floor
            assert sum(in_compartment(local, box) for box in boxes) == 1
        floor = env.bin2_pos[2] + env.bin_size[2] / 2 - table_top(env)
        for name, shape in shapes.items():
            assert name.startswith(("bin1_wall", "bin2_wall"))
            assert poses[name].position[2] < floor + 0.001  # stands on or below the floor
            assert shape.size[2] > 0.05
    finally:
        env.close()


def test_one_pickplace_seed_end_to_end(tmp_path: Path) -> None:
    """Seed 0: the four objects into their compartments, by robosuite's check
    and by demoplan's (each anywhere in its compartment). Before the hand kept
    clear of the bins' walls, the bread's put-down locked the arm here and the
    cereal box was never lifted."""
    from demoplan.execution.robosuite_run import run_in_robosuite

    report = run_in_robosuite(_learned("PickPlace", tmp_path), "robosuite:PickPlace", seed=0)
    assert report.env_success, report.reason
    assert report.success
    put = {a.action.object for a in report.actions if a.action.kind == "PUT_DOWN"}
    assert put == {"Milk", "Bread", "Cereal", "Can"}
    bread = [
        a.ok for a in report.actions if (a.action.kind, a.action.object) == ("PUT_DOWN", "Bread")
    ]
    assert bread == [True]


def test_a_run_robosuite_judges_failed_is_never_a_success(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Stack seed 0 succeeds by both checks; with robosuite's check saying no,
    the run is no success, and the reason names robosuite's check."""
    from demoplan.execution import robosuite_world
    from demoplan.execution.robosuite_run import run_in_robosuite

    monkeypatch.setattr(robosuite_world.RobosuiteWorld, "env_success", lambda self: False)
    report = run_in_robosuite(_learned("Stack", tmp_path), "robosuite:Stack", seed=0)
    assert report.demoplan_success and not report.env_success
    assert not report.success
    assert report.exit_code != 0
    assert "robosuite's success check fails" in report.reason


def test_the_can_is_round_and_the_cartons_are_boxes() -> None:
    """robosuite's objects are meshes: the can's points lie on a circle and it
    is a cylinder (as a box its corners overlapped the bread it touched in
    seed 31, and the scene was refused); the milk carton (square) and the
    cereal box (long) stay boxes."""
    from demoplan.execution.robosuite_scene import env_objects, make_environment

    env = make_environment("PickPlace", 31)
    try:
        shapes = {o.name: o.geometry.shape for o in env_objects(env)}
    finally:
        env.close()
    assert shapes == {"Milk": "box", "Bread": "box", "Cereal": "box", "Can": "cylinder"}
