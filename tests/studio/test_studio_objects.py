"""A user's own objects in the studio's HTTP API (docs/studio-api.md): the
objects file (``demoplan/objects-1``) written and read back, the template or
file in use kept across reloads, landmarks moved and turned, drops that do not
pass through things, and hostile input to these endpoints answered with a 4xx
and one line."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from demoplan.commands.objects import objects_from_document, scene_document
from demoplan.errors import InputError
from demoplan.model import ObjectGeometry, footprint
from demoplan.scenes.scene import scene_from_document
from demoplan.studio.app import create_app
from tests.studio.test_studio_api import one_line_error, work
from tests.support.studio_browser import ROOT

BOX_HEIGHT = 0.02


def lunch_layout() -> dict[str, Any]:
    """The lunch box task's start: five things beside a 26 × 18 × 2 cm box."""
    objects = {
        "sandwich": {"shape": "box", "size": [0.1, 0.1, 0.03], "colour": "#e0b060", "mass": 0.15},
        "apple": {"shape": "sphere", "size": [0.07, 0.07, 0.07], "colour": "#c02020"},
        "juice": {"shape": "box", "size": [0.04, 0.06, 0.1], "density": 1000.0},
        "carrot": {"shape": "cylinder", "size": [0.03, 0.03, 0.12], "colour": "#f08020"},
        "cookie": {"shape": "cylinder", "size": [0.05, 0.05, 0.01], "type": "biscuit"},
    }
    poses = {
        "sandwich": {"position": [0.1, 0.1, 0.0], "yaw": 0.0},
        "apple": {"position": [0.25, 0.1, 0.0], "yaw": 0.0},
        "juice": {"position": [0.4, 0.1, 0.0], "yaw": 30.0},
        "carrot": {"position": [0.55, 0.1, 0.0], "yaw": 0.0},
        "cookie": {"position": [0.7, 0.1, 0.0], "yaw": 0.0},
    }
    landmarks = {
        "lunchbox": {
            "shape": "box",
            "size": [0.26, 0.18, BOX_HEIGHT],
            "position": [0.4, 0.4, 0.0],
            "yaw": 0.0,
            "colour": "#3070c0",
        }
    }
    table = {"origin": [0.0, 0.0], "size": [0.8, 0.6]}
    return {"objects": objects, "landmarks": landmarks, "poses": poses, "table": table}


@pytest.fixture
def client(tmp_path: Path) -> Iterator[TestClient]:
    with TestClient(create_app(tmp_path / "work"), base_url="http://127.0.0.1") as test_client:
        yield test_client


# --- the objects file ---


def test_objects_saved_are_listed_and_read_back_with_colour_mass_and_type(
    client: TestClient,
) -> None:
    layout = lunch_layout()
    saved = client.put("/api/objects/lunch.json", json={"layout": layout})
    assert saved.status_code == 200 and saved.json() == {"file": "lunch.json"}
    assert client.get("/api/files").json()["objects"] == ["lunch.json"]
    answer = client.get("/api/files/lunch.json").json()
    assert answer["document"]["format"] == "demoplan/objects-1"
    back = answer["layout"]
    for name, entry in layout["objects"].items():
        for key, value in entry.items():
            assert back["objects"][name][key] == value, (name, key)
        assert back["poses"][name]["position"] == layout["poses"][name]["position"]
        assert back["poses"][name]["yaw"] == pytest.approx(layout["poses"][name]["yaw"])
    box = back["landmarks"]["lunchbox"]
    assert box["size"] == [0.26, 0.18, BOX_HEIGHT] and box["colour"] == "#3070c0"
    # its start is a scene as `plan` reads it: colours, masses and types kept
    scene = scene_from_document(scene_document(answer["document"], "lunch.json"), "lunch.json")
    assert scene.given_colours == {
        name: entry["colour"]
        for group in ("objects", "landmarks")
        for name, entry in layout[group].items()
        if "colour" in entry
    }
    assert scene.object("cookie").type == "biscuit"
    assert dict(scene.landmark_geometry)["lunchbox"].size == (0.26, 0.18, BOX_HEIGHT)
    assert scene.object("juice").pose.yaw == pytest.approx(30.0)


