"""An object's colour, where its scene file gives one (the studio's *Save scene*
writes the colour a user chose), is what every renderer draws: the kinematic
frames and storyboard, the figures, MuJoCo's bodies (``--sim mujoco`` and
``arm``) and the studio's layout; a file without colours still reads, in the
palette of :mod:`demoplan.plotting.colours`."""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.commands.execution import run
from demoplan.errors import InputError
from demoplan.learning import learn
from demoplan.model import TaskModel
from demoplan.plotting.colours import assign_colours, object_colour
from demoplan.scenes.scene import Scene, load_scene, scene_from_document, scene_to_dict
from tests.support.lunch_box import BLUE, GREEN, coloured_document, lunch_demonstrations

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def lunch_model() -> TaskModel:
    return learn(lunch_demonstrations())


def hex_of(rgb: tuple[float, float, float]) -> str:
    return "#" + "".join(f"{round(v * 255):02x}" for v in rgb)


# --- the scene file ----------------------------------------------------------


channel = st.floats(0.0, 1.0, allow_nan=False)


@settings(max_examples=40, deadline=None)
@given(
    rgb=st.tuples(channel, channel, channel),
    hex_digits=st.text("0123456789abcdefABCDEF", min_size=6, max_size=6),
)
def test_a_colour_reads_in_either_form_and_is_written_back_as_rrggbb(
    rgb: tuple[float, float, float], hex_digits: str
) -> None:
    document = coloured_document(sandwich=list(rgb), lunchbox=f"#{hex_digits}")
    scene = scene_from_document(document, "scene.json")
    expected = {"sandwich": hex_of(rgb), "lunchbox": f"#{hex_digits.lower()}"}
    assert scene.given_colours == expected
    written = scene_to_dict(scene)
    assert written["objects"]["sandwich"]["colour"] == expected["sandwich"]
    assert written["landmarks"]["lunchbox"]["colour"] == expected["lunchbox"]
    assert "colour" not in written["objects"]["apple"]
    assert scene_from_document(written, "again.json").given_colours == expected


@pytest.mark.parametrize(
    ("group", "name", "value"),
    [
        ("objects", "sandwich", "red"),
        ("objects", "sandwich", "#d6272"),
        ("objects", "sandwich", "#gg2728"),
        ("objects", "sandwich", "#d62728\n"),  # `$` alone matches before a last newline
        ("objects", "sandwich", "#fff"),
        ("objects", "apple", [1.2, 0.0, 0.0]),
        ("objects", "apple", [0.5, 0.5]),
        ("objects", "apple", [214, 39, 40]),
        ("objects", "apple", [True, False, False]),
        ("objects", "apple", [10**400, 0, 0]),  # a JSON integer no float holds
        ("landmarks", "lunchbox", 7),
        ("landmarks", "lunchbox", "#d62728\n"),
    ],
)
def test_a_bad_colour_is_one_line_naming_the_file_and_the_field(
    tmp_path: Path, group: str, name: str, value: Any
) -> None:
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(coloured_document(**{name: value})))
    with pytest.raises(InputError) as error:
        load_scene(path)
    line = str(error.value)
    assert "\n" not in line
    assert str(path) in line and f"{group}.{name}.colour" in line
    assert '"#rrggbb" or [r, g, b] with each in 0–1 expected' in line


def test_a_scene_without_colours_reads_in_the_palette() -> None:
    scene = scene_from_document(coloured_document(), "old.json")
    assert scene.colours == ()
    assert assign_colours(scene.names, scene.given_colours) == assign_colours(scene.names)
    assert "colour" not in json.dumps(scene_to_dict(scene))


def test_a_given_colour_is_the_objects_and_is_forgotten_where_none_is_given() -> None:
    """One place decides: a given colour wins over the name's own (``red``) and
    the palette; the next task of the same names without it gets the palette's."""
    palette = assign_colours(["sandwich", "red"])
    given = assign_colours(["sandwich", "red"], {"sandwich": BLUE, "red": "#00FF00"})
    assert given == {"sandwich": BLUE, "red": "#00ff00"}
    assert object_colour("sandwich") == BLUE and object_colour("red") == "#00ff00"
    assert assign_colours(["sandwich", "red"]) == palette
    assert object_colour("sandwich") == palette["sandwich"] != BLUE


# --- the renderers -----------------------------------------------------------


def near(image: np.ndarray, colour: str, alpha: float, tolerance: int = 6) -> int:
    """Pixels of ``image`` (RGB or RGBA, 0–255) within ``tolerance`` of
    ``colour`` drawn at ``alpha`` over white."""
    rgb = np.array([int(colour[k : k + 2], 16) for k in (1, 3, 5)], dtype=float)
    blended = alpha * rgb + (1 - alpha) * 255
    pixels = image[..., :3].astype(float)
    return int((np.abs(pixels - blended).max(axis=-1) <= tolerance).sum())


def test_kinematic_frames_and_storyboard_draw_the_given_colours(
    lunch_model: TaskModel, tmp_path: Path
) -> None:
    import matplotlib.image as mpimg

    scene = scene_from_document(coloured_document(sandwich=BLUE, lunchbox=GREEN), "scene.json")
    palette = assign_colours(scene.names)["sandwich"]
    assert palette != BLUE
    report = run(lunch_model, scene, frames=tmp_path)
    assert report.success
    start = mpimg.imread(tmp_path / "frame-0000.png") * 255
    board = mpimg.imread(tmp_path / "storyboard.png") * 255
    for image in (start, board):
        # the sandwich (10 × 10 cm, alpha 0.85) in the user's red, never the palette's
        assert near(image, BLUE, 0.85) > 200
        assert near(image, palette, 0.85) == 0
        # the lunch box (alpha 0.6, hatched) in the user's green, not sand
        assert near(image, GREEN, 0.6) > 200
    # no sandy lunch box (a few pixels of other blends may come near it)
    assert near(start, "#d9c9a8", 0.6) < near(start, GREEN, 0.6) / 50


