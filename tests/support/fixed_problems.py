"""Fixed problems checked in as files under tests/data, each drawn by a
function kept here so the file can be made again and checked.

A draw can take many tries (the crowded parking problem: 51 draws until one
is not unsolvable on its face, about 1 s of CPU), so the tests read the file
(:func:`load_fixed`), and one slow test (tests/support/test_fixed_problems.py) checks
that drawing again gives the very same file. To write them again after a
change to a family::

    python -m tests.support.fixed_problems
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

from demoplan.planning.problem import Problem
from demoplan.planning.xml import load_problem, problem_to_xml, save_problem

DATA = Path(__file__).resolve().parents[1] / "data"


def hard_parking_draw() -> Problem:
    """A problem no search solves in a minute: 30 objects of the crowded
    parking family, seed 7 (Fast Downward's lama-first finds no plan in 60 s
    either)."""
    from tests.support.planning_families import PARKING_FAMILIES, parking_problem

    return parking_problem(30, 7, **PARKING_FAMILIES["parking-crowded"])


FIXED: dict[str, Callable[[], Problem]] = {"hard-parking": hard_parking_draw}
"""Each fixed problem's file name (``tests/data/NAME.xml``) and its draw."""


def fixed_path(name: str) -> Path:
    return DATA / f"{name}.xml"


def load_fixed(name: str) -> Problem:
    """The fixed problem ``name`` as checked in."""
    return load_problem(fixed_path(name))


def drawn_again(name: str) -> str:
    """The fixed problem ``name`` drawn again, as its file's text."""
    return problem_to_xml(FIXED[name]())


def main(names: list[str]) -> int:
    for name in names or sorted(FIXED):
        save_problem(FIXED[name](), fixed_path(name))
        print(f"wrote {fixed_path(name)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
