"""A Ctrl-C as a run's video recording starts leaves nothing beside the video.
Seen in the hostile suite under load (``test_ctrl_c_while_recording_a_video``):
``.run.mp4.<8>.part`` left — the Ctrl-C, held while the private folder was made,
came as the hold ended, inside :class:`VideoOutput`'s making, so no one removed the
folder. The world (and its ffmpeg) is closed before the folder is removed too."""

from __future__ import annotations

import signal
import threading
from pathlib import Path

import pytest

import demoplan.execution.video_output as video_output
from demoplan.execution.video_output import VideoOutput


@pytest.mark.parametrize("made", [[], ["deeper"]])
def test_a_ctrl_c_held_while_the_folder_is_made_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, made: list[str]
) -> None:
    making = video_output.make_folders

    def interrupted(folder: Path) -> list[Path]:
        folders = making(folder)
        # to this thread, which holds it: delivered as the hold ends (to the process,
        # another thread not holding it could take it at once)
        signal.pthread_kill(threading.main_thread().ident or 0, signal.SIGINT)
        return folders

    monkeypatch.setattr(video_output, "make_folders", interrupted)
    target = tmp_path.joinpath(*made, "run.mp4")
    # Python's own Ctrl-C (a test worker may ignore SIGINT)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            VideoOutput(target)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert list(tmp_path.iterdir()) == []
