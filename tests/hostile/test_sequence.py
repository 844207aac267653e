"""Hostile frames for ``perceive --sequence`` (in a process of its own, as
test_options.py): every refusal is one ``demoplan: error:`` line naming the
file (or the option), an exit code of docs/cli.md, and nothing written."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.perception.camera import Camera, save_image
from demoplan.perception.filmed import render_demonstration
from tests.hostile.harness import check_refused, fingerprint, private_device, run
from tests.support.helpers import EXAMPLES

TOP = ["--px-per-m", "1000", "--origin", "0", "-0.15", "--side", "0.04"]


@pytest.fixture(scope="module")
def frames(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with the first pyramid demonstration's 48 frames, f000.png…"""
    folder = tmp_path_factory.mktemp("frames")
    demo = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])[0]
    for i, frame in enumerate(render_demonstration(demo, Camera(1000.0, (0.0, -0.15)), rng=0)):
        save_image(frame, folder / f"f{i:03d}.png")
    return folder


def _names(count: int) -> list[str]:
    return [f"f{i:03d}.png" for i in range(count)]


@pytest.mark.parametrize(
    ("case", "names", "codes"),
    [
        ("text-as-frame", ["bad.png"], {1}),
        ("other-size", ["small.png"], {1}),
        ("not-a-video", ["film.mp4"], {1}),
        ("folder-as-video", ["folder.mp4"], {1}),
        ("device-as-frame", ["zero.png"], {1}),
        ("video-among-images", ["film.mp4"], {1}),
        ("too-many", ["10,000"], {1}),
        ("output-is-a-frame", ["f000.png"], {1}),
        ("still-only", ["f000.png"], {1}),
        ("timeout", ["--timeout"], {4}),
        ("before", ["--before"], {2}),
    ],
)
def test_hostile_frames_are_refused_in_one_line(
    frames: Path, tmp_path: Path, case: str, names: list[str], codes: set[int]
) -> None:
    for name in _names(48):
        (tmp_path / name).symlink_to(frames / name)
    some = _names(4)
    extra: list[str] = []
    if case == "text-as-frame":
        (tmp_path / "bad.png").write_text("not an image")
        args = [*some, "bad.png"]
    elif case == "other-size":
        save_image(np.zeros((30, 40, 3), np.uint8), tmp_path / "small.png")
        args = [*some, "small.png"]
    elif case in ("not-a-video", "video-among-images"):
        (tmp_path / "film.mp4").write_bytes(b"\x00\x00\x00\x18ftypmp42" + b"\xff" * 2000)
        args = ["film.mp4"] if case == "not-a-video" else [*some, "film.mp4"]
        if case == "not-a-video" and not importlib.util.find_spec("imageio_ffmpeg"):
            names = ["imageio-ffmpeg"]
    elif case == "folder-as-video":
        (tmp_path / "folder.mp4").mkdir()
        args = ["folder.mp4"]
    elif case == "device-as-frame":
        private_device(tmp_path / "zero.png", "zero")
        args = [*some, "zero.png"]
    elif case == "too-many":
        args = ["f000.png"] * 10_001
    elif case == "output-is-a-frame":
        args = some
    elif case == "still-only":
        args = _names(3)  # nobody moves a block
    elif case == "timeout":
        args, extra = _names(48), ["--timeout", "0.01"]
    else:
        args, extra = some, ["--before", "f000.png"]
    before = fingerprint(tmp_path)
    output = "f000.png" if case == "output-is-a-frame" else "demo.json"
    answer = run(["perceive", "--sequence", *args, *TOP, *extra, "-o", output], tmp_path)
    check_refused(answer, names, codes=codes)
    assert fingerprint(tmp_path) == before  # nothing written
