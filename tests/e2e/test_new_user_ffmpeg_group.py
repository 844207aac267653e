"""Where `run --video`'s ffmpeg runs. At a terminal it gets a session of its
own, so that Ctrl-C reaches demoplan alone, which finishes or stops it. A
process that leads its own session — the studio's run worker, which the
studio cancels by signalling its process group — keeps ffmpeg in its group:
a cancelled run whose worker had to be killed left ffmpeg running after the
studio's answer (measured: 1.5 s, finishing a file in a folder already
removed), where docs/studio-api.md promises that no process of the run
outlives it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("imageio_ffmpeg")

PROBE = """
import json, os, sys
import numpy as np
from pathlib import Path
from demoplan.execution.encoder import FrameEncoder
encoder = FrameEncoder(Path(sys.argv[1]), (16, 16), 10.0)
encoder.send(np.zeros((16, 16, 3), dtype=np.uint8))
groups = {"own": os.getpgrp(), "ffmpeg": os.getpgid(encoder._process.pid)}
encoder.close()
print(json.dumps(groups))
"""


def groups(tmp_path: Path, *, new_session: bool) -> dict[str, int]:
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(tmp_path / "probe.mp4")],
        capture_output=True,
        text=True,
        timeout=60,
        start_new_session=new_session,
        check=True,
    )
    assert (tmp_path / "probe.mp4").stat().st_size > 0
    found: dict[str, int] = json.loads(done.stdout)
    return found


def test_under_a_session_leader_ffmpeg_stays_in_its_process_group(tmp_path: Path) -> None:
    found = groups(tmp_path, new_session=True)
    assert found["ffmpeg"] == found["own"]


def test_under_a_terminal_shell_ffmpeg_has_a_group_of_its_own(tmp_path: Path) -> None:
    found = groups(tmp_path, new_session=False)
    assert found["ffmpeg"] != found["own"]
