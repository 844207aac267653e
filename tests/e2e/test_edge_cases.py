"""Edge cases found in review: hostile or unusual input gets a one-line error or works."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from demoplan.perception.blocks import detect_blocks
from demoplan.perception.camera import Camera, load_image, save_image
from demoplan.perception.synthetic import SyntheticBlock, render_blocks
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES

SCENE = EXAMPLES / "scenes" / "pyramid-fig4.json"
CAMERA = Camera(1000.0, (0.0, 0.0))


@pytest.fixture(scope="module")
def model_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("m") / "blocks.json"
    blocks = EXAMPLES / "blocks" / "demonstrations.json"
    assert invoke("learn", blocks, "-o", path, "--paper").exit_code == 0  # Table IV
    return path


def scene_with(tmp_path: Path, change: Any) -> Path:
    data = json.loads(SCENE.read_text())
    change(data)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(data))
    return path


def rename(data: dict[str, Any], old: str, new: str) -> None:
    data["objects"][new] = data["objects"].pop(old)


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        (lambda d: rename(d, "red", "my red"), "without spaces"),
        (lambda d: rename(d, "red", "loc1"), "a name demoplan gives"),
        (lambda d: d["objects"]["red"].update(position=[0.3, 0.3, -0.1]), "under the table"),
        (lambda d: d.update(freespace=[[0.1, 0.3, 0.5]]), "freespace[0]"),
    ],
)
def test_scene_names_and_heights(
    model_path: Path, tmp_path: Path, change: Any, fragment: str
) -> None:
    result = invoke("plan", model_path, scene_with(tmp_path, change))
    assert result.exit_code == 1 and fragment in result.stderr, result.stderr
    assert len(result.stderr.splitlines()) == 1


def test_free_space_on_a_huge_table(model_path: Path, tmp_path: Path) -> None:
    path = scene_with(
        tmp_path, lambda d: d.update(table={"min": [-1000, -1000], "max": [1000, 1000]})
    )
    # --timeout inf: the free space of a huge table is built and searched without a race
    assert invoke("plan", model_path, path, "--json", "--timeout", "inf").exit_code == 0


def test_a_model_with_only_the_spec_fields_plans_with_text_output(
    model_path: Path, tmp_path: Path
) -> None:
    data = json.loads(model_path.read_text())
    minimal = {k: data[k] for k in ("format", "states", "sequences", "constraints", "goals")}
    path = tmp_path / "minimal.json"
    path.write_text(json.dumps(minimal))
    scene = json.loads(SCENE.read_text())  # the sizes must come from the scene now
    for entry in scene["objects"].values():
        entry.setdefault("size", [0.04, 0.04, 0.04])
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json.dumps(scene))
    result = invoke("plan", path, scene_path)
    assert result.exit_code == 0, result.stderr
    # No names without the demonstrations: the goals are numbered from 1.
    rows = [
        line.split("│")[1].strip() for line in result.stdout.splitlines() if line.startswith("│ ")
    ]
    assert "goal of demonstration" in result.stdout and rows[:2] == ["1", "2"]


@pytest.mark.parametrize(
    ("args", "code"),
    [
        (["run", "MODEL", str(SCENE), "--seed", "-1"], 2),
        (["perceive", "IMAGE", "--px-per-m", "1e300", "--origin", "0", "0"], 2),
        (["perceive", "IMAGE", "--px-per-m", "1000", "--origin", "1e308", "0"], 2),
    ],
)
def test_out_of_range_options(model_path: Path, tmp_path: Path, args: list[str], code: int) -> None:
    image = tmp_path / "image.png"
    save_image(render_blocks([SyntheticBlock("red", 0.2, 0.2, 0, 0.04)], CAMERA), image)
    args = [str(model_path) if a == "MODEL" else str(image) if a == "IMAGE" else a for a in args]
    assert invoke(*args).exit_code == code


def test_outputs_never_overwrite_inputs(model_path: Path, tmp_path: Path) -> None:
    image = tmp_path / "image.png"
    save_image(render_blocks([SyntheticBlock("red", 0.2, 0.2, 0, 0.04)], CAMERA), image)
    before = image.read_bytes()
    result = invoke("perceive", image, "--px-per-m", "1000", "--origin", "0", "0", "-o", image)
    assert result.exit_code == 1 and image.read_bytes() == before
    model = model_path.read_bytes()
    assert invoke("problem", model_path, SCENE, "-o", model_path).exit_code == 1
    assert model_path.read_bytes() == model
    stream = tmp_path / "s.csv"
    stream.write_text("t,object,x,y,z\n0,a,0,0,0\n")
    assert invoke("segment", stream, "-o", stream).exit_code == 1
    assert stream.read_text() == "t,object,x,y,z\n0,a,0,0,0\n"


def test_an_empty_table_is_not_a_scene(tmp_path: Path) -> None:
    image = tmp_path / "empty.png"
    save_image(render_blocks([], CAMERA), image)
    result = invoke("perceive", image, "--px-per-m", "1000", "--origin", "0", "0")
    assert result.exit_code == 1 and "no blocks found" in result.stderr


def test_sixteen_bit_grey_images_are_read(tmp_path: Path) -> None:
    from PIL import Image

    rgb = render_blocks([SyntheticBlock("red", 0.2, 0.2, 10.0, 0.04)], CAMERA, noise=0)
    grey = (rgb.astype(np.uint16).mean(axis=2) * 257).astype(np.uint16)
    path = tmp_path / "grey16.png"
    Image.fromarray(grey).save(path)
    image = load_image(path)
    assert image.dtype == np.uint8 and 100 < image.mean() < 250
    (block,) = detect_blocks(image, CAMERA)
    assert abs(block.x - 0.2) < 0.001 and block.name == "grey"


def test_colours_without_a_plain_name_are_numbered_blocks() -> None:
    from demoplan.perception import synthetic

    odd = dict(synthetic.COLOURS, pink=(240, 150, 200), teal=(20, 128, 128))
    try:
        synthetic.COLOURS.update(odd)
        image = render_blocks(
            [
                SyntheticBlock("pink", 0.15, 0.15, 0, 0.04),
                SyntheticBlock("teal", 0.3, 0.2, 0, 0.04),
            ],
            CAMERA,
        )
    finally:
        for name in ("pink", "teal"):
            synthetic.COLOURS.pop(name)
    assert sorted(b.name for b in detect_blocks(image, CAMERA)) == ["block1", "block2"]


def test_stacking_without_a_known_side_invents_no_blocks(tmp_path: Path) -> None:
    """Fig. 4's start: red moved onto wood and green; the strips left in view are
    pieces of covered blocks, not new small blocks."""
    wood, green = (
        SyntheticBlock("wood", 0.3, 0.04, 0, 0.04),
        SyntheticBlock("green", 0.34, 0.041, 2, 0.04),
    )
    save_image(
        render_blocks([wood, green, SyntheticBlock("red", 0.2, 0.2, 0, 0.04)], CAMERA, rng=1),
        tmp_path / "b.png",
    )
    save_image(
        render_blocks([wood, green, SyntheticBlock("red", 0.32, 0.04, 0, 0.04)], CAMERA, rng=2),
        tmp_path / "a.png",
    )
    result = invoke(
        "perceive",
        tmp_path / "a.png",
        "--before",
        tmp_path / "b.png",
        "--px-per-m",
        "1000",
        "--origin",
        "0",
        "0",
        "--json",
    )
    assert result.exit_code == 0, result.stderr
    assert sorted(json.loads(result.stdout)["objects"]) == ["green", "red", "wood"]


def test_mujoco_copes_with_any_object_names(tmp_path: Path) -> None:
    """Bodies get internal names: objects called hand, target or obstacle1 are fine."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    pytest.importorskip("mujoco", reason="MuJoCo is not installed")
    from demoplan.execution.physics import MujocoWorld
    from demoplan.model import ObjectGeometry, Pose
    from demoplan.scenes.scene import Scene, SceneObject

    cube = ObjectGeometry("box", (0.04, 0.04, 0.04))
    scene = Scene(
        objects=tuple(
            SceneObject(name, Pose((0.1 * k, 0.0, 0.0)), cube)
            for k, name in enumerate(("hand", "target", "obstacle1"))
        )
    )
    world = MujocoWorld(scene)
    assert sorted(world.observe().poses) == ["hand", "obstacle1", "target"]
    world.grasp("target", 0.0)
    assert world.observe().held == "target"
