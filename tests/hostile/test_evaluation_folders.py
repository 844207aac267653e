"""``evaluate --resume DIR`` opens the folder closed, as a recording: its
settings and rows are checked field by field before any run (a tampered file
is one line naming the file and the field, exit 1), and nothing in it may be
a link or a special file."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from demoplan.commands import evaluation as evaluation_command
from demoplan.commands.evaluation import evaluate, settings_from_options
from demoplan.errors import InputError
from demoplan.evaluation.plan import read_settings
from demoplan.evaluation.results import read_rows
from demoplan.learning.modelfile import save_model
from tests.support.helpers import ONE_MOVE_SCENE, paper_model

SCENE = ONE_MOVE_SCENE


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An evaluation of two runs of one move (the checks read the folder, not
    what its runs did), made here one after the other, with the storyboard of
    its worst run only (no test here reads storyboards; each is that run made
    again frame by frame, most of the evaluation's CPU —
    tests/evaluation/test_evaluate.py's ``one_storyboard``)."""
    folder = tmp_path_factory.mktemp("evaluation")
    model = folder / "model.json"
    save_model(paper_model("blocks/demonstrations.json"), model)
    settings = settings_from_options(
        model, [SCENE], random_scenes=0, seeds=2, faults=None, sim="kinematic", clutter=0
    )
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(evaluation_command, "STORYBOARDS", 1)
        evaluate(settings, folder / "out")
    return folder / "out"


@pytest.fixture(autouse=True)
def one_storyboard(monkeypatch: pytest.MonkeyPatch) -> None:
    """Resuming keeps ``finished``'s one storyboard rather than drawing the
    second worst run's."""
    monkeypatch.setattr(evaluation_command, "STORYBOARDS", 1)


def _copy(finished: Path, tmp_path: Path) -> Path:
    out = tmp_path / "out"
    out.mkdir()
    for path in finished.rglob("*"):
        if path.is_file():
            target = out / path.relative_to(finished)
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(path.read_bytes())
    return out


SETTINGS_CHANGES: dict[str, tuple[Callable[[dict[str, Any]], None], str]] = {
    "attempts as a string": (lambda d: d["layout"].update(attempts="400"), "layout.attempts"),
    "a margin of 1e308": (lambda d: d["layout"].update(margin=1e308), "layout.margin"),
    "a negative yaw range": (lambda d: d["layout"].update(yaw_range=-30.0), "layout.yaw_range"),
    "seeds as a float": (lambda d: d.update(seeds=2.0), "seeds"),
    "an unknown field": (lambda d: d.update(shell="rm -rf /"), "shell"),
    "scenes not a list": (lambda d: d.update(scenes="a.json"), "scenes"),
}


@pytest.mark.parametrize("case", sorted(SETTINGS_CHANGES))
def test_a_tampered_settings_file_is_one_line(finished: Path, tmp_path: Path, case: str) -> None:
    out = _copy(finished, tmp_path)
    change, field = SETTINGS_CHANGES[case]
    data = json.loads((out / "evaluation.json").read_text())
    change(data)
    (out / "evaluation.json").write_text(json.dumps(data))
    with pytest.raises(InputError) as caught:
        evaluate(None, out, resume=True)
    text = str(caught.value)
    assert text.startswith(f"{out / 'evaluation.json'}: {field}"), text
    assert "\n" not in text


def test_a_tampered_row_is_one_line(finished: Path, tmp_path: Path) -> None:
    out = _copy(finished, tmp_path)
    rows = (out / "runs.jsonl").read_text().splitlines()
    second = json.loads(rows[1]) | {"success": "yes"}
    (out / "runs.jsonl").write_text(rows[0] + "\n" + json.dumps(second) + "\n")
    with pytest.raises(
        InputError, match=r"runs\.jsonl: line 2\.success: Input should be a valid boolean"
    ):
        read_rows(out)


@pytest.mark.parametrize(
    "entry", ["evaluation.json", "runs.jsonl", "scenes", f"scenes/{SCENE.name}"]
)
def test_a_link_in_the_folder_is_refused(finished: Path, tmp_path: Path, entry: str) -> None:
    out = _copy(finished, tmp_path)
    target = out / entry
    moved = tmp_path / "elsewhere"
    target.rename(moved)
    target.symlink_to(moved)
    with pytest.raises(InputError, match="is a link or a special file") as caught:
        read_settings(out)
    assert str(caught.value).startswith(str(target))


def test_the_untouched_folder_resumes_with_nothing_to_make(finished: Path, tmp_path: Path) -> None:
    out = _copy(finished, tmp_path)
    done = evaluate(None, out, resume=True)
    assert (done.made, done.planned) == (0, 2)
