"""Objects' masses: ``mass`` (kg) or ``density`` (kg/m³) in scene and
demonstration files, checked for a plausible solid, solid wood by default."""

from __future__ import annotations

import math
from typing import Any

import pytest

from demoplan.documents.demonstrations import (
    demonstration_to_dict,
    demonstrations_from_document,
)
from demoplan.errors import InputError
from demoplan.model import WOOD_DENSITY
from demoplan.scenes.scene import scene_from_document


def _scene(objects: dict[str, Any]) -> dict[str, Any]:
    return {"format": "demoplan/scene-1", "objects": objects}


BOWL = {"position": [0.4, 0.0, 0.0], "shape": "cylinder", "size": [0.15, 0.15, 0.07]}


def test_mass_density_and_the_wooden_default() -> None:
    """A mass as given; a density times the solid's volume; neither: wood
    (a 4 cm block in centimetres weighs 38.4 g)."""
    bowl = scene_from_document(_scene({"bowl": {**BOWL, "mass": 0.4}}), "s").objects[0].geometry
    assert bowl is not None and bowl.kg == 0.4
    cup = scene_from_document(_scene({"c": {**BOWL, "density": 250}}), "s").objects[0].geometry
    assert cup is not None and cup.kg == pytest.approx(250 * math.pi * 0.075**2 * 0.07)
    block = (
        scene_from_document(
            _scene({"block": {"position": [20, 0], "size": [4, 4, 4]}})
            | {"units": {"length": "cm"}},
            "s",
        )
        .objects[0]
        .geometry
    )
    assert block is not None and block.mass is None
    assert block.kg == pytest.approx(WOOD_DENSITY * 0.04**3) == pytest.approx(0.0384)


@pytest.mark.parametrize(
    ("extra", "field", "words"),
    [
        ({"mass": 4000}, "objects.bowl.mass", "between 1.2 (air) and 22600 (osmium)"),
        ({"mass": 1e-6}, "objects.bowl.mass", "mean density"),
        ({"density": 1e6}, "objects.bowl.density", "kg/m³"),
        ({"mass": -1}, "objects.bowl.mass", "greater than 0"),
        ({"mass": 0.4, "density": 300}, "objects.bowl", 'both "mass" and "density"'),
    ],
)
def test_absurd_masses_are_refused_in_one_line_naming_the_field(
    extra: dict[str, float], field: str, words: str
) -> None:
    with pytest.raises(InputError) as caught:
        scene_from_document(_scene({"bowl": {**BOWL, **extra}}), "s.json")
    assert caught.value.field == field and words in caught.value.message
    assert "\n" not in str(caught.value)


def test_a_mass_without_a_size_is_refused() -> None:
    with pytest.raises(InputError, match='no "size"') as caught:
        scene_from_document(_scene({"bowl": {"position": [0.4, 0.0], "mass": 0.4}}), "s")
    assert caught.value.field == "objects.bowl.mass"


def test_demonstrations_carry_masses_and_write_them_back() -> None:
    document = {
        "format": "demoplan/demonstration-1",
        "objects": {"bowl": {"shape": "cylinder", "size": [0.15, 0.15, 0.07], "mass": 0.4}},
        "steps": [{"object": "bowl", "position": [0.4, 0.1, 0.0]}],
    }
    (demo,) = demonstrations_from_document(document, "d.json")
    assert dict(demo.objects)["bowl"].kg == 0.4
    assert demonstration_to_dict(demo)["objects"]["bowl"]["mass"] == 0.4
    document["objects"]["bowl"]["density"] = 100  # type: ignore[index]
    with pytest.raises(InputError, match="both"):
        demonstrations_from_document(document, "d.json")
