"""The one-import Python API: learn, plan, run — and a world of one's own."""

from __future__ import annotations

import doctest
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pytest

import demoplan
from demoplan import api
from demoplan.execution.world import Observation
from demoplan.model import Pose
from tests.support.helpers import EXAMPLES

ROOT = Path(__file__).resolve().parents[1]
SCENE = EXAMPLES / "scenes" / "pyramid-fig4.json"


def test_the_module_example_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)  # its paths are the repository's
    failures, tried = doctest.testmod(api, raise_on_error=False)
    assert tried >= 5 and failures == 0


@dataclass
class Recording:
    """A World that delegates to the kinematic simulator and logs every call —
    the shape of a wrapper around a real robot."""

    inner: demoplan.World
    calls: list[tuple[str, str]] = field(default_factory=list)
    name: str = "recording"

    def observe(self) -> Observation:
        return self.inner.observe()

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        self.calls.append(("grasp", obj))
        self.inner.grasp(obj, axis, where)

    def put_down(self, obj: str, pose: Pose) -> None:
        self.calls.append(("put_down", obj))
        self.inner.put_down(obj, pose)

    def between_actions(self, upcoming: Sequence[Pose] = ()) -> None:
        self.inner.between_actions(upcoming)


def test_run_in_a_world_of_ones_own() -> None:
    """Everything a plan does goes through the World protocol: the report's
    actions are exactly the calls the world received."""
    from demoplan.execution.faults import Faults
    from demoplan.execution.runner import make_world
    from demoplan.scenes.scene import complete_geometry

    model = demoplan.learn([EXAMPLES / "blocks"], settings=demoplan.PAPER_SETTINGS)
    scene = complete_geometry(demoplan.load_scene(SCENE), model)
    world = Recording(make_world("kinematic", scene, Faults(), 0, "state"))
    report = demoplan.run(model, scene, world=world)
    assert report.success
    kinds = {"GRASP": "grasp", "PUT_DOWN": "put_down"}
    assert world.calls == [(kinds[a.action.kind], a.action.object) for a in report.actions]
    assert len(world.calls) == 8  # Experiment 2: 4 moves


def test_learn_takes_paths_and_demonstrations_alike() -> None:
    demos = demoplan.load_demonstrations([EXAMPLES / "blocks"])
    from_paths = demoplan.learn([EXAMPLES / "blocks"])
    from_objects = demoplan.learn(demos)
    assert [s.id for s in from_paths.states] == [s.id for s in from_objects.states]
    assert from_paths.constraints == from_objects.constraints
