"""Demonstrations from a camera (``perceive --sequence``): frames of a filmed
demonstration, the hand reaching in and carrying each block, perceived back
into the demonstration; Experiment 2 learned from its frames."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.errors import InputError
from demoplan.learning import learn
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.model import Demonstration, ObjectGeometry, Pose, TaskModel
from demoplan.perception.blocks import PerceptionSettings, detect_blocks
from demoplan.perception.camera import Camera, save_image
from demoplan.perception.filmed import FilmSettings, random_demonstration, render_demonstration
from demoplan.perception.sequence import (
    Frame,
    demonstration_from_frames,
    hand_mask,
    top_view_detector,
)
from tests.support.cli import invoke

EXAMPLE = Path(__file__).parents[2] / "examples" / "blocks" / "demonstrations.json"
PYRAMID_CAMERA = Camera(1000.0, (0.0, -0.15))  # 500 × 400 px: x 0–0.5 m, y −0.15–0.25 m
SIDE = 0.04
NEAR = PerceptionSettings(min_side=0.85 * SIDE, max_side=1.15 * SIDE)


def perceived(demo: Demonstration, camera: Camera, film: FilmSettings, rng: int) -> Demonstration:
    frames = render_demonstration(demo, camera, film, rng=rng)
    return demonstration_from_frames(
        (Frame(f"frame {i}", f) for i, f in enumerate(frames)),
        top_view_detector(camera, SIDE),
        name=demo.name,
        side=SIDE,
    )


@pytest.fixture(scope="module")
def pyramids() -> tuple[list[Demonstration], list[Demonstration]]:
    """Experiment 2's demonstration files, and the same perceived from their frames."""
    files = load_demonstrations([EXAMPLE])
    seen = [perceived(d, PYRAMID_CAMERA, FilmSettings(), rng=k) for k, d in enumerate(files)]
    return files, seen


def assert_same_model(expected: TaskModel, got: TaskModel) -> None:
    """The models' essential content: sequences, constraints, goals and per state
    its object, members, references and values (to 1 mm, 0.5°)."""
    assert got.sequences == expected.sequences
    assert got.constraints == expected.constraints
    assert got.goals == expected.goals
    assert len(got.states) == len(expected.states)
    for a, b in zip(expected.states, got.states, strict=True):
        assert (b.id, b.object, b.members) == (a.id, a.object, a.members)
        assert b.position.reference == a.position.reference
        assert b.position.value == pytest.approx(a.position.value, abs=0.001)
        assert b.orientation.reference == a.orientation.reference
        assert a.orientation.rpy is not None and b.orientation.rpy is not None
        assert b.orientation.rpy[2] == pytest.approx(a.orientation.rpy[2], abs=0.5)


def test_experiment_2_from_camera_frames_learns_table_iv(
    pyramids: tuple[list[Demonstration], list[Demonstration]],
) -> None:
    """ACCEPTANCE: the two pyramid demonstrations filmed with the hand, perceived
    and learned with the paper's settings give the model the files give."""
    files, seen = pyramids
    for truth, demo in zip(files, seen, strict=True):
        assert [s.object for s in demo.steps] == [s.object for s in truth.steps]
        for a, b in zip(truth.steps, demo.steps, strict=True):
            assert b.pose.position == pytest.approx(a.pose.position, abs=0.001)
        assert dict(demo.objects) == {
            n: ObjectGeometry("box", (SIDE,) * 3) for n, _ in demo.objects
        }
    assert_same_model(learn(files, settings=PAPER_SETTINGS), learn(seen, settings=PAPER_SETTINGS))


def test_the_hand_is_found_and_no_block_is_taken_for_it() -> None:
    files = load_demonstrations([EXAMPLE])
    frames = render_demonstration(files[0], PYRAMID_CAMERA, rng=3)
    assert not hand_mask(frames[0]).any()  # the blocks alone
    reaching = frames[FilmSettings().still_frames + FilmSettings().move_frames - 1]
    mask = hand_mask(reaching)
    assert mask.sum() > 5 * 1600  # the arm and palm: several blocks' area
    assert mask[0].any()  # from the top edge


