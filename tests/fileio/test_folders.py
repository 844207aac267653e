"""A folder of outputs written all or none (demoplan.fileio.folders.staged_folder)
when Ctrl-C lands at the two moments a private folder used to be left behind:
between mkdtemp's mkdir and its return, and during the removal of the unfinished
folder (a second signal, or the redelivery of the first)."""

from __future__ import annotations

import shutil
import signal
import tempfile
from pathlib import Path
from typing import Any

import pytest

from demoplan.fileio import staged_folder


def test_ctrl_c_as_the_private_folder_is_made_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ctrl_c_raises: None
) -> None:
    real_mkdtemp = tempfile.mkdtemp

    def mkdtemp_then_ctrl_c(*args: Any, **kwargs: Any) -> str:
        made = real_mkdtemp(*args, **kwargs)
        signal.raise_signal(signal.SIGINT)  # lands before mkdtemp has returned
        return made

    monkeypatch.setattr(tempfile, "mkdtemp", mkdtemp_then_ctrl_c)
    with pytest.raises(KeyboardInterrupt), staged_folder(tmp_path / "frames", "test") as building:
        (building / "frame-0001.png").write_bytes(b"unfinished")
    assert sorted(tmp_path.iterdir()) == []


def test_ctrl_c_while_an_unfinished_folder_is_removed_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ctrl_c_raises: None
) -> None:
    real_rmtree = shutil.rmtree

    def ctrl_c_then_rmtree(*args: Any, **kwargs: Any) -> None:
        signal.raise_signal(signal.SIGINT)  # a second Ctrl-C as the removal starts
        real_rmtree(*args, **kwargs)

    monkeypatch.setattr(shutil, "rmtree", ctrl_c_then_rmtree)
    with pytest.raises(KeyboardInterrupt), staged_folder(tmp_path / "frames", "test") as building:
        (building / "frame-0001.png").write_bytes(b"unfinished")
        raise KeyboardInterrupt  # the first Ctrl-C, mid-run
    assert sorted(tmp_path.iterdir()) == []


def test_a_finished_folder_is_swapped_in_whole(tmp_path: Path) -> None:
    with staged_folder(tmp_path / "frames", "test") as building:
        (building / "frame-0001.png").write_bytes(b"done")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames"]
    assert (tmp_path / "frames" / "frame-0001.png").read_bytes() == b"done"
