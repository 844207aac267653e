"""Tables in an 80-column terminal: nothing cut off, names whole, empty columns gone."""

from __future__ import annotations

import io
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rich.console import Console

from demoplan.cli import states_table
from demoplan.documents.demonstrations import load_demonstrations
from demoplan.learning import learn
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.model import Demonstration, Pose, Step, TaskModel
from demoplan.rotations import quat_from_yaw
from tests.support.fixture_families import fixture_task
from tests.support.helpers import EXAMPLES


def rendered(model: TaskModel, width: int = 80) -> str:
    console = Console(width=width, file=io.StringIO(), record=True)
    console.print(states_table(model, 2, width))
    return console.export_text()


def words(text: str) -> set[str]:
    return set(re.findall(r"[\w.\-#]+", text))


@pytest.mark.parametrize(
    ("folder", "paper"),
    [
        ("set_table", True),
        ("blocks", True),
        ("kitting/demonstrations.json", False),
        ("cucumber", False),
    ],
)
def test_the_states_table_fits_80_columns_with_every_name_whole(folder: str, paper: bool) -> None:
    model = learn(
        load_demonstrations([EXAMPLES / folder]), settings=PAPER_SETTINGS if paper else None
    )
    text = rendered(model)
    assert max(len(line) for line in text.splitlines()) <= 80
    names = {s.object for s in model.states}  # printed as given
    references = {s.position.reference for s in model.states if s.position.reference}
    assert names | references <= words(text)
    assert {s.id for s in model.states} <= words(text)
    if all(s.orientation.value is None for s in model.states):  # the set table: planar
        assert "Orientation" not in text


@settings(max_examples=25, deadline=None)
@given(
    names=st.lists(
        st.from_regex(r"[a-z][a-z_]{2,21}", fullmatch=True), min_size=2, max_size=4, unique=True
    ),
    oriented=st.booleans(),
)
def test_long_object_names_are_never_cut(names: list[str], oriented: bool) -> None:
    """Names up to 22 characters, the second placed relative to the first."""
    demos = []
    for k, shift in enumerate((0.0, 0.3, 0.7)):
        steps = []
        for i, name in enumerate(names):
            yaw = quat_from_yaw(10.0 * i + k) if oriented else None
            steps.append(Step(name, Pose((0.1 + shift + 0.15 * i, 0.2, 0.0), yaw)))
        demos.append(Demonstration(f"demo-{k + 1}", tuple(steps)))
    model = learn(demos)
    text = rendered(model)
    assert max(len(line) for line in text.splitlines()) <= 80
    assert set(names) <= words(text)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), items=st.integers(2, 4), demos=st.integers(2, 4))
def test_the_compact_table_names_a_reference_its_orientation_turns_with_once(
    seed: int, items: int, demos: int
) -> None:
    """A lunch box never turned in the demonstrations (tests/support/fixture_families.py):
    every item's orientation turns with its position's reference, and the
    compact table's one reference column says so without the name twice
    (``lunchbox; turns with it: never seen turned``, not ``lunchbox / turns
    with lunchbox: …``), the note's words whole."""
    task = fixture_task(np.random.default_rng(seed), items, demos, turn=0.0, landmark=True)
    model = learn(task.demos)
    table = states_table(model, 2, 80)
    assert max(len(line) for line in rendered(model).splitlines()) <= 80
    column = next(c for c in table.columns if str(c.header) == "Relative to")
    cells = [str(cell) for cell in column.cells]
    followed = 0
    for state, cell in zip(model.states, cells, strict=True):
        reference = state.position.reference
        assert reference is not None
        follows = [n for n in state.notes if n.startswith(f"turns with {reference}:")]
        if state.orientation.reference == reference and follows:
            followed += 1
            said = follows[0].removeprefix(f"turns with {reference}")
            assert cell == f"{reference}; turns with it{said}"
        assert cell.count(reference) == 1, cell
    assert followed  # never turned: at least one orientation is a tie that went to the box