def test_plan_figures_draw_the_given_colours(lunch_model: TaskModel) -> None:
    pytest.importorskip("matplotlib")
    from matplotlib.colors import to_hex

    from demoplan.commands.planning import plan
    from demoplan.plotting.backend import use_agg
    from demoplan.plotting.figures import plot_scene_plan

    use_agg()
    scene = scene_from_document(coloured_document(sandwich=BLUE, lunchbox=GREEN), "scene.json")
    result = plan(lunch_model, scene, timeout=None)
    assert result.scene.given_colours == {"sandwich": BLUE, "lunchbox": GREEN}  # kept on the way
    ax = plot_scene_plan(result.scene, result.chosen.problem, result.chosen.plan)
    faces = {to_hex(p.get_facecolor()) for p in ax.patches}
    assert BLUE in faces and GREEN in faces
    assert assign_colours(scene.names)["sandwich"] not in faces


os.environ.setdefault("MUJOCO_GL", "egl")


def body_colours(xml: str) -> dict[str, str]:
    """Each body's geom colour in an MJCF document, as ``#rrggbb``."""
    colours = {}
    for body in ET.fromstring(xml).iter("body"):
        geom = body.find("geom")
        if geom is not None and geom.get("rgba"):
            red, green, blue, _ = (float(v) for v in geom.get("rgba", "").split())
            colours[body.get("name", "")] = hex_of((red, green, blue))
    return colours


def test_mujoco_bodies_have_the_given_colours() -> None:
    """The simulator of ``--sim mujoco`` and ``arm`` (the arm adds itself to
    this same document) colours each body as the scene file says."""
    from demoplan.execution.physics import scene_xml

    scene = scene_from_document(coloured_document(sandwich=BLUE, lunchbox=GREEN), "scene.json")
    colours = body_colours(scene_xml(scene))
    index = scene.names.index("sandwich")
    assert colours[f"_object{index}"] == BLUE
    assert colours["_landmark0"] == GREEN
    plain = scene_from_document(coloured_document(), "scene.json")
    palette = body_colours(scene_xml(plain))
    assert palette[f"_object{index}"] == assign_colours(plain.names)["sandwich"] != BLUE
    assert palette["_landmark0"] != GREEN
    for name in scene.names:  # the others keep the palette's
        if name != "sandwich":
            k = scene.names.index(name)
            assert colours[f"_object{k}"] == palette[f"_object{k}"]


def test_mujoco_renders_the_given_colour(lunch_model: TaskModel) -> None:
    """MuJoCo's own picture (from straight above) shows the sandwich in the
    user's blue: its pixels' hue is blue's, not the palette's."""
    pytest.importorskip("mujoco")
    from demoplan.execution.physics import MujocoWorld
    from demoplan.scenes.scene import complete_geometry

    def hue_at_sandwich(scene: Scene) -> np.ndarray:
        world = MujocoWorld(complete_geometry(scene, lunch_model))
        image = world.top_image()
        x, y, _ = scene.object("sandwich").pose.position
        u, v = world.top_camera.to_pixels(x, y)
        patch = image[int(v) - 10 : int(v) + 10, int(u) - 10 : int(u) + 10, :3].astype(float)
        mean: np.ndarray = patch.reshape(-1, 3).mean(axis=0)
        return mean / mean.max()  # the colour, whatever the light

    def normalised(colour: str) -> np.ndarray:
        rgb = np.array([int(colour[k : k + 2], 16) for k in (1, 3, 5)], dtype=float)
        return rgb / rgb.max()

    coloured = scene_from_document(coloured_document(sandwich=BLUE), "scene.json")
    palette = assign_colours(coloured.names)["sandwich"]
    seen = hue_at_sandwich(coloured)
    assert np.abs(seen - normalised(BLUE)).max() < 0.15
    assert np.abs(seen - normalised(palette)).max() > 0.3
    plain = hue_at_sandwich(scene_from_document(coloured_document(), "scene.json"))
    assert np.abs(plain - normalised(palette)).max() < 0.15


def test_camera_perception_refuses_a_block_given_another_colour_than_its_type() -> None:
    """``--perception camera`` names blocks by the colour their type names: a red
    block the scene paints blue would be seen as a blue one, so it is refused
    in one line before the run (exit 2); painted its own red, it is accepted."""
    pytest.importorskip("mujoco")
    from demoplan.errors import UsageError
    from demoplan.execution.camera_world import CameraWorld
    from demoplan.execution.physics import MujocoWorld
    from demoplan.plotting.colours import NAMED

    document = json.loads((ROOT / "examples" / "scenes" / "pyramid-fig4.json").read_text())
    document["objects"]["red"]["colour"] = BLUE
    scene = scene_from_document(document, "pyramid.json")
    with pytest.raises(UsageError) as error:
        CameraWorld(MujocoWorld(scene), scene)
    assert error.value.exit_code == 2 and "\n" not in str(error.value)
    # the file, the field, the colour given and the one expected
    assert str(error.value).startswith(f"pyramid.json: objects.red.colour: {BLUE} ")
    assert f"type red's ({NAMED['red']})" in str(error.value)
    document["objects"]["red"]["colour"] = NAMED["red"].upper()
    same = scene_from_document(document, "pyramid.json")
    assert CameraWorld(MujocoWorld(same), same).world.scene.given_colours == {"red": NAMED["red"]}
