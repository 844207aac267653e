"""The fixed problems under tests/data are what their draws give
(tests/support/fixed_problems.py), and read back as drawn."""

from __future__ import annotations

import pytest

from demoplan.planning.xml import problem_from_xml
from tests.support.fixed_problems import FIXED, drawn_again, fixed_path, load_fixed


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(FIXED))
def test_drawing_a_fixed_problem_again_gives_its_file(name: str) -> None:
    text = drawn_again(name)
    assert fixed_path(name).read_text() == text, (
        f"tests/data/{name}.xml is not what its draw gives: "
        "python -m tests.support.fixed_problems writes it again"
    )
    assert load_fixed(name) == problem_from_xml(text, name)