# --- generated demonstrations (hypothesis) -----------------------------------

GEN_CAMERA = Camera(1000.0, (0.0, 0.0))
GEN_FILM = FilmSettings(width=420, height=320, move_frames=3)


def _yaw_error(a: Pose, b: Pose) -> float:
    assert a.rpy is not None and b.rpy is not None
    return abs((a.rpy[2] - b.rpy[2] + 45.0) % 90.0 - 45.0)


@settings(
    max_examples=8, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(
    seed=st.integers(0, 2**31 - 1),
    count=st.integers(2, 5),
    moves=st.integers(1, 4),
)
def test_generated_demonstrations_are_recovered(seed: int, count: int, moves: int) -> None:
    """Blocks at random poses, moved onto the table or stacked, filmed with the
    hand: the steps come back in order, each block within 3 mm and 2°, on the
    right level (the edges of lower blocks showing beside an upper one pull its
    fit by up to ~2.5 mm; docs/perception.md)."""
    truth = random_demonstration(seed, count, moves, SIDE, ((0.06, 0.36), (0.06, 0.26)))
    if not truth.steps:
        return
    demo = perceived(truth, GEN_CAMERA, GEN_FILM, rng=seed)
    assert [s.object for s in demo.steps] == [s.object for s in truth.steps]
    for a, b in zip(truth.steps, demo.steps, strict=True):
        assert b.pose.position[:2] == pytest.approx(a.pose.position[:2], abs=0.003)
        assert b.pose.position[2] == pytest.approx(a.pose.position[2], abs=0.002)
        assert _yaw_error(a.pose, b.pose) < 2.0
    initial = dict(demo.initial)
    for name, pose in truth.initial:
        assert initial[name].position == pytest.approx(pose.position, abs=0.002)


def test_no_frames_and_still_pictures_are_one_line_errors() -> None:
    def detect(image: np.ndarray) -> list[Any]:
        return detect_blocks(image, GEN_CAMERA, NEAR)

    with pytest.raises(InputError, match="no frames"):
        demonstration_from_frames([], detect, name="x")
    files = load_demonstrations([EXAMPLE])
    still = render_demonstration(files[0], PYRAMID_CAMERA, rng=0)[:3]  # nobody moves a block
    with pytest.raises(InputError, match="no block was moved"):
        demonstration_from_frames([Frame(str(i), f) for i, f in enumerate(still)], detect, name="x")


# --- the command line -------------------------------------------------------


@pytest.fixture(scope="module")
def frame_files(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """The first pyramid demonstration's frames as PNG files."""
    folder = tmp_path_factory.mktemp("frames")
    files = load_demonstrations([EXAMPLE])
    paths = []
    for i, frame in enumerate(render_demonstration(files[0], PYRAMID_CAMERA, rng=0)):
        paths.append(folder / f"pyramid-{i:03d}.png")
        save_image(frame, paths[-1])
    return paths


TOP = ("--px-per-m", "1000", "--origin", "0", "-0.15")


def test_cli_writes_a_demonstration_that_learn_accepts(
    frame_files: list[Path], tmp_path: Path
) -> None:
    out = tmp_path / "demo.json"
    result = invoke("perceive", "--sequence", *frame_files, *TOP, "--side", "0.04", "-o", out)
    assert result.exit_code == 0, result.output
    assert "Demonstration pyramid from 48 frames" in result.stdout
    document = json.loads(out.read_text())
    assert document["format"] == "demoplan/demonstration-1"
    assert [s["object"] for s in document["steps"]] == ["wood", "green", "red"]
    assert document["steps"][2]["position"][2] == pytest.approx(0.04)
    model = tmp_path / "model.json"
    learned = invoke("learn", out, EXAMPLE, "--paper", "-o", model)
    assert learned.exit_code == 0, learned.output
    assert model.exists()


def test_cli_with_a_camera_file(frame_files: list[Path], tmp_path: Path) -> None:
    """--camera: each frame rectified by the camera file's homography (here the
    top view's own mapping) before the blocks are looked for."""
    camera = tmp_path / "camera.json"
    homography = [[0.001, 0, 0.0005], [0, -0.001, -0.15 + 0.3995], [0, 0, 1]]
    camera.write_text(
        json.dumps(
            {
                "format": "demoplan/camera-1",
                "image_size": [500, 400],
                "homography": homography,
                "reprojection_error": {"px": 0, "mm": 0},
            }
        )
    )
    result = invoke(
        "perceive", "--sequence", *frame_files, "--camera", camera, "--side", "0.04", "--json"
    )
    assert result.exit_code == 0, result.output
    steps = json.loads(result.stdout)["steps"]
    truth = load_demonstrations([EXAMPLE])[0].steps
    assert [s["object"] for s in steps] == [s.object for s in truth]
    for step, true in zip(steps, truth, strict=True):  # red on the bridge, 4 cm up
        assert step["position"] == pytest.approx(list(true.pose.position), abs=0.001)


def test_cli_json_and_name(frame_files: list[Path]) -> None:
    result = invoke("perceive", "--sequence", *frame_files, *TOP, "--name", "mine", "--json")
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["name"] == "mine" and len(document["steps"]) == 3
    assert document["provenance"]["frames"] == 48


def test_cli_reads_a_video(tmp_path: Path) -> None:
    """One MP4 file (H.264, as imageio-ffmpeg writes it) is a sequence too."""
    pytest.importorskip("imageio_ffmpeg", reason="imageio-ffmpeg is not installed (.[sim])")
    from demoplan.execution.encoder import FrameEncoder

    files = load_demonstrations([EXAMPLE])
    video = tmp_path / "pyramid.mp4"
    encoder = FrameEncoder(video, (500, 400), 10.0)
    for frame in render_demonstration(files[0], PYRAMID_CAMERA, rng=0):
        encoder.send(frame)
    encoder.close()
    result = invoke("perceive", "--sequence", video, *TOP, "--side", "0.04", "--json")
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["name"] == "pyramid"
    steps = document["steps"]
    assert [s["object"] for s in steps] == ["wood", "green", "red"]
    for step, truth in zip(steps, files[0].steps, strict=True):
        # H.264 (yuv420p) keeps colour at half resolution: where colours touch, ~1 mm
        assert step["position"] == pytest.approx(list(truth.pose.position), abs=0.002)


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


@pytest.mark.parametrize(
    ("case", "code", "fragment"),
    [
        ("not-an-image", 1, "not a readable image"),
        ("sizes", 1, "the size of the first"),
        ("video", 1, "not a readable video"),
        ("many", 1, "at most 10,000 expected"),
        ("output-is-input", 1, "is also an input"),
        ("several-without-sequence", 2, "--sequence"),
        ("no-mapping", 2, "how pixels map"),
    ],
)
def test_hostile_sequences(
    frame_files: list[Path], tmp_path: Path, case: str, code: int, fragment: str
) -> None:
    first = frame_files[:2]
    args: list[Any]
    if case == "not-an-image":
        args = ["--sequence", *first, _write(tmp_path / "x.png", b"not an image"), *TOP]
    elif case == "sizes":
        small = tmp_path / "small.png"
        save_image(np.zeros((10, 12, 3), np.uint8), small)
        args = ["--sequence", *first, small, *TOP]
    elif case == "video":
        args = ["--sequence", _write(tmp_path / "film.mp4", b"\x00" * 4096), *TOP]
    elif case == "many":
        args = ["--sequence", *([first[0]] * 10_001), *TOP]
    elif case == "output-is-input":
        args = ["--sequence", *first, *TOP, "-o", first[0]]
    elif case == "several-without-sequence":
        args = [*first, *TOP]
    else:
        args = ["--sequence", *first]
    result = invoke("perceive", *args)
    assert result.exit_code == code, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) >= 1 and lines[-1].startswith(("demoplan: error:", "Error", "│", "╰"))
    assert fragment in result.stderr
