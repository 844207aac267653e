"""``run --video`` checks how ffmpeg ended (docs/limits.md "Outputs"): an
encoder that exits with a status other than 0, or stops reading its frames,
is one error line and exit 1 with no video left — even where the file it
left looks whole (before, imageio-ffmpeg's writer never looked at the exit
status: only the MP4's boxes were checked). ffmpeg is replaced through
imageio-ffmpeg's own setting, ``IMAGEIO_FFMPEG_EXE``, by a script that
behaves as told; a real ffmpeg is used for the control case and for the
complete MP4 the script copies.
"""

from __future__ import annotations

import importlib.util
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.hostile.harness import check_refused, fingerprint, run
from tests.support.helpers import EXAMPLES, ONE_MOVE_SCENE

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        not all(importlib.util.find_spec(m) for m in ("mujoco", "imageio_ffmpeg")),
        reason="MuJoCo or imageio-ffmpeg not installed",
    ),
]

FAKE = """#!{python}
import shutil, sys
reads, status = {reads!r}, {status!r}
if reads:
    while sys.stdin.buffer.read(1 << 16):
        pass
else:
    sys.stdin.close()
shutil.copyfile({whole!r}, sys.argv[-1])
sys.exit(status)
"""


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("video")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(ONE_MOVE_SCENE, folder / "scene.json")  # a video of any run: the shortest
    assert run(["learn", "demos.json", "--paper", "-o", "model.json"], folder).code == 0
    from demoplan.execution.encoder import FrameEncoder
    from demoplan.execution.video_output import complete_mp4

    encoder = FrameEncoder(folder / "whole.mp4", (64, 48), 10)
    for shade in range(10):
        encoder.send(np.full((48, 64, 3), 20 * shade, dtype=np.uint8))
    encoder.close()
    assert complete_mp4(folder / "whole.mp4")
    return folder


def fake_ffmpeg(folder: Path, reads: bool, status: int, whole: Path) -> Path:
    script = folder / "fake-ffmpeg"
    script.write_text(
        FAKE.format(python=sys.executable, reads=reads, status=status, whole=str(whole))
    )
    script.chmod(0o755)
    return script


def run_video(workspace: Path, case: Path, script: Path | None, monkeypatch: pytest.MonkeyPatch):
    if script is not None:
        monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(script))
    try:
        return run(
            ["run", "model.json", "scene.json", "--sim", "mujoco", "--video", str(case / "v.mp4")],
            workspace,
        )
    finally:
        monkeypatch.delenv("IMAGEIO_FFMPEG_EXE", raising=False)


@settings(
    max_examples=4,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(reads=st.booleans(), status=st.integers(0, 255))
def test_an_encoder_that_fails_is_an_error_and_leaves_no_video(
    workspace: Path,
    tmp_path_factory: pytest.TempPathFactory,
    monkeypatch: pytest.MonkeyPatch,
    reads: bool,
    status: int,
) -> None:
    if reads and status == 0:
        status = 1  # a fake ffmpeg that reads every frame and succeeds is the control below
    case = tmp_path_factory.mktemp("case")
    script = fake_ffmpeg(case, reads, status, workspace / "whole.mp4")
    before = fingerprint(case)
    answer = run_video(workspace, case, script, monkeypatch)
    check_refused(answer, ["v.mp4"], codes={1})
    assert "ffmpeg" in answer.stderr, answer
    assert fingerprint(case) == before, answer  # no video, no part file, no folder


def test_a_real_encoder_makes_the_video(
    workspace: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The control: the real ffmpeg finishes, exit 0, the video in place."""
    from demoplan.execution.video_output import complete_mp4

    answer = run_video(workspace, tmp_path, None, monkeypatch)
    assert answer.code == 0, answer
    assert complete_mp4(tmp_path / "v.mp4")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.mp4"]
