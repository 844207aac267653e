"""A disk that fills up while a command writes its folder of outputs
(``run --frames``, ``experiments``): one line naming the output, exit 1, and
nothing left behind — no partial folder, no temporary one (issue 14). Needs a
small tmpfs, so it runs where the tests may mount one (root in CI's VM)."""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.helpers import EXAMPLES
from tests.hostile.harness import check_refused, run


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 200 KB tmpfs: enough for a demonstration, not for a storyboard."""
    where = tmp_path / "small"
    where.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(where)],
        capture_output=True,
        check=False,
    )
    if mounted.returncode:
        pytest.skip(f"cannot mount a small tmpfs here: {mounted.stderr.decode().strip()}")
    try:
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=False)


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("disk")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", folder / "scene.json")
    assert run(["learn", "demos.json", "--paper", "-o", "model.json"], folder).code == 0
    return folder


@pytest.mark.parametrize(
    ("args", "output"),
    [
        (["run", "model.json", "scene.json", "--frames", "SMALL/frames"], "frames"),
        (["experiments", "--out", "SMALL/report"], "report"),
    ],
    ids=["run-frames", "experiments"],
)
def test_a_disk_that_fills_up_leaves_nothing(
    workspace: Path, small_disk: Path, args: list[str], output: str
) -> None:
    answer = run([a.replace("SMALL", str(small_disk)) for a in args], workspace)
    check_refused(answer, [str(small_disk / output)], codes={1})
    assert "no space left" in answer.stderr
    assert ".tmp" not in answer.stderr  # the output as the user named it
    assert list(small_disk.iterdir()) == []