def test_an_objects_file_keeps_lengths_without_the_pages_float_noise(
    client: TestClient, tmp_path: Path
) -> None:
    """The page's arithmetic gives 0.1 + 0.005 = 0.10500000000000001; the file
    says 0.105 (lengths to the micrometre)."""
    layout = lunch_layout()
    layout["poses"]["apple"]["position"] = [0.1 + 0.005, 0.1, 0.0]
    layout["landmarks"]["lunchbox"]["position"] = [0.3 + 0.03, 0.4, 0.0]
    assert client.put("/api/objects/lunch.json", json={"layout": layout}).status_code == 200
    text = (tmp_path / "work" / "lunch.json").read_text()
    assert "0.10500000000000001" not in text and "0.32999999999999996" not in text
    document = json.loads(text)
    assert document["objects"]["apple"]["position"][0] == 0.105
    assert document["landmarks"]["lunchbox"]["position"][0] == 0.33


def test_an_objects_file_is_replaced_only_when_asked_and_only_an_objects_file(
    client: TestClient,
) -> None:
    layout = lunch_layout()
    assert client.put("/api/objects/lunch.json", json={"layout": layout}).status_code == 200
    layout["objects"]["apple"]["colour"] = "#20a020"
    one_line_error(
        client.put("/api/objects/lunch.json", json={"layout": layout}), 409, "lunch.json", "replace"
    )
    again = client.put("/api/objects/lunch.json", json={"layout": layout, "replace": True})
    assert again.status_code == 200
    assert client.get("/api/files/lunch.json").json()["layout"]["objects"]["apple"]["colour"] == (
        "#20a020"
    )
    (work(client) / "model.json").write_text('{"format": "demoplan/model-1"}')
    one_line_error(
        client.put("/api/objects/model.json", json={"layout": layout, "replace": True}),
        409,
        "only an objects file",
    )


def test_a_bad_objects_file_in_the_folder_is_one_line_naming_the_field(
    client: TestClient,
) -> None:
    document = {
        "format": "demoplan/objects-1",
        "objects": {"pear": {"position": [0, 0], "size": [0.05, 0.05, 0.05], "colour": "green"}},
    }
    (work(client) / "bad.json").write_text(json.dumps(document))
    one_line_error(client.get("/api/files/bad.json"), 422, "bad.json", "objects.pear.colour")
    with pytest.raises(InputError, match=r"objects\.pear\.size"):
        objects_from_document(
            {"format": "demoplan/objects-1", "objects": {"pear": {"position": [0, 0]}}}, "f"
        )


def test_the_objects_file_shown_in_formats_md_is_read() -> None:
    page = (ROOT / "docs" / "formats.md").read_text(encoding="utf-8")
    section = page.split("## Objects file (`demoplan/objects-1`)")[1]
    example = section.split("```json")[1].split("```")[0]
    read = objects_from_document(json.loads(example), "formats.md")
    assert read.scene.given_colours == {
        "sandwich": "#d9a441",
        "cookie": "#7f5539",
        "lunchbox": "#2e86c1",
    }
    assert read.scene.object("cookie").type == "biscuit"


# --- the source in use ---


