"""Behaviour tree files (``run --bt``) that would crash, hang or mislead the
engine are refused before it sees them, in one line naming the node, exit 1; a
tree that never ends stops at the tick limit (exit 4); ``export bt`` never
writes what the run refuses."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.commands.export import behaviour_tree
from demoplan.documents.demonstrations import load_demonstrations
from demoplan.documents.poses import MAX_DISTANCE_M
from demoplan.errors import InputError, LimitReachedError, UsageError
from demoplan.execution.behaviour_tree import run_behaviour_tree
from demoplan.execution.kinematic import KinematicWorld
from demoplan.execution.tree_checks import MAX_ATTEMPTS, check_tree
from demoplan.learning import learn
from demoplan.learning.modelfile import save_model
from demoplan.scenes.plan import ScenePlan
from tests.hostile.harness import check_refused, run
from tests.support.helpers import EXAMPLES, paper_model

pytest.importorskip("behaviortreepy")

SCENE = EXAMPLES / "scenes" / "set-table-cluttered.json"
HEAD = '<root BTCPP_format="4" main_tree_to_execute="Task">'


@pytest.fixture(scope="module")
def exported() -> tuple[str, ScenePlan]:
    return behaviour_tree(paper_model("set_table"), SCENE)


def _tree(body: str, *others: str) -> str:
    trees = "".join(others)
    return f'{HEAD}<BehaviorTree ID="Task">{body}</BehaviorTree>{trees}</root>'


HOSTILE = {
    "refers to itself": (_tree('<SubTree ID="Task"/>'), "cycle (Task → Task)"),
    "a cycle of two": (
        _tree(
            '<SubTree ID="A"/>',
            '<BehaviorTree ID="A"><SubTree ID="B"/></BehaviorTree>',
            '<BehaviorTree ID="B"><Sequence><SubTree ID="A"/></Sequence></BehaviorTree>',
        ),
        "cycle (A → B → A)",
    ),
    "include of an absolute path": (
        f'{HEAD}<include path="/etc/hostname"/><BehaviorTree ID="Task"><AlwaysSuccess/>'
        "</BehaviorTree></root>",
        "<include> is not followed",
    ),
    "an undefined variable in a script": (
        _tree('<Script code="x:=undefined+1"/>'),
        "only name:='text' is run",
    ),
    "a scripted precondition": (
        _tree('<AlwaysSuccess _skipIf="undefined == 1"/>'),
        "_skipIf is not run",
    ),
    "endless retries": (
        _tree('<RetryUntilSuccessful num_attempts="-1"><AlwaysFailure/></RetryUntilSuccessful>'),
        f"a whole number from 1 to {MAX_ATTEMPTS} expected",
    ),
    "an unknown node": (_tree('<Timeout msec="1"><AlwaysSuccess/></Timeout>'), "unknown node"),
    "an undefined subtree": (_tree('<SubTree ID="Nowhere"/>'), "a tree of this file expected"),
    "no main tree": (
        '<root BTCPP_format="4" main_tree_to_execute="Main"><BehaviorTree ID="Task">'
        "<AlwaysSuccess/></BehaviorTree></root>",
        "main_tree_to_execute='Main'",
    ),
    "format 3": (
        '<root BTCPP_format="3"><BehaviorTree ID="Task"><AlwaysSuccess/></BehaviorTree></root>',
        'BTCPP_format="4"',
    ),
    "entities": (
        '<!DOCTYPE r [<!ENTITY a "aaaa">]><root BTCPP_format="4"/>',
        "not a behaviour tree",
    ),
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_a_tree_the_engine_could_crash_on_is_refused_first(case: str) -> None:
    xml, expected = HOSTILE[case]
    with pytest.raises(InputError, match=re.escape(expected)) as caught:
        check_tree(xml, "task.xml")
    assert str(caught.value).startswith("task.xml: ") and "\n" not in str(caught.value)


PORTS = {  # a vocabulary port of the exported tree: (replacement, expected)
    "a target 5 km away": ('x="0.52"', 'x="5000"', "within 1000 m"),
    "a negative tolerance": ('tolerance="0.01"', 'tolerance="-1"', "a tolerance above 0"),
    "a grasp axis of 1e308": ('axis="0"', 'axis="1e308"', "an angle within 360°"),
    "a NaN yaw": ('yaw="0"', 'yaw="nan"', "an angle within 360°"),
    "a blackboard object": ('object="plate"', 'object="{moved}"', "a literal value expected"),
    "an unknown port": ('check_yaw="false"', 'check_yaw="false" speed="9"', "not a port of"),
    "a yes/no that is neither": ('check_yaw="false"', 'check_yaw="maybe"', "true or false"),
}


@pytest.mark.parametrize("case", sorted(PORTS))
def test_absurd_port_values_are_refused(exported: tuple[str, ScenePlan], case: str) -> None:
    old, new, expected = PORTS[case]
    xml, _ = exported
    assert old in xml
    with pytest.raises(InputError, match=re.escape(expected)):
        check_tree(xml.replace(old, new, 1), "task.xml")


@settings(max_examples=60, deadline=None)
@given(x=st.floats(allow_nan=True, allow_infinity=True))
def test_a_target_is_accepted_exactly_within_the_bounds_of_a_scene(x: float) -> None:
    node = (
        f'<SubTree ID="MoveToFree" object="cup" axis="0" x="{x!r}" y="0" z="0" yaw="0" '
        'tolerance="0.01"/>'
    )
    vocabulary = '<BehaviorTree ID="MoveToFree"><MoveToFreeAction/></BehaviorTree>'
    xml = _tree(node, vocabulary)
    if math.isfinite(x) and abs(x) <= MAX_DISTANCE_M:
        check_tree(xml, "task.xml")
    else:
        with pytest.raises(InputError, match="within 1000 m"):
            check_tree(xml, "task.xml")


def test_every_exported_tree_passes_the_checks(exported: tuple[str, ScenePlan]) -> None:
    xml, _ = exported
    check_tree(xml, "task.xml")  # raises where the export wrote what a run refuses


def test_export_bounds_the_attempts_and_refuses_names_read_as_entries(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match=f"1 to {MAX_ATTEMPTS} expected"):
        behaviour_tree(paper_model("set_table"), SCENE, attempts=3_000_000_000)
    folder = tmp_path / "demos"
    folder.mkdir()
    for demo in sorted((EXAMPLES / "set_table").glob("*.json")):
        (folder / demo.name).write_text(demo.read_text().replace('"napkin"', '"{napkin}"'))
    scene = tmp_path / "scene.json"
    scene.write_text(SCENE.read_text().replace('"napkin"', '"{napkin}"'))
    model = learn(load_demonstrations(sorted(folder.glob("*.json"))))
    with pytest.raises(
        InputError, match=re.escape("object '{napkin}' cannot be named in a behaviour tree")
    ):
        behaviour_tree(model, scene)


def test_a_tree_that_never_ends_stops_at_the_tick_limit(exported: tuple[str, ScenePlan]) -> None:
    _, result = exported
    xml = _tree("<KeepRunningUntilFailure><AlwaysSuccess/></KeepRunningUntilFailure>")
    with pytest.raises(LimitReachedError, match="still runs after 1,000 ticks"):
        run_behaviour_tree(xml, KinematicWorld(result.scene), max_ticks=1000)


@pytest.mark.parametrize("case", ["refers to itself", "include of an absolute path"])
def test_the_command_answers_in_one_line_where_the_engine_crashed(
    tmp_path: Path, case: str
) -> None:
    """The process itself: a SIGSEGV before, one line and exit 1 now."""
    tree = tmp_path / "task.xml"
    tree.write_text(HOSTILE[case][0])
    model = tmp_path / "model.json"
    save_model(paper_model("set_table"), model)
    done = run(["run", "--bt", tree, model, SCENE], tmp_path)
    check_refused(done, [f"demoplan: error: {tree}: "], codes={1})
