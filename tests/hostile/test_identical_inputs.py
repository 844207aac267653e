"""Hostile input on the surfaces of identical objects: types in demonstrations
and scenes, roles in model files, scenes with too few instances or too many
ways to bind them. Each is refused in one line naming the file and the field
(docs/limits.md), through the real command line."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.hostile.harness import check_clean, check_refused, run
from tests.support.helpers import EXAMPLES

TOWER = EXAMPLES / "identical" / "tower.json"
TOWER_SCENE = EXAMPLES / "identical" / "tower-scene.json"


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("identical")
    answer = run(["learn", TOWER, "-o", "tower.model.json"], folder)
    assert answer.code == 0, answer
    return folder


def _write(folder: Path, name: str, data: dict[str, Any]) -> Path:
    path = folder / name
    path.write_text(json.dumps(data))
    return path


def _tower() -> dict[str, Any]:
    data: dict[str, Any] = json.loads(TOWER.read_text())
    return data


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    kind=st.one_of(
        st.text(min_size=0, max_size=3).map(lambda t: t + " x"),
        st.text(max_size=5).map(lambda t: "#" + t),
        st.just(""),
        st.text(min_size=101, max_size=120, alphabet="ab"),
        st.integers(),
        st.lists(st.integers(), max_size=2),
        st.none().map(lambda _: {"nested": 1}),
    )
)
def test_a_bad_type_in_a_demonstration_is_refused(tmp_path: Path, kind: object) -> None:
    data = _tower()
    data["demonstrations"][0]["objects"]["red-a"]["type"] = kind
    path = _write(tmp_path, "demos.json", data)
    answer = run(["learn", path, "-o", "model.json"], tmp_path)
    check_refused(answer, ["demonstrations[0].objects.red-a.type"])
    assert not (tmp_path / "model.json").exists()


def test_instances_of_one_type_with_different_sizes_are_refused(tmp_path: Path) -> None:
    data = _tower()
    for demo in data["demonstrations"]:
        demo["objects"]["red-a"]["size"] = [0.05, 0.04, 0.04]
    path = _write(tmp_path, "demos.json", data)
    check_refused(run(["learn", path, "-o", "model.json"], tmp_path), ["objects.red-b.type"])


def test_a_role_name_as_an_object_name_is_refused(tmp_path: Path) -> None:
    data = _tower()
    for demo in data["demonstrations"]:
        objects = demo["objects"]
        objects["red#1"] = objects.pop("red-a")
        del objects["red#1"]["type"]
        for step in demo["steps"]:
            if step["object"] == "red-a":
                step["object"] = "red#1"
    path = _write(tmp_path, "demos.json", data)
    check_refused(run(["learn", path, "-o", "model.json"], tmp_path), ["objects.red#1"])


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda m: m["roles"][0].update(instances=["red-a"]), "roles[0].instances"),
        (lambda m: m["roles"][0].update(type="green"), "roles[0].name"),
        (lambda m: m["roles"][0].update(instances="red-a"), "roles[0].instances"),
        (lambda m: m["roles"].append({"name": "x"}), "roles[2]"),
        (lambda m: m.update(roles={"red#1": "red"}), "roles"),
    ],
)
def test_a_model_file_with_bad_roles_is_refused(workspace: Path, change: Any, field: str) -> None:
    model = json.loads((workspace / "tower.model.json").read_text())
    bad = copy.deepcopy(model)
    change(bad)
    path = _write(workspace, "bad.model.json", bad)
    check_refused(run(["plan", path, TOWER_SCENE], workspace), [field])


def test_a_scene_with_fewer_instances_than_roles_names_the_type(workspace: Path) -> None:
    scene = json.loads(TOWER_SCENE.read_text())
    del scene["objects"]["red-y"]
    path = _write(workspace, "scene.json", scene)
    answer = run(["plan", "tower.model.json", path], workspace)
    check_refused(answer, ["objects"])
    assert "2 objects of type 'red'" in answer.stderr and "red-x" in answer.stderr


def test_a_scene_with_an_extra_instance_plans_it_as_an_object_with_no_goal(workspace: Path) -> None:
    scene = json.loads(TOWER_SCENE.read_text())
    scene["objects"]["red-z"] = {**scene["objects"]["red-y"], "position": [0.6, 0.4, 0.0]}
    path = _write(workspace, "scene.json", scene)
    answer = run(["plan", "tower.model.json", path, "--timeout", "inf", "--json"], workspace)
    check_clean(answer)
    assert answer.code == 0
    plan = json.loads(answer.stdout)
    assert plan["length"] == 8 and plan["optimal"]
    assert set(plan["binding"].values()) < {"red-x", "red-y", "red-z"}


def test_too_many_ways_to_bind_identical_objects_is_refused_with_the_numbers(
    tmp_path: Path,
) -> None:
    """Eight identical blocks in a row, 8! bindings: beyond the limit, exit 4."""
    names = [f"cube-{i}" for i in range(8)]
    demos = []
    for shift in (0, 3):
        order = names[shift:] + names[:shift]
        demos.append(
            {
                "objects": {n: {"size": [0.04, 0.04, 0.04], "type": "cube"} for n in names},
                "steps": [
                    {"object": n, "position": [0.1 * i, 0.0, 0.0]} for i, n in enumerate(order)
                ],
            }
        )
    path = _write(
        tmp_path, "row.json", {"format": "demoplan/demonstrations-1", "demonstrations": demos}
    )
    assert run(["learn", path, "-o", "row.model.json"], tmp_path).code == 0
    scene = {
        "format": "demoplan/scene-1",
        "objects": {
            n: {"position": [0.1 * i, 0.5, 0.0], "size": [0.04, 0.04, 0.04], "type": "cube"}
            for i, n in enumerate(names)
        },
    }
    scene_path = _write(tmp_path, "scene.json", scene)
    answer = run(["plan", "row.model.json", scene_path], tmp_path)
    check_refused(answer, ["ways to give the scene's instances"], codes={4})