def test_the_template_or_file_in_use_is_kept_across_reloads(tmp_path: Path) -> None:
    folder = tmp_path / "work"
    with TestClient(create_app(folder), base_url="http://127.0.0.1") as first:
        assert first.get("/api/source").json() == {"source": None}
        assert first.put("/api/source", json={"kind": "template", "id": "kit"}).status_code == 200
        assert first.put("/api/objects/lunch.json", json={"layout": lunch_layout()}).is_success
        kept = first.put("/api/source", json={"kind": "file", "id": "lunch.json"}).json()
        assert kept == {"source": {"kind": "file", "id": "lunch.json"}}
        assert ".studio-source.json" not in json.dumps(first.get("/api/files").json())
    with TestClient(create_app(folder), base_url="http://127.0.0.1") as reloaded:
        assert reloaded.get("/api/source").json() == {
            "source": {"kind": "file", "id": "lunch.json"}
        }
        one_line_error(
            reloaded.put("/api/source", json={"kind": "template", "id": "dinner"}), 404, "dinner"
        )
        one_line_error(
            reloaded.put("/api/source", json={"kind": "file", "id": "../etc/passwd.json"}),
            422,
            "id",
        )
        one_line_error(
            reloaded.put("/api/source", json={"kind": "file", "id": ".studio-source.json"}),
            422,
            "id",
        )
        one_line_error(reloaded.put("/api/source", json={"kind": "file", "id": "x.json"}), 404)


# --- physics: drops and landmarks ---


def drop(client: TestClient, layout: dict[str, Any], name: str, x: float, y: float) -> Any:
    return client.post(
        "/api/drop", json={"layout": layout, "object": name, "position": [x, y], "yaw": 0.0}
    )


def test_a_thing_released_over_the_box_lands_on_its_top_and_never_passes_through(
    client: TestClient,
) -> None:
    layout = lunch_layout()
    inside = drop(client, layout, "sandwich", 0.4, 0.4).json()
    assert inside == {"pose": {"position": [0.4, 0.4, BOX_HEIGHT], "yaw": 0.0}, "on": "lunchbox"}
    # 3 mm over the box's rim: too little to stand on (the support rule's 5 %),
    # it would stand in the box's wall
    one_line_error(drop(client, layout, "sandwich", 0.223, 0.4), 422, "sandwich", "lunchbox")
    # 4 mm into the apple's side (more than the 2 mm touch tolerance): through the apple
    one_line_error(drop(client, layout, "juice", 0.199, 0.1), 422, "pass through", "apple")
    # 1 mm: a touch, it stands beside the apple
    assert drop(client, layout, "juice", 0.196, 0.1).json()["on"] is None
    # the cookie on the sandwich that stands in the box: on the sandwich's top
    layout["poses"]["sandwich"] = inside["pose"]
    cookie = drop(client, layout, "cookie", 0.4, 0.4).json()
    assert cookie["on"] == "sandwich"
    assert cookie["pose"]["position"][2] == pytest.approx(BOX_HEIGHT + 0.03)


def test_a_landmark_moves_and_turns_on_clear_table_only(client: TestClient) -> None:
    layout = lunch_layout()

    def move(x: float, y: float, yaw: float) -> Any:
        body = {"layout": layout, "landmark": "lunchbox", "position": [x, y], "yaw": yaw}
        return client.post("/api/landmark", json=body)

    assert move(0.45, 0.42, 25.0).json() == {"pose": {"position": [0.45, 0.42, 0.0], "yaw": 25.0}}
    one_line_error(move(0.2, 0.15, 0.0), 422, "lunchbox", "sandwich", "apple")
    one_line_error(move(0.4, 0.1, 90.0), 422, "juice")
    unknown = {"layout": layout, "landmark": "tray", "position": [0.4, 0.4], "yaw": 0.0}
    one_line_error(client.post("/api/landmark", json=unknown), 422, "tray")


# --- hostile input ---

BAD_OBJECTS: list[tuple[str, Any, str]] = [
    ("shape", "pyramid", "shape"),
    ("size", [0.1, -0.1, 0.1], "size"),
    ("size", [0.1, 0.1, 0.0], "size"),
    ("size", [0.1, 0.1, 1e9], "size"),
    ("size", [0.1, 0.1], "size"),
    ("size", ["0.1", 0.1, 0.1], "size"),
    ("mass", -1.0, "mass"),
    ("mass", 1e12, "mass"),
    ("density", 0.0, "density"),
    ("colour", "red; drop table", "colour"),
    ("type", "two words", "type"),
    ("type", "plate#1", "type"),
    ("weight", 1.0, "weight"),
]


