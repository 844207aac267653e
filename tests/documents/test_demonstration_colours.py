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
from tests.support.lunch_box import BLUE, GREEN, coloured_document, lunch_demonstrations

matplotlib.use("Agg")


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


def test_a_scene_draws_identical_objects_in_the_colours_taught_for_them() -> None:
    """Instances of a type given colours (a red and a blue plate, each filling
    either role in turn) keep them in a scene naming those instances: the
    model's demonstrations name roles (``plate#1``), a scene names instances."""
    from demoplan.scenes.landmarks import complete_scene
    from demoplan.scenes.scene import load_scene

    identical = Path(__file__).parents[2] / "examples" / "identical"
    document = json.loads((identical / "table-for-two.json").read_text())
    colours = {"plate-a": "#ff0000", "plate-b": BLUE}
    for demonstration in document["demonstrations"]:
        for name, colour in colours.items():
            demonstration["objects"][name]["colour"] = colour
    model = learn(demonstrations_from_document(document, "table-for-two.json"))
    assert {instance for role in model.roles for instance in role.instances} >= set(colours)
    assert any(len(set(role.instances)) > 1 for role in model.roles if role.type == "plate")
    scene = complete_scene(load_scene(identical / "table-scene.json"), model)
    assert {n: c for n, c in scene.given_colours.items() if n.startswith("plate")} == colours


def test_a_landmarks_colour_stands_once_where_its_size_stands_under_objects() -> None:
    """A landmark whose size stands under ``objects`` (as ``import`` writes it)
    may give its colour there too: read as the landmark's, written back under
    ``landmarks`` and read again as the same demonstration; given in both
    places, one line naming the landmark's field, as for its size."""
    document = coloured(lunch_demonstrations()[0], sandwich=BLUE)
    objects = document["objects"]
    assert "size" in objects["lunchbox"]  # where demonstration_to_dict writes it
    document["objects"] = {"lunchbox": {**objects.pop("lunchbox"), "colour": GREEN}, **objects}
    demo = read(document)
    assert demo.given_colours == {"sandwich": BLUE, "lunchbox": GREEN}
    written = demonstration_to_dict(demo)
    assert written["landmarks"]["lunchbox"]["colour"] == GREEN
    assert read(json.loads(json.dumps(written))) == demo
    document["landmarks"]["lunchbox"]["colour"] = GREEN
    with pytest.raises(InputError) as caught:
        read(document, "lunch.json")
    assert str(caught.value).startswith("lunch.json: landmarks.lunchbox.colour: ")


def test_demonstrations_giving_one_thing_two_colours_are_learned_with_a_warning(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Each demonstration's figure draws its own colours, a scene naming none
    takes the first's, and learning says so once per thing (a colour changes
    no plan: not refused, as a second size is)."""
    demos = lunch_demonstrations()
    blue, green = coloured(demos[0], sandwich=BLUE), coloured(demos[1], sandwich=GREEN)
    same = coloured(demos[2], sandwich=BLUE, lunchbox=GREEN)
    with caplog.at_level("WARNING"):
        model = learn([read(blue, "one.json"), read(green, "two.json"), read(same, "three.json")])
    lines = [r.getMessage() for r in caplog.records if "colour" in r.getMessage()]
    assert lines == [
        f"two.json: objects.sandwich.colour: {GREEN} here and {BLUE} in one.json; "
        f"a scene naming no colour for it draws it in {BLUE}"
    ]
    assert [d.given_colours.get("sandwich") for d in model.demonstrations] == [BLUE, GREEN, BLUE]


def test_the_models_figure_draws_a_thing_in_one_colour_where_one_demonstration_gives_it(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """``show --plot``'s panels: a demonstration giving the sandwich no colour
    draws it in the colour another gives (as plan and run draw it), not in the
    palette's."""
    from matplotlib.figure import Figure

    from demoplan.plotting import figures

    demos = lunch_demonstrations()
    model = learn([read(coloured(demos[0], sandwich=BLUE)), *demos[1:]])
    assert [d.given_colours for d in model.demonstrations] == [{"sandwich": BLUE}, {}, {}]
    drawn: list[Figure] = []
    monkeypatch.setattr(figures, "save_figure", lambda figure, _: drawn.append(figure))
    figures.save_demonstrations(model, tmp_path / "model.png", "lunch")
    (figure,) = drawn
    panels = figure.axes[0::2]  # each demonstration above its constraints
    assert len(panels) == len(demos)
    for panel in panels:
        assert BLUE in {to_hex(p.get_facecolor(), keep_alpha=False) for p in panel.patches}
