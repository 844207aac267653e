"""Names as the user gave them, and "did you mean" for every unknown one."""

from __future__ import annotations

import pytest

from demoplan.errors import InputError
from demoplan.learning import learn
from demoplan.scenes.scene import scene_from_document
from demoplan.scenes.targets import check_scene_objects
from demoplan.wording import did_you_mean
from tests.helpers import paper_model


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
    with pytest.raises(InputError, match=r"lacks; .*did you mean 'Wood'\?"):
        check_scene_objects(model, scene)
