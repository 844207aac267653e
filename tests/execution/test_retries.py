"""The executor does not repeat a failed grasp forever: the same grasp (object,
finger axis, place) is tried at most three times, then another grasp, then
the run stops naming the object."""

from __future__ import annotations

from collections import Counter

import pytest

from demoplan.execution.executor import MAX_SAME_GRASP, execute
from demoplan.execution.faults import Faults
from demoplan.execution.kinematic import KinematicWorld
from demoplan.execution.report import RunReport
from demoplan.model import TaskModel
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import complete_geometry, load_scene
from tests.support.helpers import EXAMPLES, paper_model

BLOCKS = EXAMPLES / "scenes" / "pyramid-fig4.json"


@pytest.fixture(scope="module")
def blocks() -> TaskModel:
    return paper_model("blocks/demonstrations.json")


def _tries(report: RunReport) -> Counter[tuple[str, str, tuple[float, ...]]]:
    """How often each grasp (object, grasp, place to the centimetre) was tried."""
    return Counter(
        (e.action.object, e.action.grasp, tuple(round(v, 2) for v in e.pose.position))
        for e in report.actions
        if e.action.kind == "GRASP"
    )


def test_a_grasp_that_failed_three_times_gives_way_to_another(blocks: TaskModel) -> None:
    """The first grasp misses three times in a row (the kinematic world's
    scheduled faults): the replan takes the object with its other grasp, and
    the run ends with the pyramid."""
    scene = complete_geometry(load_scene(BLOCKS), blocks)
    world = KinematicWorld(scene, schedule={k: "grasp" for k in range(1, MAX_SAME_GRASP + 1)})
    report = execute(blocks, prepare(blocks, scene, clutter=True), world)
    assert report.success and [f.kind for f in report.failures] == ["grasp"] * MAX_SAME_GRASP
    first, fourth = (report.actions[k].action for k in (0, MAX_SAME_GRASP))
    assert fourth.kind == "GRASP" and (fourth.object, fourth.grasp) != (first.object, first.grasp)
    assert max(_tries(report).values()) == MAX_SAME_GRASP


def test_a_run_whose_grasps_all_fail_stops_naming_the_object(blocks: TaskModel) -> None:
    """Every grasp misses: each is tried three times, then the run stops in one
    line naming the object — not after 25 replans."""
    scene = complete_geometry(load_scene(BLOCKS), blocks)
    report = execute(
        blocks, prepare(blocks, scene, clutter=True), KinematicWorld(scene, Faults(grasp=1.0), 0)
    )
    assert not report.success and report.exit_code == 4 and "\n" not in report.reason
    first = report.actions[0].action.object
    assert report.reason.startswith(f"{first} could not be grasped in 6 attempts (grasps tried: ")
    assert f"then gave up on {first}: each of its grasps failed 3 times" in report.reason
    tries = _tries(report)
    assert set(tries.values()) == {MAX_SAME_GRASP} and len(tries) == 2  # blocks: 2 grasps
    assert len(report.failures) == report.replans == 2 * MAX_SAME_GRASP  # the last one stops