@pytest.mark.parametrize(("field", "value", "named"), BAD_OBJECTS)
def test_bad_objects_are_refused_with_one_line(
    client: TestClient, field: str, value: Any, named: str
) -> None:
    layout = lunch_layout()
    layout["objects"]["apple"][field] = value
    one_line_error(client.put("/api/objects/lunch.json", json={"layout": layout}), 422, named)
    assert client.get("/api/files").json()["objects"] == []


def test_nan_in_a_size_is_refused_before_it_is_read(client: TestClient) -> None:
    text = json.dumps({"layout": lunch_layout()}).replace("0.07, 0.07, 0.07", "0.07, NaN, 0.07")
    headers = {"Content-Type": "application/json"}
    one_line_error(client.put("/api/objects/lunch.json", content=text, headers=headers), 422, "NaN")


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    name=st.one_of(
        st.sampled_from(
            [
                "../lunch.json",
                "..json",
                ".hidden.json",
                "a/b.json",
                "lunch",
                "a\\b.json",
                "%2e%2e.json",
            ]
        ),
        st.text(
            st.characters(min_codepoint=32, max_codepoint=0x2FFF, blacklist_characters="\x7f"),
            min_size=1,
            max_size=30,
        )
        .filter(lambda t: "/" not in t and "?" not in t and "#" not in t)
        .filter(lambda t: t.strip(". ") != ""),
    )
)
def test_object_file_names_stay_inside_the_work_folder(client: TestClient, name: str) -> None:
    response = client.put(f"/api/objects/{name}", json={"layout": lunch_layout()})
    assert response.status_code < 500, response.text
    if response.status_code == 200:
        written = work(client) / response.json()["file"]
        assert written.parent == work(client) and written.is_file()
        written.unlink()
    else:
        detail = response.json()["detail"]
        assert isinstance(detail, str) and "\n" not in detail


def test_object_names_that_plans_cannot_show_are_refused(client: TestClient) -> None:
    layout = lunch_layout()
    layout["objects"]["loc3"] = layout["objects"].pop("apple")
    layout["poses"]["loc3"] = layout["poses"].pop("apple")
    one_line_error(client.put("/api/objects/x.json", json={"layout": layout}), 422, "loc3")
    layout = lunch_layout()
    layout["objects"]["green apple"] = layout["objects"].pop("apple")
    layout["poses"]["green apple"] = layout["poses"].pop("apple")
    one_line_error(client.put("/api/objects/x.json", json={"layout": layout}), 422, "green apple")


def landmark_body(**changes: Any) -> dict[str, Any]:
    body = {"layout": lunch_layout(), "landmark": "lunchbox", "position": [0.4, 0.4], "yaw": 10.0}
    return body | changes


BAD_LANDMARK_MOVES: list[tuple[dict[str, Any], str]] = [
    (landmark_body(yaw=1e9), "yaw"),
    (landmark_body(position=[1e6, 0.4]), "position"),
    (landmark_body(position=[0.4]), "position"),
    (landmark_body(position=["0.4", 0.4]), "position"),
    (landmark_body(landmark="box\x00"), "landmark"),
    (landmark_body(turn=5), "turn"),
    (landmark_body(landmark="../lunchbox"), "../lunchbox"),
]


@pytest.mark.parametrize(("body", "named"), BAD_LANDMARK_MOVES)
def test_bad_landmark_moves_are_refused_with_one_line(
    client: TestClient, body: dict[str, Any], named: str
) -> None:
    one_line_error(client.post("/api/landmark", json=body), 422, named)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("shape", "pyramid"),
        ("size", [0.26, -0.18, 0.02]),
        ("size", [0.26, 0.18, 1e6]),
        ("mass", 1.0),
    ],
)
def test_bad_landmarks_in_an_objects_file_are_refused(
    client: TestClient, field: str, value: Any
) -> None:
    layout = lunch_layout()
    layout["landmarks"]["lunchbox"][field] = value
    one_line_error(
        client.put("/api/objects/lunch.json", json={"layout": layout}), 422, "landmarks", field
    )
    body = landmark_body(layout=layout)
    one_line_error(client.post("/api/landmark", json=body), 422, "landmarks", field)


