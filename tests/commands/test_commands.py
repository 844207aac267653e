"""The command layer (demoplan.commands): each operation returns a value and
never prints; a failure carries what the front end needs to draw it; the
library's learn / plan / run are the same functions the command line calls."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

import demoplan
from demoplan.cli import app
from demoplan.commands import execution, learning, planning
from demoplan.learning.modelfile import save_model
from demoplan.scenes import plan as scene_plan
from demoplan.scenes.plan import SceneNoPlanError
from tests.support.helpers import EXAMPLES, paper_model

BLOCKS_SCENE = EXAMPLES / "scenes" / "pyramid-fig4.json"


@pytest.fixture(scope="module")
def blocks_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("model") / "blocks.json"
    save_model(paper_model("blocks"), path)
    return path


def _no_room(tmp_path: Path) -> Path:
    """Experiment 2's scene with no free space: neither goal has a plan."""
    scene = json.loads(BLOCKS_SCENE.read_text())
    scene["freespace"] = []
    path = tmp_path / "no-room.json"
    path.write_text(json.dumps(scene))
    return path


def test_the_library_and_the_command_line_share_the_command_functions() -> None:
    assert demoplan.learn is learning.learn_model
    assert demoplan.plan is planning.plan
    assert demoplan.run is execution.run


def test_commands_return_values_and_print_nothing(
    blocks_file: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    result = planning.plan(blocks_file, BLOCKS_SCENE)
    assert len(result.chosen.plan) == 8  # the paper's Experiment 2: 4 moves
    shown = learning.show(blocks_file)
    assert isinstance(shown, learning.ShownModel) and shown.model.states
    report = execution.run(blocks_file, BLOCKS_SCENE)
    assert report.success
    written = planning.write_problem(blocks_file, BLOCKS_SCENE, tmp_path / "p.xml")
    assert written.files == (tmp_path / "p.xml",) and written.files[0].is_file()
    out, err = capfd.readouterr()
    assert (out, err) == ("", "")


def test_a_failed_plan_carries_every_candidate_and_its_figure_builds_nothing_again(
    blocks_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``plan --plot`` without a plan draws the targets from the problems the
    planner was given (carried by the error): each candidate's problem is
    built once, not a second time for the figure."""
    scene = _no_room(tmp_path)
    with pytest.raises(SceneNoPlanError) as failure:
        planning.plan(blocks_file, scene)
    outcomes = failure.value.outcomes
    assert len(outcomes) == 2 and all(o.plan is None and o.reason for o in outcomes)
    assert failure.value.scene.names and failure.value.model.sequences

    built = []
    original = scene_plan.build_problem

    def counting(*args: object, **kwargs: object) -> object:
        built.append(1)
        return original(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(scene_plan, "build_problem", counting)
    picture = tmp_path / "why.png"
    result = CliRunner().invoke(app, ["plan", str(blocks_file), str(scene), "--plot", str(picture)])
    assert result.exit_code == 3, result.stderr
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(built) == len(outcomes), f"{len(built)} problems built for {len(outcomes)} goals"
