"""The scene is prepared once per run: checked, completed and its goals
resolved in one place (scenes.prepared), not again by the planner, the
executor and every replan."""

from __future__ import annotations

from typing import Any

import pytest

import demoplan.scenes.prepared as prepared_module
from demoplan.budget import PLANNING_SECONDS
from demoplan.execution.faults import Faults
from demoplan.execution.runner import run_task
from demoplan.planning.strips import validate
from demoplan.scenes.plan import plan_in_scene
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import load_scene
from tests.support.helpers import EXAMPLES, UNTIMED, paper_model


@pytest.fixture
def completions(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Every completion of a scene, by its source."""
    seen: list[str] = []
    original = prepared_module.complete_scene

    def counted(scene: Any, model: Any) -> Any:
        seen.append(scene.source)
        return original(scene, model)

    monkeypatch.setattr(prepared_module, "complete_scene", counted)
    return seen


def test_a_run_with_replans_prepares_its_scene_once(completions: list[str]) -> None:
    model = paper_model("blocks")
    scene = load_scene(EXAMPLES / "scenes" / "pyramid-fig4.json")
    report = run_task(
        model, prepare(model, scene), faults=Faults(drop=0.5, block=0.3), seed=2, settings=UNTIMED
    )
    assert report.replans > 0, "the seed injects no fault: pick another"
    assert report.success, report.reason
    assert len(completions) == 1, completions


def test_planning_a_prepared_scene_does_not_prepare_it_again(completions: list[str]) -> None:
    model = paper_model("blocks")
    prepared = prepare(model, load_scene(EXAMPLES / "scenes" / "pyramid-fig4.json"))
    result = plan_in_scene(model, prepared)
    validate(result.chosen.problem.problem, result.chosen.plan.actions)
    assert result.scene is prepared.scene  # what the figures draw
    assert len(completions) == 1


def test_one_planning_budget_default() -> None:
    """The CLI, the library and the executor take the default from one place,
    and every planning command's --timeout is the one declaration, its help
    naming the default it reads."""
    import inspect
    import typing

    import demoplan.api as api
    from demoplan.budget import default_budget
    from demoplan.cli.clock import DEFAULT_TIMEOUT
    from demoplan.cli.execution import run as run_command
    from demoplan.cli.export import export as export_command
    from demoplan.cli.planning import plan as plan_command
    from demoplan.cli.planning import solve as solve_command
    from demoplan.execution.executor import ExecutionSettings

    assert ExecutionSettings().budget.timeout == PLANNING_SECONDS == DEFAULT_TIMEOUT
    assert inspect.signature(api.plan).parameters["timeout"].default is None  # default_budget()
    assert default_budget().timeout == PLANNING_SECONDS
    assert inspect.signature(api.run).parameters["settings"].default is None  # ExecutionSettings()
    assert inspect.signature(run_task).parameters["settings"].default is None
    for command in (run_command, plan_command, solve_command, export_command):
        assert inspect.signature(command).parameters["timeout"].default is None  # the default
        option = typing.get_type_hints(command, include_extras=True)["timeout"].__metadata__[0]
        assert option.help.endswith(f"[default: {DEFAULT_TIMEOUT:g}] ('inf': no limit).")


def test_a_run_logs_its_phases_for_verbose(caplog: pytest.LogCaptureFixture) -> None:
    """--verbose shows the run as it goes: each plan, action and its end."""
    model = paper_model("blocks")
    scene = load_scene(EXAMPLES / "scenes" / "pyramid-fig4.json")
    with caplog.at_level("INFO", logger="demoplan.execution.executor"):
        report = run_task(model, prepare(model, scene), settings=UNTIMED)
    said = [r.getMessage() for r in caplog.records]
    assert said[0].startswith("run: plan at step 0")
    actions = [m for m in said if m.startswith("run: action")]
    assert len(actions) == len(report.actions)
    assert said[-1].startswith("run: done")