def test_an_objects_file_without_objects_or_sizes_is_refused(client: TestClient) -> None:
    layout = lunch_layout()
    layout["objects"], layout["poses"] = {}, {}
    one_line_error(client.put("/api/objects/x.json", json={"layout": layout}), 422, "objects")
    layout = lunch_layout()
    layout["objects"]["apple"]["size"] = None
    one_line_error(
        client.put("/api/objects/x.json", json={"layout": layout}), 422, "objects.apple.size"
    )
    assert client.get("/api/files").json()["objects"] == []


def outline(entry: dict[str, Any], pose: dict[str, Any]) -> Any:
    size = entry["size"]
    return footprint(ObjectGeometry(entry["shape"], tuple(size)), pose["position"], pose["yaw"])


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    box=st.tuples(st.floats(0.2, 0.6), st.floats(0.3, 0.5), st.floats(-180, 180)),
    near=st.sampled_from(["lunchbox", "sandwich", "apple", "juice", "carrot", "cookie"]),
    release=st.tuples(st.floats(-0.15, 0.15), st.floats(-0.12, 0.12), st.floats(-180, 180)),
    thing=st.sampled_from(["sandwich", "juice", "carrot", "cookie"]),
)
def test_a_release_never_rests_inside_a_thing(
    client: TestClient,
    box: tuple[float, float, float],
    near: str,
    release: tuple[float, float, float],
    thing: str,
) -> None:
    """Wherever the box stands and a thing is released near something (by
    ``release``, an offset from it): it rests on the table
    or on a top, clear (within the touch tolerance) of everything that stands
    higher, or the release is refused; released wholly over the box, it stands
    on the box's top."""
    layout = lunch_layout()
    mark = layout["landmarks"]["lunchbox"]
    mark["position"], mark["yaw"] = [box[0], box[1], 0.0], box[2]
    poses = layout["poses"]
    box_outline = outline(mark, mark)
    for name in list(poses):  # things the box would stand on are taken off the table
        if outline(layout["objects"][name], poses[name]).intersects(box_outline):
            del layout["objects"][name], poses[name]
    if thing not in poses:
        return
    if near != "lunchbox" and near not in poses:
        return
    centre = (mark if near == "lunchbox" else poses[near])["position"]
    x, y, yaw = centre[0] + release[0], centre[1] + release[1], release[2]
    body = {"layout": layout, "object": thing, "position": [x, y], "yaw": yaw}
    answer = client.post("/api/drop", json=body)
    dropped = outline(layout["objects"][thing], {"position": [x, y], "yaw": yaw})
    event(f"{answer.status_code}: on {answer.json().get('on') or 'the table'}")
    if answer.status_code == 422:
        assert (
            "pass through" in answer.json()["detail"] or "moves with it" in answer.json()["detail"]
        )
        return
    assert answer.status_code == 200, answer.text
    z = answer.json()["pose"]["position"][2]
    core = dropped.buffer(-0.002)
    things = [(mark, mark, BOX_HEIGHT)] + [
        (layout["objects"][n], p, p["position"][2] + layout["objects"][n]["size"][2])
        for n, p in poses.items()
        if n != thing
    ]
    for entry, pose, top in things:
        if top > z + 1e-9:
            assert not core.intersects(outline(entry, pose)), (entry, pose, z)
    if box_outline.contains(dropped) and not any(
        dropped.intersects(outline(layout["objects"][n], p)) for n, p in poses.items() if n != thing
    ):
        assert answer.json()["on"] == "lunchbox" and z == pytest.approx(BOX_HEIGHT)
