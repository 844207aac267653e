"""Names as the user gave them, and "did you mean" for every unknown one."""

from __future__ import annotations

from typing import Any

import pytest

from demoplan.documents.demonstrations import demonstrations_from_document
from demoplan.errors import InputError
from demoplan.learning import learn
from demoplan.scenes.scene import scene_from_document
from demoplan.scenes.targets import check_scene_objects
from demoplan.wording import did_you_mean
from tests.support.helpers import paper_model


@pytest.mark.parametrize(
    ("name", "known", "expected"),
    [
        ("Tray", ["tray", "plate"], "; did you mean 'tray'?"),
        ("tary", ["tray", "plate"], "; did you mean 'tray'?"),
        ("bleach_cleanser", ["Bleach_cleanser"], "; did you mean 'Bleach_cleanser'?"),
        ("knife", ["tray", "plate"], ""),
        ("tray", ["tray"], ""),  # the name itself is no suggestion
        ("x", [], ""),
    ],
)
def test_did_you_mean(name: str, known: list[str], expected: str) -> None:
    assert did_you_mean(name, known) == expected


def test_a_misspelt_requirement_names_the_object_meant() -> None:
    model = paper_model("set_table")
    with pytest.raises(InputError, match=r"'Plate' is neither .*; did you mean 'plate'\?$"):
        learn(list(model.demonstrations), require=["Plate<napkin"])


def test_a_scene_object_in_other_letters_is_named() -> None:
    model = paper_model("blocks")
    document = {
        "format": "demoplan/scene-1",
        "objects": {
            "Wood": {"position": [0.3, 0.04, 0.0], "size": [0.04, 0.04, 0.04]},
            "green": {"position": [0.3, -0.1, 0.0], "size": [0.04, 0.04, 0.04]},
            "red": {"position": [0.4, -0.1, 0.0], "size": [0.04, 0.04, 0.04]},
        },
    }
    names = {s.object for s in model.states}
    for name in sorted(names - {"wood", "green", "red"}):
        document["objects"][name] = {"position": [0.5, 0.1, 0.0], "size": [0.04, 0.04, 0.04]}
    scene = scene_from_document(document, "scene.json")
    with pytest.raises(InputError, match=r"lacks; .*the scene's 'Wood' .*did you mean 'wood'\?"):
        check_scene_objects(model, scene)


LUNCH = {
    "format": "demoplan/demonstration-1",
    "objects": {
        "sandwich": {"size": [0.1, 0.1, 0.03]},
        "apple": {"shape": "sphere", "size": [0.07, 0.07, 0.07]},
    },
    "landmarks": {"lunchbox": {"position": [0.4, 0.2, 0], "size": [0.26, 0.18, 0.02]}},
    "initial": {"sandwich": {"position": [0.1, -0.3]}, "apple": {"position": [0.3, -0.3]}},
    "steps": [
        {"object": "sandwich", "position": [0.35, 0.2, 0.02]},
        {"object": "apple", "position": [0.47, 0.2, 0.02]},
    ],
}


def _lunch_scene(objects: dict[str, list[float]]) -> Any:
    return scene_from_document(
        {
            "format": "demoplan/scene-1",
            "objects": {name: {"position": xyz} for name, xyz in objects.items()},
            "landmarks": {"lunchbox": {"position": [0.4, 0.2, 0], "yaw": 30}},
        },
        "lunch.json",
    )


def test_a_misspelt_scene_object_is_the_field_and_the_model_s_name_the_suggestion() -> None:
    """The issue's lunch box: the scene names 'sandwhich', the model 'sandwich'.
    The suggestion is the model's name (the scene's own is not echoed back),
    the field the scene's misspelt object, and the lunch box no object."""
    model = learn(demonstrations_from_document(LUNCH, "lunch-demo.json"))
    scene = _lunch_scene({"sandwhich": [0.1, -0.3], "apple": [0.3, -0.3]})
    with pytest.raises(InputError) as raised:
        check_scene_objects(model, scene)
    line = str(raised.value)
    assert line.startswith("lunch.json: objects.sandwhich: the task model needs sandwich")
    assert line.endswith("did you mean 'sandwich'?"), line
    assert "did you mean 'sandwhich'" not in line
    assert "expected objects ['apple', 'sandwich'] (landmarks: lunchbox)" in line


def test_the_unknown_object_message_lists_the_landmark_apart() -> None:
    model = learn(demonstrations_from_document(LUNCH, "lunch-demo.json"))
    scene = _lunch_scene({"sandwich": [0.1, -0.3], "apple": [0.3, -0.3], "napkin": [0.5, -0.3]})
    with pytest.raises(InputError) as raised:
        check_scene_objects(model, scene)
    line = str(raised.value)
    assert "never saw napkin; expected only objects of the demonstrations " in line
    assert "['apple', 'sandwich'] (landmarks: lunchbox)" in line, line
    check_scene_objects(model, scene, clutter=True)  # an object with no goal


def test_the_model_s_landmark_among_the_scene_s_objects_is_refused() -> None:
    model = learn(demonstrations_from_document(LUNCH, "lunch-demo.json"))
    document = {
        "format": "demoplan/scene-1",
        "objects": {
            "sandwich": {"position": [0.1, -0.3]},
            "apple": {"position": [0.3, -0.3]},
            "lunchbox": {"position": [0.4, 0.2, 0], "size": [0.26, 0.18, 0.02]},
        },
    }
    with pytest.raises(InputError) as raised:
        check_scene_objects(model, scene_from_document(document, "lunch.json"), clutter=True)
    assert str(raised.value).startswith(
        "lunch.json: objects.lunchbox: 'lunchbox' is a landmark of the task model"
    )
