"""A demonstration file's colours (docs/formats.md, ``colour`` on an object or a
landmark — the studio's Teach view writes the colours a user chose): read as
``#rrggbb``, written back, kept in the model learned from it, drawn by the
demonstration's figure and by the studio's layout of it; a bad colour is one
line naming its field; a file without colours reads as before, in the palette."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import matplotlib
import pytest
from matplotlib.colors import to_hex

from demoplan.documents.demonstrations import (
    demonstration_to_dict,
    demonstrations_from_document,
    load_demonstrations,
)
from demoplan.errors import InputError
from demoplan.learning import learn
from demoplan.learning.modelfile import load_model, save_model
from demoplan.model import Demonstration
from demoplan.plotting.colours import assign_colours
from demoplan.plotting.figures import plot_demonstration
from demoplan.scenes.scene import scene_from_document
from demoplan.studio.layouts import layout_of_demonstration
from tests.support.lunch_box import lunch_demonstrations

matplotlib.use("Agg")

BLUE = "#1f5fbf"  # the user's blue sandwich; the palette gives it another colour
GREEN = "#27ae60"  # the user's green lunch box (a landmark)


def coloured(demo: Demonstration, **colours: Any) -> dict[str, Any]:
    """``demo``'s file, the things named in ``colours`` given that ``colour``."""
    document = demonstration_to_dict(demo)
    landmarks = document.get("landmarks", {})
    for name, colour in colours.items():  # a landmark's size stands under objects
        (landmarks if name in landmarks else document["objects"])[name]["colour"] = colour
    return document


def read(document: dict[str, Any], source: str = "demo.json") -> Demonstration:
    (demo,) = demonstrations_from_document(document, source)
    return demo


def test_the_palette_differs_from_the_users_colours() -> None:
    """The test's colours are not what the palette would draw anyway."""
    palette = assign_colours(["sandwich", "apple", "juice", "carrot", "cookie", "lunchbox"])
    assert palette["sandwich"] != BLUE
    assert GREEN not in palette.values()


def test_a_demonstrations_colours_are_read_and_written_back() -> None:
    demo = read(
        coloured(lunch_demonstrations()[0], sandwich=BLUE.upper(), lunchbox=[0.0, 0.2, 1.0])
    )
    assert demo.given_colours == {"sandwich": BLUE, "lunchbox": "#0033ff"}
    again = read(json.loads(json.dumps(demonstration_to_dict(demo))))
    assert again == demo
    assert again.given_colours == demo.given_colours
    written = demonstration_to_dict(demo)
    assert written["objects"]["sandwich"]["colour"] == BLUE
    assert written["landmarks"]["lunchbox"]["colour"] == "#0033ff"
    assert "colour" not in written["objects"]["apple"]


def test_a_file_without_colours_reads_without_them() -> None:
    demo = read(demonstration_to_dict(lunch_demonstrations()[0]))
    assert demo.given_colours == {}
    assert "colour" not in json.dumps(demonstration_to_dict(demo))


@pytest.mark.parametrize(
    ("value", "field"),
    [
        ("blue", "objects.sandwich.colour"),
        ([0.1, 2.0, 0.3], "objects.sandwich.colour"),
        (["a", "b", "c"], "objects.sandwich.colour"),
        ("#12345", "landmarks.lunchbox.colour"),
    ],
)
def test_a_bad_colour_is_one_line_naming_its_field(value: Any, field: str) -> None:
    name = field.split(".")[1]
    document = coloured(lunch_demonstrations()[0], **{name: value})
    with pytest.raises(InputError) as caught:
        read(document, "lunch.json")
    message = str(caught.value)
    assert "\n" not in message
    assert "lunch.json" in message and field in message
    assert "#rrggbb" in message


def test_the_model_keeps_the_demonstrations_colours(tmp_path: Path) -> None:
    files = []
    for index, demo in enumerate(lunch_demonstrations()):
        path = tmp_path / f"lunch-{index + 1}.json"
        path.write_text(json.dumps(coloured(demo, sandwich=BLUE, lunchbox=GREEN)))
        files.append(path)
    model = learn(load_demonstrations(files))
    save_model(model, tmp_path / "model.json")
    loaded = load_model(tmp_path / "model.json")
    assert [d.given_colours for d in loaded.demonstrations] == [
        {"sandwich": BLUE, "lunchbox": GREEN}
    ] * 3


def test_the_demonstrations_figure_draws_its_colours() -> None:
    demo = read(coloured(lunch_demonstrations()[0], sandwich=BLUE, lunchbox=GREEN))
    ax = plot_demonstration(demo)
    faces = {to_hex(patch.get_facecolor(), keep_alpha=False) for patch in ax.patches}
    assert {BLUE, GREEN} <= faces
    plain = plot_demonstration(read(demonstration_to_dict(lunch_demonstrations()[0])))
    assert not {BLUE, GREEN} & {to_hex(p.get_facecolor(), keep_alpha=False) for p in plain.patches}


def test_the_studio_lays_a_demonstration_out_in_its_colours() -> None:
    demo = read(coloured(lunch_demonstrations()[0], sandwich=BLUE, lunchbox=GREEN))
    layout = layout_of_demonstration(demo)
    assert layout["objects"]["sandwich"]["colour"] == BLUE
    assert layout["landmarks"]["lunchbox"]["colour"] == GREEN
    assert layout["objects"]["apple"]["colour"] not in {BLUE, GREEN}


def test_a_scene_naming_no_colours_is_drawn_in_the_taught_ones(tmp_path: Path) -> None:
    """The colours taught stay the things' colours where a scene names none (a
    scene's own colour wins): the prepared scene every renderer reads has them,
    and the plan's figure draws them."""
    from demoplan.commands.planning import plan
    from demoplan.plotting.figures import plot_scene_plan
    from tests.execution.test_colours import coloured_document

    model = learn(
        [read(coloured(d, sandwich=BLUE, lunchbox=GREEN)) for d in lunch_demonstrations()]
    )
    plain = plan(model, scene_from_document(coloured_document(), "scene.json"), timeout=None)
    assert plain.scene.given_colours == {"sandwich": BLUE, "lunchbox": GREEN}
    ax = plot_scene_plan(plain.scene, plain.chosen.problem, plain.chosen.plan)
    assert {BLUE, GREEN} <= {to_hex(p.get_facecolor(), keep_alpha=False) for p in ax.patches}
    own = scene_from_document(coloured_document(sandwich="#ff8800"), "own.json")
    assert plan(model, own, timeout=None).scene.given_colours == {
        "sandwich": "#ff8800",
        "lunchbox": GREEN,
    }
