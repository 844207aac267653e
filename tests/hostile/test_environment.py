"""Settings MuJoCo refuses (from the environment) and outputs that would be
left behind are refused before a run, in one line, exit 2."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from demoplan.learning.modelfile import save_model
from tests.hostile.harness import check_refused, run
from tests.support.helpers import EXAMPLES, paper_model

# Asked of the installation, not imported: MuJoCo imported here, before demoplan sets
# MUJOCO_GL=egl, would leave this test worker unable to render for every later test.
pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("mujoco") is None, reason="MuJoCo is not installed"
)


@pytest.mark.parametrize("sim", ["mujoco", "arm"])
def test_a_rendering_backend_mujoco_refuses_is_one_line(
    tmp_path: Path, sim: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    model = tmp_path / "model.json"
    save_model(paper_model("set_table"), model)
    scene = EXAMPLES / "scenes" / "set-table-cluttered.json"
    monkeypatch.setenv("MUJOCO_GL", "bogus")
    done = run(["run", model, scene, "--sim", sim], tmp_path)
    check_refused(done, ["MUJOCO_GL"], codes={2})
    assert done.stderr.splitlines() == [
        "demoplan: error: MUJOCO_GL='bogus': one of egl, osmesa, glx, glfw, disable expected "
        "(egl renders without a display)"
    ]


def test_a_video_inside_the_frames_folder_is_refused_before_the_run(tmp_path: Path) -> None:
    """The frames folder is written whole or not at all: a video recorded into it
    was left behind when the folder could not be swapped in."""
    model = tmp_path / "model.json"
    save_model(paper_model("blocks"), model)
    scene = EXAMPLES / "scenes" / "pyramid-fig4.json"
    out = tmp_path / "out"
    done = run(
        ["run", model, scene, "--sim", "mujoco", "--frames", out, "--video", out / "run.mp4"],
        tmp_path,
    )
    check_refused(done, ["lies in the --frames folder"], codes={2})
    assert not out.exists()
