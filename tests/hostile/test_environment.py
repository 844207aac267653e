"""Settings from the environment that MuJoCo refuses are one line, exit 2."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from demoplan.learning.modelfile import save_model
from tests.helpers import EXAMPLES, paper_model

pytest.importorskip("mujoco")


@pytest.mark.parametrize("sim", ["mujoco", "arm"])
def test_a_rendering_backend_mujoco_refuses_is_one_line(tmp_path: Path, sim: str) -> None:
    model = tmp_path / "model.json"
    save_model(paper_model("set_table"), model)
    scene = EXAMPLES / "scenes" / "set-table-cluttered.json"
    done = subprocess.run(
        [sys.executable, "-m", "demoplan", "run", str(model), str(scene), "--sim", sim],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "MUJOCO_GL": "bogus"},
        check=False,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.splitlines() == [
        "demoplan: error: MUJOCO_GL='bogus': one of egl, osmesa, glx, glfw, disable expected "
        "(egl renders without a display)"
    ]
