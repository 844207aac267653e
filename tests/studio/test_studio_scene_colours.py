"""A scene file's colours in the studio (docs/studio-api.md): the layout of a
scene that gives its things' colours draws them in those colours, a bad one is
a 422 with one line naming the file and the field, and a scene without colours
is drawn in demoplan's (the page's *Save scene* writes every thing's colour:
tests/studio/test_studio_own_task_browser.py)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from demoplan.plotting.colours import assign_colours
from demoplan.studio.app import create_app
from tests.studio.test_studio_api import one_line_error, work
from tests.support.lunch_box import BLUE, GREEN, coloured_document


@pytest.fixture
def client(tmp_path: Path) -> Iterator[TestClient]:
    with TestClient(create_app(tmp_path / "work"), base_url="http://127.0.0.1") as test_client:
        yield test_client


def test_a_scene_is_drawn_in_the_colours_it_gives(client: TestClient) -> None:
    document = coloured_document(sandwich=BLUE, lunchbox=[0.153, 0.682, 0.376])
    (work(client) / "coloured.json").write_text(json.dumps(document))
    (work(client) / "plain.json").write_text(json.dumps(coloured_document()))
    layout = client.get("/api/files/coloured.json").json()["layout"]
    assert layout["objects"]["sandwich"]["colour"] == BLUE
    assert layout["landmarks"]["lunchbox"]["colour"] == GREEN
    plain = client.get("/api/files/plain.json").json()["layout"]
    palette = assign_colours([*plain["objects"], *plain["landmarks"]])
    assert {name: entry["colour"] for name, entry in plain["objects"].items()} == {
        name: palette[name] for name in plain["objects"]
    }
    assert plain["objects"]["sandwich"]["colour"] != BLUE
    for name in ("apple", "juice", "carrot", "cookie"):  # the others as without colours
        assert layout["objects"][name]["colour"] == plain["objects"][name]["colour"]


def test_a_bad_colour_in_a_scene_is_one_line_naming_the_field(client: TestClient) -> None:
    (work(client) / "bad.json").write_text(json.dumps(coloured_document(lunchbox="green")))
    one_line_error(client.get("/api/files/bad.json"), 422, "bad.json", "landmarks.lunchbox.colour")
