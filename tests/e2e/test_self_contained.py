"""The repository stands alone: a user clones it without the project's
working papers, so no file points outside it — no path to the folder of
those papers beside the checkout and no section of the contract they hold —
and the paper is cited by title, authors, venue and year (README)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
OUTSIDE = re.compile(r"\.\./" + "shared" + r"|\b" + "SP" + r"EC\b")


def _tracked_text_files() -> list[Path]:
    try:
        listed = subprocess.run(
            ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    paths = [ROOT / name for name in listed.decode().split("\0") if name]
    return [p for p in paths if p.is_file() and b"\0" not in p.read_bytes()[:8192]]


def test_no_file_points_outside_the_repository() -> None:
    found = [
        f"{path.relative_to(ROOT)}:{number}: {line.strip()[:80]}"
        for path in _tracked_text_files()
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
        if OUTSIDE.search(line)
    ]
    assert not found, "points outside the repository:\n" + "\n".join(found)


def test_the_readme_cites_the_paper() -> None:
    text = " ".join((ROOT / "README.md").read_text().split())
    assert "Learning Task Models from Multiple Human Demonstrations" in text
    assert "Ekvall" in text and "Kragic" in text and "RO-MAN 2006" in text
