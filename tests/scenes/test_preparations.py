"""A command prepares its scene once, and each replan the observed world once
(docs/architecture.md): counted for ``plan``, ``run`` and the studio's run,
whose paths are the CLI's, the command layer's and the studio worker's."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Iterator
from io import StringIO
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import demoplan.scenes.prepared as prepared_module
from demoplan.cli import app
from demoplan.commands.execution import run
from demoplan.commands.learning import learn_files
from demoplan.commands.planning import plan
from demoplan.execution.faults import Faults
from demoplan.studio import worker
from tests.support.helpers import EXAMPLES

BLOCKS = EXAMPLES / "blocks" / "demonstrations.json"
FIG4 = EXAMPLES / "scenes" / "pyramid-fig4.json"
PREPARATIONS = ("prepare", "prepare_observed")


class Preparations:
    """Calls of the preparation functions, wherever they were imported."""

    def __init__(self) -> None:
        self.calls: list[str] = []

    def count(self, name: str, original: Callable[..., Any]) -> Callable[..., Any]:
        def counted(*args: Any, **kwargs: Any) -> Any:
            self.calls.append(name)
            return original(*args, **kwargs)

        return counted

    def of(self, name: str) -> int:
        return self.calls.count(name)

    def reset(self) -> None:
        self.calls.clear()


@pytest.fixture
def preparations(monkeypatch: pytest.MonkeyPatch) -> Iterator[Preparations]:
    """Each preparation function counted in its own module and in every loaded
    module of the package that imported it by name (the modules the commands
    run through are imported above, so that none binds a counted one for good)."""
    seen = Preparations()
    for name in PREPARATIONS:
        original = getattr(prepared_module, name)
        counted = seen.count(name, original)
        for module in list(sys.modules.values()):
            if (getattr(module, "__name__", "") or "").startswith("demoplan") and getattr(
                module, name, None
            ) is original:
                monkeypatch.setattr(module, name, counted)
    yield seen


@pytest.fixture(scope="module")
def blocks_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("model") / "model.json"
    learn_files([BLOCKS], output=path)
    return path


def test_plan_prepares_its_scene_once(preparations: Preparations, blocks_model: Path) -> None:
    result = CliRunner().invoke(app, ["plan", str(blocks_model), str(FIG4), "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["length"] == 8  # the paper's Experiment 2: 4 moves
    assert preparations.calls == ["prepare"]


def test_a_plan_out_of_time_stops_in_the_preparation(
    preparations: Preparations, blocks_model: Path
) -> None:
    """The preparation runs on the command's clock: a budget spent before it
    starts stops it there (exit 4), naming the time budget."""
    from demoplan.budget import Budget
    from demoplan.errors import LimitReachedError
    from demoplan.scenes import plan as scene_plan

    spent = Budget(timeout=0.0)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(scene_plan, "BUILDING_SECONDS", 0.0)  # no grace for a slow start
        complete = prepared_module.complete_scene

        def slow(*args: Any) -> Any:
            from demoplan.budget import check_time

            check_time(" completing the scene")  # as the geometry does, object by object
            return complete(*args)

        patch.setattr(prepared_module, "complete_scene", slow)
        with pytest.raises(LimitReachedError, match="completing the scene") as caught:
            plan(blocks_model, FIG4, budget=spent)
    assert caught.value.exit_code == 4
    assert preparations.calls == ["prepare"]


@settings(
    max_examples=4,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(drop=st.sampled_from([0.0, 0.4, 0.8]), seed=st.integers(0, 1_000))
def test_run_prepares_once_and_once_per_replan(
    preparations: Preparations, blocks_model: Path, drop: float, seed: int
) -> None:
    preparations.reset()  # one fixture for every example
    report = run(blocks_model, FIG4, faults=Faults(drop=drop, block=drop / 2), seed=seed)
    assert preparations.of("prepare") == 1
    assert preparations.of("prepare_observed") == report.replans


def test_the_studio_run_prepares_once_and_once_per_replan(
    preparations: Preparations, blocks_model: Path
) -> None:
    scene = json.loads(FIG4.read_text(encoding="utf-8"))
    scene.pop("format")
    request = {
        "model": str(blocks_model),
        "scene": scene,
        "sim": "kinematic",
        "faults": "drop=0.5,block=0.3",
        "seed": 2,
    }
    outcome = worker._run(request, StringIO())
    replans = outcome["result"]["replans"]
    assert replans > 0, "the seed injects no fault: pick another"
    assert preparations.of("prepare") == 1
    assert preparations.of("prepare_observed") == replans
