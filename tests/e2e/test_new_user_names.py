"""A newcomer's typo in a scene is named with the name meant: two letters
swapped in a short name (``mgu`` for ``mug``) is one slip of the hand, as
near as a letter left out, though difflib's ratio for it is only 2/3."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from demoplan.documents.demonstrations import demonstrations_from_document
from demoplan.errors import InputError
from demoplan.learning import learn
from demoplan.scenes.scene import scene_from_document
from demoplan.scenes.targets import check_scene_objects
from demoplan.wording import did_you_mean

NAMES = st.text(alphabet="abcdefghijklmnopqrstuvwxyz_", min_size=3, max_size=12)


@given(NAMES, st.data())
def test_two_neighbouring_letters_swapped_name_the_name_meant(
    name: str, data: st.DataObject
) -> None:
    at = data.draw(st.integers(0, len(name) - 2))
    typo = name[:at] + name[at + 1] + name[at] + name[at + 2 :]
    if typo != name:
        assert did_you_mean(typo, [name, "0123456789"]) == f"; did you mean {name!r}?"


@pytest.mark.parametrize(
    ("name", "known", "expected"),
    [
        ("mgu", ["mug", "plate"], "; did you mean 'mug'?"),
        ("Mgu", ["mug", "plate"], "; did you mean 'mug'?"),
        ("cpu", ["cup"], "; did you mean 'cup'?"),
        ("knife", ["tray", "plate"], ""),
        ("gum", ["mug"], ""),  # a word read backwards is not a slip of the hand
    ],
)
def test_near_names(name: str, known: list[str], expected: str) -> None:
    assert did_you_mean(name, known) == expected


def test_a_scene_with_a_swapped_letter_names_the_field_and_the_object_meant() -> None:
    demonstration = {
        "objects": {"mug": {"size": [0.08, 0.08, 0.1]}, "plate": {"size": [0.16, 0.16, 0.015]}},
        "initial": {"mug": {"position": [0.1, 0.1]}, "plate": {"position": [0.3, 0.1]}},
    }
    demonstrations = [
        {
            **demonstration,
            "name": f"d{k}",
            "steps": [
                {"object": "plate", "position": [0.5, 0.2 + dy, 0.0]},
                {"object": "mug", "position": [0.5, 0.2 + dy, 0.015]},
            ],
        }
        for k, dy in enumerate((0.0, 0.001, -0.001))
    ]
    model = learn(
        [
            d
            for document in demonstrations
            for d in demonstrations_from_document(
                {"format": "demoplan/demonstration-1", **document}, "demo.json"
            )
        ]
    )
    scene = scene_from_document(
        {
            "format": "demoplan/scene-1",
            "objects": {
                "mgu": {"position": [0.1, 0.1, 0.0], "size": [0.08, 0.08, 0.1]},
                "plate": {"position": [0.3, 0.1, 0.0], "size": [0.16, 0.16, 0.015]},
            },
        },
        "scene.json",
    )
    with pytest.raises(InputError) as error:
        check_scene_objects(model, scene)
    assert error.value.field == "objects.mgu"
    assert str(error.value).endswith("did you mean 'mug'?")
