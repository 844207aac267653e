"""Block perception (paper §V.B): generated images → poses; stacking from occlusion."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception.blocks import DetectedBlock, PerceptionSettings, detect_blocks
from demoplan.perception.camera import Camera, save_image
from demoplan.perception.colours import name_colour
from demoplan.perception.stacking import BlockTracker, TrackedBlock
from demoplan.perception.synthetic import (
    COLOURS,
    SyntheticBlock,
    random_blocks,
    render_blocks,
    touching_pair,
)
from demoplan.scenes.prepared import prepare
from tests.support.cli import invoke

CAMERA = Camera(1000.0, (0.0, 0.0))  # 1 px = 1 mm, the setting


def errors(
    truth: list[SyntheticBlock], found: list[DetectedBlock]
) -> list[tuple[float, float, float]]:
    """(position mm, angle deg, side mm) per true block, matched by colour and distance."""
    out = []
    for block in truth:
        candidates = [f for f in found if f.colour == block.colour]
        assert candidates, f"{block.colour} block not found"
        f = min(candidates, key=lambda f: math.dist((f.x, f.y), (block.x, block.y)))
        angle = abs(((f.yaw - block.yaw + 45.0) % 90.0) - 45.0)
        out.append(
            (
                1000 * math.dist((f.x, f.y), (block.x, block.y)),
                angle,
                1000 * abs(f.side - block.side),
            )
        )
    return out


def test_one_to_five_blocks_at_random_poses() -> None:
    """Every block counted; median position error < 1 mm and angle < 1° (the targets),
    and no block off by more than 1 mm or 1°, over 30 noisy, shaded images."""
    rng = np.random.default_rng(11)
    measured = []
    for _ in range(30):
        truth = random_blocks(int(rng.integers(1, 6)), CAMERA, 500, 400, rng)
        image = render_blocks(truth, CAMERA, noise=float(rng.uniform(1, 5)), rng=rng)
        found = detect_blocks(image, CAMERA)
        assert sorted(f.colour for f in found) == sorted(b.colour for b in truth)
        measured += errors(truth, found)
    position, angle, side = np.array(measured).T
    assert np.median(position) < 1.0 and np.median(angle) < 1.0
    assert position.max() < 1.0 and angle.max() < 1.0 and side.max() < 1.0


@settings(max_examples=40, deadline=None)
@given(
    colour=st.sampled_from(sorted(COLOURS)),
    x_mm=st.integers(60, 440),
    y_mm=st.integers(60, 340),
    side_mm=st.integers(21, 50),
    seed=st.integers(0, 2**16),
)
def test_a_block_on_pixel_borders(
    colour: str, x_mm: int, y_mm: int, side_mm: int, seed: int
) -> None:
    """A block at yaw 0 on whole millimetres (1 px = 1 mm): its edges lie on pixel
    borders, as in a render of a scene at round coordinates (MuJoCo's top camera).
    Its centre on a Hough bin border once split the votes, and a square in a corner
    of the block (two free sides) was taken for it; it is found to a millimetre."""
    truth = [SyntheticBlock(colour, x_mm / 1000, y_mm / 1000, 0.0, side_mm / 1000)]
    found = detect_blocks(render_blocks(truth, CAMERA, rng=seed), CAMERA)
    assert [f.colour for f in found] == [colour]
    ((position, angle, side),) = errors(truth, found)
    assert position < 1.0 and angle < 1.0 and side < 1.0


@pytest.mark.parametrize("seed", range(6))
def test_touching_blocks_of_different_colours(seed: int) -> None:
    """The paper's failure case (close blocks confused the Hough maxima): colour
    separates them, and each is found to within a millimetre."""
    rng = np.random.default_rng(seed)
    colours = tuple(str(c) for c in rng.permutation(list(COLOURS))[:2])
    truth = touching_pair(CAMERA, 500, 400, rng, (colours[0], colours[1]))
    found = detect_blocks(render_blocks(truth, CAMERA, rng=rng), CAMERA)
    assert len(found) == 2
    for position, angle, side in errors(truth, found):
        assert position < 1.0 and angle < 1.0 and side < 1.0


def test_touching_blocks_of_one_colour_stretch_case() -> None:
    """Same colour, faces touching: found one after the other (the first is cut out
    of the mask); the shared face is invisible, so errors reach ~1.5 mm."""
    rng = np.random.default_rng(5)
    both, worst = 0, 0.0
    for _ in range(10):
        truth = touching_pair(CAMERA, 500, 400, rng, ("red", "red"))
        found = detect_blocks(render_blocks(truth, CAMERA, rng=rng), CAMERA)
        if len(found) == 2:
            both += 1
            for block in truth:
                f = min(found, key=lambda f: math.dist((f.x, f.y), (block.x, block.y)))
                worst = max(worst, 1000 * math.dist((f.x, f.y), (block.x, block.y)))
    assert both == 10 and worst < 2.0
    assert {f.name for f in found} == {"red", "red2"}


def test_world_coordinates_follow_the_camera() -> None:
    """Scale and origin (docs/formats.md): image x = world x, image up = world y."""
    camera = Camera(500.0, (-0.3, 0.2))
    truth = [
        SyntheticBlock("blue", -0.1, 0.45, 20.0, 0.05),
        SyntheticBlock("yellow", 0.2, 0.3, -30.0, 0.06),
    ]
    found = detect_blocks(render_blocks(truth, camera, width=600, height=400, rng=1), camera)
    for position, angle, _ in errors(truth, found):
        assert position < 2.0 and angle < 1.0  # 1 px = 2 mm here


def test_no_blocks_no_detections() -> None:
    image = render_blocks([], CAMERA, rng=3)
    assert detect_blocks(image, CAMERA) == []


@pytest.mark.parametrize(
    ("rgb", "name"),
    [
        ((200, 40, 40), "red"),
        ((50, 150, 60), "green"),
        ((180, 135, 90), "wood"),
        ((40, 80, 190), "blue"),
        ((225, 190, 40), "yellow"),
        ((100, 20, 20), "red"),
        ((20, 20, 20), "black"),
        ((200, 200, 205), "grey"),
    ],
)
def test_colour_names(rgb: tuple[int, int, int], name: str) -> None:
    assert name_colour(np.array(rgb, dtype=float)) == name


def tracked(block: DetectedBlock | SyntheticBlock, z: float = 0.0) -> TrackedBlock:
    name = block.name if isinstance(block, DetectedBlock) else block.colour
    return TrackedBlock(name, block.x, block.y, z, block.yaw, block.side)


def test_stacking_from_occlusion() -> None:
    """§V.B: red is moved onto wood and green (a bridge); both become partly covered,
    so red stands on them (z = 4 cm) and they keep their poses."""
    wood = SyntheticBlock("wood", 0.25, 0.2, 0.0, 0.04)
    green = SyntheticBlock("green", 0.29, 0.2, 0.0, 0.04)
    red_before = SyntheticBlock("red", 0.15, 0.1, 10.0, 0.04)
    red_after = SyntheticBlock("red", 0.27, 0.2, 0.0, 0.04)
    settings = PerceptionSettings(min_side=0.034, max_side=0.046)
    before = detect_blocks(
        render_blocks([wood, green, red_before], CAMERA, rng=1), CAMERA, settings
    )
    tracker = BlockTracker(tracked(b) for b in before)
    after = tracker.update(
        detect_blocks(render_blocks([wood, green, red_after], CAMERA, rng=2), CAMERA, settings)
    )
    assert after["red"].z == pytest.approx(0.04, abs=0.002)
    assert math.dist((after["red"].x, after["red"].y), (0.27, 0.2)) < 0.001
    for block in (wood, green):
        assert after[block.colour].z == 0.0
        assert math.dist((after[block.colour].x, after[block.colour].y), (block.x, block.y)) < 0.001


def test_a_fully_covered_block_keeps_its_pose() -> None:
    wood = SyntheticBlock("wood", 0.25, 0.2, 5.0, 0.04)
    red_before = SyntheticBlock("red", 0.15, 0.1, 10.0, 0.04)
    red_after = SyntheticBlock("red", 0.25, 0.2, 5.0, 0.045)  # hides wood entirely
    tracker = BlockTracker([tracked(wood), tracked(red_before)])
    after = tracker.update(detect_blocks(render_blocks([wood, red_after], CAMERA, rng=2), CAMERA))
    assert after["red"].z == pytest.approx(0.04)
    assert after["wood"] == tracked(wood)


def test_a_held_block_is_left_out() -> None:
    red = SyntheticBlock("red", 0.15, 0.1, 10.0, 0.04)
    tracker = BlockTracker([tracked(red)])
    assert tracker.update([], held="red") == {}


def test_perceive_cli_json_and_stacking(tmp_path: Path) -> None:
    wood = SyntheticBlock("wood", 0.25, 0.2, 0.0, 0.04)
    green = SyntheticBlock("green", 0.29, 0.2, 0.0, 0.04)
    red = SyntheticBlock("red", 0.15, 0.1, 10.0, 0.04)
    save_image(render_blocks([wood, green, red], CAMERA, rng=1), tmp_path / "before.png")
    moved = SyntheticBlock("red", 0.27, 0.2, 0.0, 0.04)
    save_image(render_blocks([wood, green, moved], CAMERA, rng=2), tmp_path / "after.png")
    result = invoke(
        "perceive",
        tmp_path / "after.png",
        "--px-per-m",
        "1000",
        "--origin",
        "0",
        "0",
        "--before",
        tmp_path / "before.png",
        "--side",
        "0.04",
        "--json",
        "-o",
        tmp_path / "scene.json",
    )
    assert result.exit_code == 0, result.stderr
    scene = json.loads(result.stdout)
    assert scene["format"] == "demoplan/scene-1"
    assert scene["objects"]["red"]["position"][2] == pytest.approx(0.04, abs=0.002)
    assert scene["objects"]["red"]["size"] == pytest.approx([0.04] * 3, abs=0.001)
    assert json.loads((tmp_path / "scene.json").read_text()) == scene
    from demoplan.scenes.scene import load_scene

    assert {o.name for o in load_scene(tmp_path / "scene.json").objects} == {"red", "wood", "green"}


@pytest.mark.parametrize(
    ("content", "args", "code", "fragment"),
    [
        (b"not an image", [], 1, "not a readable image"),
        (None, [], 1, "no such file"),
        (b"png", ["--origin", "nan", "0"], 2, "finite"),
    ],
)
def test_perceive_bad_input(
    tmp_path: Path, content: bytes | None, args: list[str], code: int, fragment: str
) -> None:
    path = tmp_path / "image.png"
    if content is not None:
        path.write_bytes(content)
    base = ["perceive", path, "--px-per-m", "1000"]
    result = invoke(*base, *(args or ["--origin", "0", "0"]))
    assert result.exit_code == code, result.output
    assert fragment in result.stderr


def test_a_decompression_bomb_is_refused(tmp_path: Path) -> None:
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    path = tmp_path / "bomb.png"  # a header claiming 60000 × 60000 pixels (3.6 Gpx)
    header = struct.pack(">IIBBBBB", 60_000, 60_000, 1, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IEND", b""))
    result = invoke("perceive", path, "--px-per-m", "1000", "--origin", "0", "0")
    assert result.exit_code == 1
    # demoplan's words, naming the size and the limits (not PIL's "decompression bomb")
    assert "not a readable image (60000 × 60000 pixels; at most 50,000,000" in result.stderr
    assert "DOS" not in result.stderr


def test_experiment_2_on_vision_in_mujoco() -> None:
    """The whole loop on the top camera: the pyramid is built, red on top; checked
    against the simulator's true poses, not against what the camera saw."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    pytest.importorskip("mujoco", reason="MuJoCo is not installed (pip install -e '.[sim]')")
    from demoplan.execution.camera_world import CameraWorld
    from demoplan.execution.executor import execute
    from demoplan.execution.physics import MujocoWorld
    from demoplan.scenes.scene import complete_geometry, load_scene
    from tests.support.helpers import EXAMPLES, paper_model

    model = paper_model("blocks/demonstrations.json")
    scene = complete_geometry(load_scene(EXAMPLES / "scenes" / "pyramid-fig4.json"), model)
    world = MujocoWorld(scene)
    camera_world = CameraWorld(world, scene)
    report = execute(model, prepare(model, scene, clutter=True), camera_world)
    assert report.success, (report.reason, report.failures)
    assert camera_world.pictures >= 9  # one per action and the start
    truth = {n: world._pose(n).position for n in ("wood", "green", "red")}
    states = {s.id: s for s in model.states}
    for state_id in model.goals[1]:
        state = states[state_id]
        base = truth[state.position.reference] if state.position.reference else (0.0, 0.0, 0.0)
        expected = [b + v for b, v in zip(base, state.position.value, strict=True)]
        assert math.dist(truth[state.object], expected) < 0.01, state_id
    assert truth["red"][2] == pytest.approx(0.04, abs=0.003)
