"""The objects file the studio's *Save objects* writes (``demoplan/objects-1``,
docs/formats.md "Objects file") is read by ``plan`` and ``run`` as the scene it
starts from, its colours read as a scene's (every renderer draws them)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.learning import learn
from demoplan.learning.modelfile import save_model
from demoplan.scenes.scene import load_scene, scene_to_dict
from tests.support.lunch_box import LUNCH, lunch_demonstrations, lunch_scene

COLOURS = {"sandwich": "#C8A165", "apple": "#cc2222", "lunchbox": "#3366aa"}


def _objects_file(path: Path) -> Path:
    """The lunch box's start as an objects file: the scene with colours and sizes."""
    document = scene_to_dict(lunch_scene())
    document["format"] = "demoplan/objects-1"
    for group in ("objects", "landmarks"):
        for name, entry in document.get(group, {}).items():
            if name in COLOURS:
                entry["colour"] = COLOURS[name]
    for name, entry in document["objects"].items():
        shape, size, _ = LUNCH[name]
        entry.update(shape=shape, size=list(size))
    path.write_text(json.dumps(document))
    return path


def test_plan_reads_an_objects_file_as_the_scene_it_starts_from(tmp_path: Path) -> None:
    model = tmp_path / "model.json"
    save_model(learn(lunch_demonstrations()), model)
    objects = _objects_file(tmp_path / "objects.json")
    scene = tmp_path / "scene.json"
    plain = json.loads(objects.read_text())
    plain["format"] = "demoplan/scene-1"
    for group in ("objects", "landmarks"):
        for entry in plain[group].values():
            entry.pop("colour", None)
    scene.write_text(json.dumps(plain))

    read = load_scene(objects)
    assert read.given_colours == {name: colour.lower() for name, colour in COLOURS.items()}
    assert replace(read, colours=()) == replace(load_scene(scene), source=str(objects))
    runner = CliRunner()
    options = ["--json", "--timeout", "inf"]
    from_objects = runner.invoke(app, ["plan", str(model), str(objects), *options])
    from_scene = runner.invoke(app, ["plan", str(model), str(scene), *options])
    assert from_objects.exit_code == 0, from_objects.output
    assert from_scene.exit_code == 0, from_scene.output
    assert json.loads(from_objects.stdout)["actions"] == json.loads(from_scene.stdout)["actions"]


def test_a_colour_that_is_not_rrggbb_is_one_line_naming_its_field(tmp_path: Path) -> None:
    model = tmp_path / "model.json"
    save_model(learn(lunch_demonstrations()), model)
    objects = _objects_file(tmp_path / "objects.json")
    document = json.loads(objects.read_text())
    document["objects"]["apple"]["colour"] = "red"
    objects.write_text(json.dumps(document))
    result = CliRunner().invoke(app, ["plan", str(model), str(objects)])
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, result.output
    assert "objects.apple.colour" in lines[0] and "#rrggbb" in lines[0]


def test_show_reads_an_objects_file(tmp_path: Path) -> None:
    objects = _objects_file(tmp_path / "objects.json")
    result = CliRunner().invoke(app, ["show", str(objects)])
    assert result.exit_code == 0, result.output
    assert "lunchbox" in result.output and "sandwich" in result.output
