"""The tests lie where tests/README.md says: tests/PACKAGE/ for each package of
src/demoplan/, tests/e2e/, tests/hostile/, tests/support/, and at the top only
the root modules' and the tree's tests (tests/support/relayout.py's FOLDERS)."""

from __future__ import annotations

import re
from pathlib import Path

from tests.support.relayout import FOLDERS, HELPERS

TESTS = Path(__file__).resolve().parents[1]
PACKAGES = {
    path.name
    for path in (TESTS.parent / "src" / "demoplan").iterdir()
    if (path / "__init__.py").exists()
}
OWN_FOLDERS = {"e2e", "hostile", "support"}


def test_each_test_file_lies_in_its_package_s_folder() -> None:
    misplaced = []
    for path in TESTS.rglob("test_*.py"):
        parts = path.relative_to(TESTS).parts
        if len(parts) == 1:
            if FOLDERS.get(path.stem) != "":
                misplaced.append(path.name)  # flat: python -m tests.support.relayout
        elif parts[0] not in PACKAGES | OWN_FOLDERS:
            misplaced.append("/".join(parts))
    assert not misplaced, misplaced


def test_every_package_has_its_tests_folder_and_helpers_lie_in_support() -> None:
    assert {p for p in PACKAGES if not (TESTS / p).is_dir()} == set()
    assert {p.stem for p in TESTS.glob("*.py")} <= {"__init__", "conftest"} | {
        name for name, folder in FOLDERS.items() if folder == ""
    }
    assert all((TESTS / "support" / f"{name}.py").exists() for name in HELPERS)


def test_no_file_names_a_helper_where_it_lay_before_the_move() -> None:
    """A branch written before the move still says ``tests.robosuite_data`` or
    ``tests/helpers.py``: found here rather than as a collection error."""
    names = "|".join(HELPERS)
    old = re.compile(rf"\btests\.({names})\b|(?<!support/)\btests/({names})\.py\b")
    stale = []
    for folder in ("tests", "benchmarks", "docs", "src"):
        for path in (TESTS.parent / folder).rglob("*"):
            if path == Path(__file__).resolve():
                continue  # its own docstring names one
            if path.suffix in {".py", ".md"} and old.search(path.read_text(encoding="utf-8")):
                stale.append(str(path.relative_to(TESTS.parent)))
    assert not stale, stale
