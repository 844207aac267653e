"""demoplan.commands.learning.learn_files: learning from files as `learn` does
it, callable without the command line."""

from __future__ import annotations

from pathlib import Path

import pytest

from demoplan.commands.learning import learn_files, read_requirements
from demoplan.errors import InputError
from demoplan.learning.modelfile import load_model
from tests.support.helpers import EXAMPLES

BLOCKS = EXAMPLES / "blocks" / "demonstrations.json"


def test_without_an_output_nothing_is_written(tmp_path: Path) -> None:
    result = learn_files([BLOCKS], paper=True)
    assert result.written is None and result.changes is None
    assert [s.id for s in result.model.states] == ["A", "B", "C", "D"]  # Table IV
    assert list(tmp_path.iterdir()) == []


def test_an_update_writes_back_and_says_what_changed(tmp_path: Path) -> None:
    model = tmp_path / "m.json"
    first = learn_files([BLOCKS], output=model, paper=True)
    assert first.written == model and load_model(model).states == first.model.states
    assert ("D", "A") in first.model.constraints  # pyramid-2 puts green (D) first
    again = learn_files([BLOCKS], update_path=model, require=["wood<green"])
    assert again.written == model and again.changes is not None
    assert "constraints added: A<D" in again.changes.lines()
    constraints = load_model(model).constraints  # the teacher's wood<green holds for D too
    assert ("A", "D") in constraints and ("D", "A") not in constraints


def test_a_bad_requirement_from_a_file_names_the_file(tmp_path: Path) -> None:
    rules = tmp_path / "rules.txt"
    rules.write_text("# teacher\nwood<nothing  # an unknown object\n")
    assert read_requirements(rules) == ["wood<nothing"]
    with pytest.raises(InputError) as caught:
        learn_files([BLOCKS], require_file=rules, paper=True)
    assert caught.value.source == str(rules)


def test_the_output_may_not_be_an_input(tmp_path: Path) -> None:
    copy = tmp_path / "d.json"
    copy.write_bytes(BLOCKS.read_bytes())
    with pytest.raises(InputError, match="is also an input"):
        learn_files([copy], output=copy)


def test_learning_from_a_studio_work_folder_skips_its_model_scene_and_objects_file(
    tmp_path: Path,
) -> None:
    """The studio writes its demonstrations, the user's scene and the model it
    learned into one work folder (demoplan.studio.workfolder), and an objects
    file may stand beside them: `learn FOLDER` learns from the demonstrations
    alone and names the other files in one warning line (it stopped at the
    model: "unknown format 'demoplan/model-1'")."""
    import json

    from typer.testing import CliRunner

    from demoplan.cli import app
    from demoplan.learning.modelfile import save_model
    from demoplan.studio.workfolder import WorkFolder

    folder = WorkFolder(tmp_path / "work")
    sources = sorted((EXAMPLES / "set_table").glob("demonstration-*.json"))
    for source in sources:
        folder.create(json.loads(source.read_text()), None, "demonstration")
    scene = json.loads((EXAMPLES / "scenes" / "set-table-cluttered.json").read_text())
    folder.create(scene, "my-scene.json", "scene")
    learned = learn_files(sources).model
    save_model(learned, folder.root / "model.json")
    objects = {"objects": json.loads(sources[0].read_text())["objects"]}
    (folder.root / "objects.json").write_text(json.dumps(objects))
    output = tmp_path / "relearned.json"
    result = CliRunner().invoke(app, ["learn", str(folder.root), "-o", str(output)])
    assert result.exit_code == 0, result.stderr
    skipped = [line for line in result.stderr.splitlines() if "skipped" in line]
    assert skipped == [
        f"demoplan: WARNING: {folder.root}: skipped 3 files that are not a demonstration: "
        "model.json (a task model), my-scene.json (a scene), objects.json (an objects file)"
    ]
    model = load_model(output)
    assert len(model.demonstrations) == len(sources)
    assert model.states == learned.states and model.constraints == learned.constraints


def test_a_folder_of_models_only_is_refused_naming_what_it_holds(tmp_path: Path) -> None:
    from demoplan.learning.modelfile import save_model

    save_model(learn_files([BLOCKS]).model, tmp_path / "model.json")
    with pytest.raises(InputError, match=r"no demonstration files, only model\.json \(a task"):
        learn_files([tmp_path])


def test_one_demonstration_is_learned_with_one_plain_warning(tmp_path: Path) -> None:
    """One demonstration (or exact repeats of it) is learned — `learn --update`
    adds the next — with one warning line saying to teach at least two, not a
    warning per state and decision (there were 14 for the dinner table)."""
    from typer.testing import CliRunner

    from demoplan.cli import app

    first = EXAMPLES / "set_table" / "demonstration-1.json"
    second = EXAMPLES / "set_table" / "demonstration-2.json"
    for inputs, told in (([first], "one demonstration"), ([first, first], "one demonstration")):
        output = str(tmp_path / "model.json")
        result = CliRunner().invoke(app, ["learn", *map(str, inputs), "-o", output])
        assert result.exit_code == 0, result.stderr
        warnings = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
        assert len(warnings) == 1 and f"learned from {told}" in warnings[0]
        assert "teach the task at least twice" in warnings[0]
    output = str(tmp_path / "two.json")
    result = CliRunner().invoke(app, ["learn", str(first), str(second), "-o", output])
    assert result.exit_code == 0 and "at least twice" not in result.stderr
    assert "warning: state" in result.stderr  # two demonstrations: the usual diagnostics


def test_counts_in_a_model_files_errors_are_in_the_singular_for_one(tmp_path: Path) -> None:
    """"1 goals for 2 sequences" read as a typo; a count of one takes the singular."""
    import json

    from demoplan.learning.modelfile import save_model

    path = tmp_path / "model.json"
    save_model(learn_files([BLOCKS]).model, path)
    document = json.loads(path.read_text())
    assert len(document["sequences"]) == 2
    document["goals"] = document["goals"][:1]
    path.write_text(json.dumps(document))
    with pytest.raises(InputError, match=r"goals: 1 goal for 2 sequences; one goal per"):
        load_model(path)
    document = json.loads(path.read_text())
    document["demonstrations"] = document["demonstrations"][:1]
    document["goals"] = document["goals"] * 2
    path.write_text(json.dumps(document))
    with pytest.raises(InputError, match=r"1 demonstration for 2 sequences; one sequence per"):
        load_model(path)
