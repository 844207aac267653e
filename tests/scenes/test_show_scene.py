"""``demoplan show SCENE``: a scene looked at before planning — where objects
stand, what stands on what, which grasps the neighbours block, free space —
checked against hand-computed geometry and against what the planner does."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.scenes.preview import preview_scene
from demoplan.scenes.scene import scene_from_document
from tests.support.cli import exit_and_output as invoke
from tests.support.helpers import EXAMPLES, write

PYRAMID = EXAMPLES / "scenes" / "pyramid-fig4.json"
BLOCK = 0.04


def blocks_scene(positions: list[tuple[float, float]]) -> dict[str, Any]:
    return {
        "format": "demoplan/scene-1",
        "objects": {
            f"b{k}": {"position": [x, y, 0.0], "yaw": 0, "size": [BLOCK, BLOCK, BLOCK]}
            for k, (x, y) in enumerate(positions)
        },
        "freespace": [[1.0, 1.0]],
    }


def test_the_fig4_scene_shows_red_on_top_blocking_the_two_under_it(tmp_path: Path) -> None:
    code, out, err = invoke("show", PYRAMID, "--json", "--plot", tmp_path / "scene.png")
    assert code == 0, err
    shown = json.loads(out)["objects"]
    assert shown["red"]["on"] == ["green", "wood"]
    assert shown["wood"]["on"] == shown["green"]["on"] == []
    for under in ("wood", "green"):  # nothing under red can be lifted
        assert all("red" in g["blocked_by"] for g in shown[under]["grasps"])
    assert all(not g["blocked_by"] for g in shown["red"]["grasps"])
    assert (tmp_path / "scene.png").read_bytes().startswith(b"\x89PNG")
    assert "wrote" in err
    # The planner agrees: its first move lifts red, the only graspable block.
    code, out, err = invoke("learn", EXAMPLES / "blocks", "--paper", "-o", tmp_path / "m.json")
    assert code == 0, err
    code, out, err = invoke("plan", tmp_path / "m.json", PYRAMID, "--json")
    assert code == 0, err
    assert json.loads(out)["actions"][0][:2] == ["GRASP", "red"]


def test_the_table_names_the_blocked_grasps_and_the_generated_free_space() -> None:
    code, out, err = invoke("show", PYRAMID)
    assert code == 0, err
    assert "wood" in out and "0°: green, red; 90°: red" in out
    assert "Free space, generated near the objects (the scene lists none; " in out
    assert ": 3 spots: " in out
    assert "Cannot be grasped where they stand: wood, green" in out


@settings(max_examples=40, deadline=None)
@given(
    gap=st.floats(min_value=0.0, max_value=0.2),
    vertical=st.booleans(),
)
def test_two_blocks_side_by_side_block_only_the_grasp_across_them(
    gap: float, vertical: bool
) -> None:
    """Paper §V.B: the fingers stand block/2 + g_r = 4 cm from the centre along
    the grasp axis, discs of g_r = 2 cm. A neighbour at distance d along x is
    hit by the x grasp when |d − 4 cm| < r + g_r = 4 cm, i.e. d < 8 cm; the
    grasp across (y) never reaches it."""
    distance = BLOCK + gap
    second = (0.5, 0.5 + distance) if vertical else (0.5 + distance, 0.5)
    preview = preview_scene(scene_from_document(blocks_scene([(0.5, 0.5), second]), "generated"))
    along, across = (90.0, 0.0) if vertical else (0.0, 90.0)
    for obj, other in ((preview.objects[0], "b1"), (preview.objects[1], "b0")):
        axes = {g.axis: g.blocked_by for g in obj.grasps}
        expected = (other,) if distance < 2 * BLOCK - 1e-9 else ()
        if abs(distance - 2 * BLOCK) > 1e-6:  # not on the boundary itself
            assert axes[along] == expected
        assert axes[across] == ()
        assert obj.on == ()


def test_a_model_is_still_shown_as_the_papers_tables(tmp_path: Path) -> None:
    model = tmp_path / "m.json"
    code, _, err = invoke("learn", EXAMPLES / "blocks", "--paper", "-o", model)
    assert code == 0, err
    code, out, err = invoke("show", model)
    assert code == 0, err
    assert "State" in out
    # Its plot: the demonstrations, each step marked with its state (Fig. 3).
    code, out, err = invoke("show", model, "--plot", tmp_path / "x.png")
    assert code == 0, err
    assert (tmp_path / "x.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, out, err = invoke("show", model, "--model", model)
    assert code == 1
    assert err.count("\n") == 1 and "--model is for a scene" in err


def test_a_file_of_neither_kind_is_one_line_naming_both(tmp_path: Path) -> None:
    other = write(tmp_path / "d.json", {"format": "demoplan/demonstrations-1"})
    code, _, err = invoke("show", other)
    assert code == 1
    assert err.count("\n") == 1
    expected = "'demoplan/model-1' or 'demoplan/objects-1' or 'demoplan/scene-1'"
    assert expected in err and "format" in err


def test_sizes_the_scene_omits_come_from_the_model(tmp_path: Path) -> None:
    scene = json.loads(PYRAMID.read_text())
    for entry in scene["objects"].values():
        del entry["size"]
    path = write(tmp_path / "no-sizes.json", scene)
    code, _, err = invoke("show", path)
    assert code == 1 and "size" in err
    model = tmp_path / "m.json"
    assert invoke("learn", EXAMPLES / "blocks", "--paper", "-o", model)[0] == 0
    code, out, err = invoke("show", path, "--model", model, "--json")
    assert code == 0, err
    assert json.loads(out)["objects"]["red"]["size"] == [BLOCK, BLOCK, BLOCK]


def test_an_object_on_a_landmark_stands_on_it_and_the_landmark_shows_its_turn_and_size(
    tmp_path: Path,
) -> None:
    """A sandwich on the lunch box's top stands on the box, not on the table;
    the box is shown turned, with its shape (docs/tutorial.md: show tells what
    each object stands on)."""
    box = {"position": [0.35, 0.25, 0], "yaw": 30, "shape": "box", "size": [0.26, 0.18, 0.02]}
    scene = {
        "format": "demoplan/scene-1",
        "objects": {
            "sandwich": {"position": [0.35, 0.25, 0.02], "size": [0.1, 0.1, 0.03]},
            "apple": {"position": [0.1, -0.3, 0], "size": [0.07, 0.07, 0.07]},
        },
        "landmarks": {"lunchbox": box},
    }
    stands = {o.name: o.on for o in preview_scene(scene_from_document(scene, "s.json")).objects}
    assert stands == {"sandwich": ("lunchbox",), "apple": ()}
    code, out, _ = invoke("show", write(tmp_path / "s.json", scene))
    assert code == 0
    assert "Landmark lunchbox at (0.35, 0.25, 0.00), turned 30°, box 0.26 × 0.18 × 0.02" in out
    assert any("sandwich" in line and "lunchbox" in line for line in out.splitlines())
