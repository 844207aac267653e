"""The studio's HTTP API (docs/studio-api.md) through fastapi's TestClient over
a work folder of its own: each endpoint on the shipped examples, checked
against the command layer and the command line; bad input answered with a
4xx and one line; files only inside the work folder; two saves at once."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import networkx as nx
import pytest
import shapely
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.commands.inputs import load_inputs
from demoplan.commands.learning import learn_model
from demoplan.learning.constraints import visit_sequence
from demoplan.learning.modelfile import load_model
from demoplan.learning.tables import state_rows
from demoplan.model import ObjectGeometry, footprint
from demoplan.plotting.colours import assign_colours
from demoplan.studio.app import create_app
from demoplan.studio.layouts import SCATTER_GAP
from tests.learning.test_orientation_follows import lunch_documents
from tests.support.helpers import EXAMPLES, ONE_MOVE_SCENE

DEMOPLAN = Path(sys.executable).parent / "demoplan"
COMMAND = [str(DEMOPLAN)] if DEMOPLAN.exists() else [sys.executable, "-m", "demoplan.cli"]
FIG4 = EXAMPLES / "scenes" / "pyramid-fig4.json"


@pytest.fixture
def client(tmp_path: Path) -> Iterator[TestClient]:
    # the studio answers requests sent to its loopback address only
    with TestClient(create_app(tmp_path / "work"), base_url="http://127.0.0.1") as test_client:
        yield test_client


def work(client: TestClient) -> Path:
    root: Path = client.app.state.workfolder.root  # type: ignore[attr-defined]
    return root


def one_line_error(response: Any, status: int, *fragments: str) -> str:
    """``status`` with ``{"detail": one line}`` naming every fragment."""
    assert response.status_code == status, (response.status_code, response.text)
    detail = response.json()["detail"]
    assert isinstance(detail, str) and "\n" not in detail and detail, detail
    assert "Traceback" not in detail
    for fragment in fragments:
        assert fragment in detail, (fragment, detail)
    return detail


def blocks_demonstrations() -> list[dict[str, Any]]:
    data = json.loads((EXAMPLES / "blocks" / "demonstrations.json").read_text())
    return list(data["demonstrations"])


def scene_body(path: Path = FIG4, **changes: Any) -> dict[str, Any]:
    document = json.loads(path.read_text())
    document.pop("format")
    return document | changes


def save_blocks_and_learn(client: TestClient) -> dict[str, Any]:
    for document in blocks_demonstrations():
        assert client.post("/api/demonstrations", json={"document": document}).status_code == 201
    response = client.post("/api/learn", json={"files": None, "output": "model.json"})
    assert response.status_code == 200, response.text
    answer: dict[str, Any] = response.json()
    return answer


# --- templates and layouts ---


def test_the_templates_are_the_three_tasks_and_an_empty_table(client: TestClient) -> None:
    ids = [t["id"] for t in client.get("/api/templates").json()["templates"]]
    assert ids == ["set_table", "blocks", "kit", "empty"]
    empty = client.get("/api/templates/empty").json()
    assert empty["objects"] == {} and empty["poses"] == {} and empty["landmarks"] == {}
    assert empty["table"]["size"] == [0.8, 0.6]


@pytest.mark.parametrize(
    ("template", "example"),
    [
        ("set_table", "set_table"),
        ("blocks", "blocks/demonstrations.json"),
        ("kit", "kitting/demonstrations.json"),
    ],
)
def test_a_template_is_its_examples_first_initial_layout(
    client: TestClient, template: str, example: str
) -> None:
    layout = client.get(f"/api/templates/{template}").json()
    first = load_inputs([EXAMPLES / example])[0]
    geometry = first.geometry()
    landmarks = first.landmark_poses()
    assert set(layout["objects"]) == set(geometry) - set(landmarks)
    assert set(layout["landmarks"]) == set(landmarks)
    colours = assign_colours([*layout["objects"], *layout["landmarks"]])
    for name, pose in first.initial:
        assert layout["poses"][name]["position"] == pytest.approx(list(pose.position))
        assert layout["poses"][name]["yaw"] == pytest.approx(pose.yaw, abs=1e-6)
        assert layout["objects"][name]["size"] == pytest.approx(list(geometry[name].size))
        assert layout["objects"][name]["colour"] == colours[name]
    # the table holds every pose of the task's demonstrations
    (x0, y0), (width, depth) = layout["table"]["origin"], layout["table"]["size"]
    for demo in load_inputs([EXAMPLES / example]):
        for pose in [p for _, p in demo.initial] + [s.pose for s in demo.steps]:
            assert x0 < pose.position[0] < x0 + width and y0 < pose.position[1] < y0 + depth


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(template=st.sampled_from(["set_table", "blocks", "kit"]), seed=st.integers(0, 2**32 - 1))
def test_a_scatter_is_seeded_apart_and_on_the_table(
    client: TestClient, template: str, seed: int
) -> None:
    layout = client.get(f"/api/templates/{template}", params={"seed": seed}).json()
    again = client.get(f"/api/templates/{template}", params={"seed": seed}).json()
    assert layout == again
    table = shapely.box(
        layout["table"]["origin"][0],
        layout["table"]["origin"][1],
        layout["table"]["origin"][0] + layout["table"]["size"][0],
        layout["table"]["origin"][1] + layout["table"]["size"][1],
    )
    outlines = {}
    for name, shape in layout["objects"].items():
        pose = layout["poses"][name]
        assert pose["position"][2] == 0.0
        geometry = ObjectGeometry(shape["shape"], tuple(shape["size"]))
        outlines[name] = footprint(geometry, pose["position"], pose["yaw"])
        assert table.contains(outlines[name]), name
    for mark in layout["landmarks"].values():
        if mark["size"] is not None:
            geometry = ObjectGeometry(mark["shape"], tuple(mark["size"]))
            outlines["landmark"] = footprint(geometry, mark["position"], mark["yaw"])
    names = sorted(outlines)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            assert outlines[a].distance(outlines[b]) >= SCATTER_GAP - 1e-4, (a, b)
    # scramble is the same generator
    scrambled = client.post("/api/scramble", json={"layout": layout, "seed": seed}).json()
    assert scrambled["poses"] == layout["poses"]


def test_a_table_too_small_for_a_scatter_is_refused_naming_the_others(
    client: TestClient,
) -> None:
    """Two 4 cm blocks on a 10 cm table: the second finds no room beside the
    first, and the one-line error counts it in the singular."""
    layout = client.get("/api/templates/blocks").json()
    two = list(layout["objects"])[:2]
    layout["objects"] = {name: layout["objects"][name] for name in two}
    layout["poses"] = {name: layout["poses"][name] for name in two}
    layout["table"]["size"] = [0.1, 0.1]
    response = client.post("/api/scramble", json={"layout": layout, "seed": 1})
    one_line_error(response, 422, "layout.table", "no room on the table", "among 1 other;")


def test_different_seeds_give_different_layouts(client: TestClient) -> None:
    layouts = [client.get("/api/templates/set_table", params={"seed": s}).json() for s in (1, 2)]
    assert layouts[0]["poses"] != layouts[1]["poses"]


# --- drops: the support rule, heights from the geometry ---


def test_a_knife_dropped_on_the_plate_rests_on_its_top(client: TestClient) -> None:
    layout = client.get("/api/templates/set_table").json()
    plate = layout["poses"]["plate"]["position"]
    body = {"layout": layout, "object": "napkin", "position": plate[:2], "yaw": 0}
    answer = client.post("/api/drop", json=body).json()
    assert answer["on"] == "plate"
    assert answer["pose"]["position"][2] == pytest.approx(layout["objects"]["plate"]["size"][2])
    # far from everything: on the table
    body["position"] = [layout["table"]["origin"][0] + 0.01, layout["table"]["origin"][1] + 0.01]
    answer = client.post("/api/drop", json=body).json()
    assert answer == {"pose": {"position": [*body["position"], 0.0], "yaw": 0.0}, "on": None}


def test_blocks_stack_and_what_a_block_carries_is_refused(client: TestClient) -> None:
    layout = client.get("/api/templates/blocks").json()
    wood = layout["poses"]["wood"]["position"]
    body = {"layout": layout, "object": "red", "position": wood[:2], "yaw": 10}
    answer = client.post("/api/drop", json=body).json()
    assert answer["on"] == "wood" and answer["pose"]["position"][2] == pytest.approx(0.04)
    # red now on wood: green on red stands at 8 cm; wood onto red (which rides on it) is refused
    layout["poses"]["red"] = answer["pose"]
    green = {"layout": layout, "object": "green", "position": wood[:2], "yaw": 0}
    assert client.post("/api/drop", json=green).json()["pose"]["position"][2] == pytest.approx(0.08)
    onto_rider = {"layout": layout, "object": "wood", "position": [wood[0] + 0.01, wood[1]]}
    one_line_error(client.post("/api/drop", json=onto_rider), 422, "red", "moves with it")


# --- files ---


def test_saved_demonstrations_are_listed_and_read_back(client: TestClient) -> None:
    documents = [json.loads(p.read_text()) for p in sorted((EXAMPLES / "set_table").iterdir())]
    names = [
        client.post("/api/demonstrations", json={"document": d, "name": None}).json()["file"]
        for d in documents
    ]
    assert names == ["demonstration-1.json", "demonstration-2.json", "demonstration-3.json"]
    scene = client.post("/api/scenes", json={"document": scene_body(), "name": "fig4.json"})
    assert scene.status_code == 201 and scene.json() == {"file": "fig4.json"}
    (work(client) / "notes.json").write_text('{"hello": 1}')
    assert client.get("/api/files").json() == {
        "demonstrations": names,
        "models": [],
        "objects": [],
        "scenes": ["fig4.json"],
        "latest_model": None,
    }
    answer = client.get("/api/files/demonstration-2.json").json()
    assert answer["document"] == documents[1]
    first = load_inputs([EXAMPLES / "set_table" / "demonstration-2.json"])[0]
    for name, pose in first.initial:
        assert answer["layout"]["poses"][name]["position"] == pytest.approx(list(pose.position))
    scene_layout = client.get("/api/files/fig4.json").json()["layout"]
    assert scene_layout["poses"]["red"]["position"] == pytest.approx([0.32, 0.04, 0.04])
    # a saved file is read by the project's own reader, as `demoplan learn` reads it
    assert load_inputs([work(client) / n for n in names]) == load_inputs([EXAMPLES / "set_table"])


def test_a_save_never_replaces_a_file(client: TestClient) -> None:
    document = blocks_demonstrations()[0]
    body = {"document": document, "name": "mine.json"}
    assert client.post("/api/demonstrations", json=body).status_code == 201
    before = (work(client) / "mine.json").read_bytes()
    one_line_error(client.post("/api/demonstrations", json=body), 409, "mine.json")
    assert (work(client) / "mine.json").read_bytes() == before


def test_two_saves_at_once_leave_two_complete_files(client: TestClient) -> None:
    documents = [dict(d, description="x" * 200_000) for d in blocks_demonstrations()]
    answers: list[Any] = [None, None]
    start = threading.Barrier(2)

    def save(k: int) -> None:
        start.wait()
        answers[k] = client.post("/api/demonstrations", json={"document": documents[k]})

    threads = [threading.Thread(target=save, args=(k,)) for k in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    files = sorted(a.json()["file"] for a in answers)
    assert files == ["demonstration-1.json", "demonstration-2.json"]
    written = sorted(json.loads((work(client) / f).read_text())["name"] for f in files)
    assert written == sorted(d["name"] for d in documents)
    for answer, document in zip(answers, documents, strict=True):
        saved = json.loads((work(client) / answer.json()["file"]).read_text())
        assert saved == {"format": "demoplan/demonstration-1", **document}


def test_two_saves_under_one_name_one_wins_whole(client: TestClient) -> None:
    documents = blocks_demonstrations()
    answers: list[Any] = [None, None]
    start = threading.Barrier(2)

    def save(k: int) -> None:
        start.wait()
        body = {"document": documents[k], "name": "same.json"}
        answers[k] = client.post("/api/demonstrations", json=body)

    threads = [threading.Thread(target=save, args=(k,)) for k in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert sorted(a.status_code for a in answers) == [201, 409]
    winner = next(k for k in range(2) if answers[k].status_code == 201)
    saved = json.loads((work(client) / "same.json").read_text())
    assert saved["name"] == documents[winner]["name"]
    assert [p.name for p in work(client).iterdir()] == ["same.json"]  # no temporary left


# --- learn, plan, run through the command layer ---


def test_learning_through_the_api_equals_the_command_layer(client: TestClient) -> None:
    documents = [json.loads(p.read_text()) for p in sorted((EXAMPLES / "set_table").iterdir())]
    for document in documents:
        client.post("/api/demonstrations", json={"document": document})
    answer = client.post("/api/learn", json={"files": None, "output": "table.json"}).json()
    saved = sorted(p for p in work(client).iterdir() if p.name.startswith("demonstration-"))
    oracle = learn_model(saved)
    assert [(s["id"], s["object"]) for s in answer["states"]] == [
        (s.id, s.object) for s in oracle.states
    ]
    for mine, theirs in zip(answer["states"], oracle.states, strict=True):
        reference = theirs.position.reference or "absolute"
        assert mine["reference"] == ("anywhere" if theirs.position.anywhere else reference)
        assert mine["position"] == pytest.approx(list(theirs.position.value))
        assert mine["spread"] == pytest.approx(math.sqrt(theirs.position.spread))
    assert answer["sequences"] == [list(s) for s in oracle.sequences]
    # the edges drawn: each demonstration's transitive reduction (networkx as the oracle)
    expected: set[tuple[str, str]] = set()
    for sequence in oracle.sequences:
        labels = set(visit_sequence(sequence))
        graph = nx.DiGraph([(x, y) for x, y in oracle.constraints if x in labels and y in labels])
        expected |= set(nx.transitive_reduction(graph).edges)
    assert {tuple(e) for e in answer["constraints"]["edges"]} == expected
    assert answer["model"] == "table.json"
    assert load_model(work(client) / "table.json").states == oracle.states
    assert client.get("/api/files").json()["models"] == ["table.json"]


def test_learning_says_in_words_what_the_states_table_says(client: TestClient) -> None:
    """The issue's lunch box, moved but never turned in three demonstrations
    (tests/learning/test_orientation_follows.py): each state's references come back in
    the words of `learn`'s states table (the same function's), an orientation
    the data could not decide as ``turns with lunchbox: never seen turned``,
    with the state's notes."""
    for document in lunch_documents():
        assert client.post("/api/demonstrations", json={"document": document}).status_code == 201
    answer = client.post("/api/learn", json={"files": None, "output": "lunch.json"}).json()
    model = load_model(work(client) / "lunch.json")
    rows = state_rows(model)
    assert [(s["relative_position"], s["relative_orientation"]) for s in answer["states"]] == [
        (row[2], row[3]) for row in rows
    ]
    assert [s["notes"] for s in answer["states"]] == [list(s.notes) for s in model.states]
    shown = {s["object"]: s["relative_orientation"] for s in answer["states"]}
    assert shown["sandwich"] == "turns with lunchbox: never seen turned"
    for state in answer["states"]:  # the box never turned: no orientation is told from the world
        assert state["orientation_reference"] is not None
        assert state["relative_orientation"].startswith(
            ("turns with ", state["orientation_reference"])
        )


def test_learning_warns_as_the_command_line_does(client: TestClient) -> None:
    documents = [json.loads(p.read_text()) for p in sorted((EXAMPLES / "set_table").iterdir())]
    documents[2]["steps"][1]["position"] = [*documents[2]["steps"][1]["position"][:2], 0.1]
    names = [
        client.post("/api/demonstrations", json={"document": d}).json()["file"] for d in documents
    ]
    answer = client.post("/api/learn", json={"files": names, "output": "m.json"}).json()
    printed = subprocess.run(
        [*COMMAND, "learn", *names, "-o", "cli.json"],
        cwd=work(client),
        capture_output=True,
        text=True,
        check=True,
    ).stderr.splitlines()
    assert answer["warnings"] == [line for line in printed if not line.startswith("wrote ")]
    assert any("fork released 10 cm above the table" in line for line in answer["warnings"])


def test_learning_and_planning_beyond_the_limit_are_refused(client: TestClient) -> None:
    jobs = client.app.state.jobs  # type: ignore[attr-defined]
    save_blocks_and_learn(client)
    with jobs.working(), jobs.working():
        one_line_error(client.post("/api/learn", json={"output": "model.json"}), 429, "at most 2")
        body = {"model": "model.json", "scene": scene_body()}
        one_line_error(client.post("/api/plan", json=body), 429, "at most 2")
    assert client.post("/api/plan", json=body).status_code == 200


def test_plan_through_the_api_is_the_command_lines(client: TestClient) -> None:
    learned = save_blocks_and_learn(client)
    scene = scene_body()
    answer = client.post("/api/plan", json={"model": "model.json", "scene": scene}).json()
    (work(client) / "fig4-scene.json").write_text(FIG4.read_text())
    printed = subprocess.run(
        # no time limit: the default 2 s count from the process start, and on a
        # loaded machine the start-up spends them, leaving a first plan unproved
        # (other actions than the proved one the API finds, or exit 4)
        [*COMMAND, "plan", "model.json", "fig4-scene.json", "--timeout", "inf"],
        cwd=work(client),
        capture_output=True,
        text=True,
        check=True,
    ).stdout.splitlines()
    assert answer["plan"] == [line for line in printed if line.startswith(("GRASP", "PUT_DOWN"))]
    assert answer["no_plan"] is None
    assert [m["action"] for m in answer["moves"]] == answer["plan"]
    # the animation ends with every block on its learned target in this scene
    with_scene = client.post("/api/learn", json={"output": "model.json", "scene": scene}).json()
    assert [s["id"] for s in with_scene["states"]] == [s["id"] for s in learned["states"]]
    last = {m["object"]: m["pose"] for m in answer["moves"] if m["kind"] == "PUT_DOWN"}
    for target in with_scene["targets"]:
        assert last[target["object"]]["position"] == pytest.approx(target["position"], abs=1e-6)


def test_no_plan_is_an_answer_with_the_command_lines_reason(client: TestClient) -> None:
    save_blocks_and_learn(client)
    scene = scene_body(freespace=[])
    answer = client.post("/api/plan", json={"model": "model.json", "scene": scene})
    assert answer.status_code == 200
    body = answer.json()
    assert body["plan"] == []
    assert body["no_plan"]["reason"].startswith("demoplan: error: ")
    assert "no free space" in body["no_plan"]["reason"]
    assert body["no_plan"]["figure"] is None or "<svg" in body["no_plan"]["figure"]


def test_an_error_about_the_start_names_the_plan_views_start_not_a_field_scene(
    client: TestClient,
) -> None:
    """The scene of a plan or a run is the page's start, no file of the user's:
    its errors name it as the page does (``the Plan view's start: objects: …``),
    never by the request's field ``scene`` the user never typed."""
    save_blocks_and_learn(client)
    lacking = scene_body()
    del lacking["objects"]["red"]
    expected = "the Plan view's start: objects: the task model needs red"
    detail = one_line_error(
        client.post("/api/plan", json={"model": "model.json", "scene": lacking}), 422, expected
    )
    assert detail.startswith(expected)
    bad_yaw = scene_body(landmarks={"tray": {"position": [0.3, 0.3, 0.0], "yaw": "x"}})
    detail = one_line_error(
        client.post("/api/runs", json={"model": "model.json", "scene": bad_yaw}), 422
    )
    assert detail.startswith("the Plan view's start: landmarks.tray.yaw: "), detail
    learned = client.post("/api/learn", json={"output": "model.json", "scene": bad_yaw})
    assert one_line_error(learned, 422).startswith("the Learn view's table: landmarks.tray.yaw: ")
    # in the run's own process (the model's objects are checked there, not before it starts)
    started = client.post("/api/runs", json={"model": "model.json", "scene": lacking})
    assert started.status_code == 202, started.text
    state = wait_for(client, started.json()["run"])
    assert state["state"] == "failed" and state["error"].startswith(expected), state


def wait_for(client: TestClient, run: str, tries: int = 3000) -> dict[str, Any]:
    """The run's state once it has ended; polled every 0.1 s up to ``tries``
    times, a hang guard (a kinematic run takes seconds unloaded, a loaded
    machine many times that; a finished run returns at once)."""
    for _ in range(tries):
        state: dict[str, Any] = client.get(f"/api/runs/{run}").json()
        if state["state"] != "running":
            return state
        time.sleep(0.1)
    raise AssertionError("the run never ended")


def test_a_run_with_a_drop_fault_shows_the_failure_and_the_replan(client: TestClient) -> None:
    save_blocks_and_learn(client)
    body = {"model": "model.json", "scene": scene_body(), "faults": "drop=1", "seed": 0}
    started = client.post("/api/runs", json=body)
    assert started.status_code == 202
    state = wait_for(client, started.json()["run"])
    assert state["state"] == "done", state
    kinds = [event["kind"] for event in state["events"]]
    assert "failure" in kinds and "replan" in kinds
    assert kinds.index("failure") < kinds.index("replan")
    failures = [e["text"] for e in state["events"] if e["kind"] == "failure"]
    assert len(failures) == len(state["result"]["failures"])
    assert any(": drop:" in line for line in state["result"]["injected"])
    assert state["result"]["replans"] == kinds.count("replan")
    assert kinds[-1] == "done"


def test_a_run_without_faults_puts_every_block_on_its_target(client: TestClient) -> None:
    learned = save_blocks_and_learn(client)
    body = {"model": "model.json", "scene": scene_body()}
    state = wait_for(client, client.post("/api/runs", json=body).json()["run"])
    assert state["result"]["success"] is True and state["result"]["failures"] == []
    assert len(learned["states"]) == 3


@pytest.mark.slow
def test_two_arm_runs_one_after_the_other_each_record_a_video(client: TestClient) -> None:
    # each run renders in a process of its own: a second MuJoCo renderer in
    # one process (as when runs were threads) could hang in EGL
    pytest.importorskip("mujoco")
    pytest.importorskip("imageio_ffmpeg")
    save_blocks_and_learn(client)
    body = {"model": "model.json", "scene": scene_body(ONE_MOVE_SCENE), "sim": "arm"}
    for _ in range(2):
        state = wait_for(client, client.post("/api/runs", json=body).json()["run"], tries=6000)
        assert state["state"] == "done", state
        video = state["result"]["video"]
        assert video == f"/api/media/run-{state['run']}.mp4"
        answer = client.get(video)
        assert answer.status_code == 200 and answer.headers["content-type"] == "video/mp4"
        assert answer.content == (work(client) / f"run-{state['run']}.mp4").read_bytes()
    assert not list(work(client).glob(".*.part"))


# --- runs in processes of their own: cancelled, killed, stopped with the studio ---

BLOCKING_WORKER = (
    sys.executable,
    "-c",
    "import json, time\n"
    "while True:  # a long run: an event every 10 ms until stopped\n"
    "    print(json.dumps({'event': {'kind': 'action', 'text': 'waiting'}}), flush=True)\n"
    "    time.sleep(0.01)\n",
)
SET_TABLE_CLUTTERED = EXAMPLES / "scenes" / "set-table-cluttered.json"


def no_video(run_id: str) -> dict[str, Any]:
    return {"video": None}


def process_state(pid: int) -> str | None:
    """The state letter of process ``pid`` in /proc (R, S, T, Z…), None when gone."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return None
    return stat.rsplit(")", 1)[1].split()[0]


def is_gone(pid: int) -> bool:
    """No such process, or a zombie (it runs nothing; its parent may not reap it)."""
    return process_state(pid) in (None, "Z")


def wait_gone(pids: list[int], seconds: float = 60.0) -> None:
    """Every process of ``pids`` gone, waiting at most ``seconds`` (a loaded machine)."""
    deadline = time.monotonic() + seconds
    while not all(is_gone(pid) for pid in pids):
        assert time.monotonic() < deadline, [(pid, process_state(pid)) for pid in pids]
        time.sleep(0.05)


def descendants(pid: int) -> dict[int, str]:
    """The live processes below ``pid`` (its children, theirs…) and their names."""
    parents: dict[int, tuple[int, str]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue
        name = text[text.index("(") + 1 : text.rindex(")")]
        parents[int(stat.parent.name)] = (int(text.rsplit(")", 1)[1].split()[1]), name)
    found: dict[int, str] = {}
    frontier = [pid]
    while frontier:
        parent = frontier.pop()
        for child, (ppid, name) in parents.items():
            if ppid == parent and child not in found:
                found[child] = name
                frontier.append(child)
    return found


def wait_for_events(client: TestClient, run: str, count: int = 1) -> dict[str, Any]:
    for _ in range(6000):
        state: dict[str, Any] = client.get(f"/api/runs/{run}").json()
        if len(state["events"]) >= count or state["state"] != "running":
            return state
        time.sleep(0.02)
    raise AssertionError("the run showed no event")


def learn_set_table(client: TestClient) -> str:
    names = []
    for path in sorted((EXAMPLES / "set_table").glob("demonstration-*.json")):
        (work(client) / path.name).write_bytes(path.read_bytes())
        names.append(path.name)
    answer = client.post("/api/learn", json={"files": names, "output": "table.json"})
    assert answer.status_code == 200, answer.text
    return "table.json"


def long_kinematic_run(client: TestClient) -> dict[str, Any]:
    """A kinematic run of a few seconds: the set table among clutter, every
    put-down dropped, replanned until it gives up."""
    model = learn_set_table(client)
    return {
        "model": model,
        "scene": scene_body(SET_TABLE_CLUTTERED),
        "clutter": True,
        "faults": "drop=1",
    }


def test_delete_cancels_a_run_and_its_process_is_gone(client: TestClient) -> None:
    job = client.app.state.jobs.start(no_video, BLOCKING_WORKER)  # type: ignore[attr-defined]
    assert wait_for_events(client, job.id)["state"] == "running"
    assert job.process is not None and not is_gone(job.process.pid)
    answer = client.delete(f"/api/runs/{job.id}")
    assert answer.status_code == 200 and answer.json()["state"] == "cancelled"
    wait_gone([job.process.pid])
    assert job.ended.wait(60)
    seen = len(client.get(f"/api/runs/{job.id}").json()["events"])
    time.sleep(0.2)
    after = client.get(f"/api/runs/{job.id}").json()
    assert after["state"] == "cancelled" and len(after["events"]) == seen


def test_runs_beyond_the_limit_are_refused(client: TestClient) -> None:
    jobs = client.app.state.jobs  # type: ignore[attr-defined]
    started = [jobs.start(no_video, BLOCKING_WORKER) for _ in range(2)]
    save_blocks_and_learn(client)
    body = {"model": "model.json", "scene": scene_body()}
    one_line_error(client.post("/api/runs", json=body), 429, "at most 2")
    for job in started:
        client.delete(f"/api/runs/{job.id}")
    assert client.post("/api/runs", json=body).status_code == 202  # the slots are free again
    one_line_error(client.get("/api/runs/nope"), 404, "nope")


def test_cancelling_a_kinematic_run_ends_its_process(client: TestClient) -> None:
    run = client.post("/api/runs", json=long_kinematic_run(client)).json()["run"]
    job = client.app.state.jobs.get(run)  # type: ignore[attr-defined]
    assert wait_for_events(client, run)["state"] == "running"
    pid = job.process.pid
    assert not is_gone(pid)
    answer = client.delete(f"/api/runs/{run}")
    assert answer.json()["state"] == "cancelled"
    wait_gone([pid])
    assert job.ended.wait(60)
    state = client.get(f"/api/runs/{run}").json()
    assert state["state"] == "cancelled" and state["result"] is None


@pytest.mark.slow
def test_cancelling_an_arm_run_ends_its_process_and_ffmpeg_and_leaves_no_file(
    client: TestClient,
) -> None:
    pytest.importorskip("mujoco")
    pytest.importorskip("imageio_ffmpeg")
    save_blocks_and_learn(client)
    body = {"model": "model.json", "scene": scene_body(), "sim": "arm"}
    run = client.post("/api/runs", json=body).json()["run"]
    job = client.app.state.jobs.get(run)  # type: ignore[attr-defined]
    assert wait_for_events(client, run)["state"] == "running"  # the video is being recorded
    below = descendants(job.process.pid)
    assert any("ffmpeg" in name for name in below.values()), below
    answer = client.delete(f"/api/runs/{run}")
    assert answer.json()["state"] == "cancelled"
    wait_gone([job.process.pid, *below])
    assert job.ended.wait(60)
    assert sorted(p.name for p in work(client).iterdir() if "run-" in p.name) == []


def test_a_run_that_does_not_stop_on_sigterm_is_killed(client: TestClient) -> None:
    # a run that never ends by itself (a real run may finish before the stop on a fast machine)
    job = client.app.state.jobs.start(no_video, BLOCKING_WORKER)  # type: ignore[attr-defined]
    run = job.id
    assert wait_for_events(client, run)["state"] == "running"
    assert job.process is not None
    os.kill(job.process.pid, signal.SIGSTOP)  # as deep in a computation as can be: SIGTERM waits
    answer = client.delete(f"/api/runs/{run}")
    assert answer.json()["state"] == "cancelled"
    wait_gone([job.process.pid])
    assert job.ended.wait(60)
    assert client.get(f"/api/runs/{run}").json()["state"] == "cancelled"


def test_a_run_whose_process_is_killed_fails_in_one_line(client: TestClient) -> None:
    body = long_kinematic_run(client)
    run = client.post("/api/runs", json=body).json()["run"]
    job = client.app.state.jobs.get(run)  # type: ignore[attr-defined]
    os.kill(job.process.pid, signal.SIGKILL)  # from outside: the kernel out of memory, a person
    state = wait_for(client, run)
    assert state["state"] == "failed" and state["result"] is None
    assert (
        state["error"]
        == "the run's process ended without a result (killed by SIGKILL, out of memory?)"
    )
    # the slot is free again
    assert client.post("/api/runs", json=long_kinematic_run(client)).status_code == 202


def test_the_studio_stopping_ends_the_runs_processes(tmp_path: Path) -> None:
    with TestClient(create_app(tmp_path / "work"), base_url="http://127.0.0.1") as client:
        jobs = client.app.state.jobs  # type: ignore[attr-defined]
        started = [jobs.start(no_video, BLOCKING_WORKER) for _ in range(2)]
        for job in started:
            wait_for_events(client, job.id)
    wait_gone([job.process.pid for job in started])
    assert [job.to_json()["state"] for job in started] == ["cancelled", "cancelled"]


def test_the_run_process_stops_as_the_command_line_when_the_studio_is_gone(
    client: TestClient,
) -> None:
    body = long_kinematic_run(client)
    request = body | {"model": str(work(client) / body["model"]), "sim": "kinematic"}
    worker = subprocess.Popen(
        [sys.executable, "-m", "demoplan.studio.worker"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        env=os.environ | {"PYTHONPATH": str(Path(__file__).parents[2] / "src")},
    )
    assert worker.stdin is not None and worker.stdout is not None
    worker.stdin.write(json.dumps(request).encode() + b"\n")
    worker.stdin.flush()
    first = json.loads(worker.stdout.readline())
    assert first["event"]["kind"] == "plan"
    worker.stdin.close()  # the studio's end: as if it was killed
    assert worker.wait(timeout=60) == 143  # SIGTERM's exit, as the command line's
    rest = [json.loads(line) for line in worker.stdout]
    assert all("event" in line for line in rest)  # no result: it stopped


# --- hostile input: a 4xx and one line ---


def test_unknown_objects_and_bad_values_are_refused(client: TestClient) -> None:
    layout = client.get("/api/templates/set_table").json()
    drop = {"layout": layout, "object": "spork", "position": [0.1, 0.1]}
    one_line_error(client.post("/api/drop", json=drop), 422, "spork")
    huge = drop | {"object": "knife", "position": [1e308, 0.1]}
    one_line_error(client.post("/api/drop", json=huge), 422, "position")
    wrong = drop | {"object": "knife", "position": ["0.1", 0.1]}
    one_line_error(client.post("/api/drop", json=wrong), 422, "position")
    text = json.dumps(drop | {"object": "knife"}).replace("[0.1, 0.1]", "[NaN, 0.1]")
    headers = {"content-type": "application/json"}
    one_line_error(client.post("/api/drop", content=text, headers=headers), 422, "NaN")
    one_line_error(client.post("/api/drop", content=b"{", headers=headers), 422, "not JSON")
    deep = b"[" * 200_000 + b"]" * 200_000
    assert client.post("/api/drop", content=deep, headers=headers).status_code == 422
    extra_pose = json.loads(json.dumps(layout))
    extra_pose["poses"]["spork"] = {"position": [0, 0]}
    one_line_error(
        client.post("/api/scramble", json={"layout": extra_pose}), 422, "unknown object 'spork'"
    )
    bad_step = blocks_demonstrations()[0]
    bad_step["steps"][0]["object"] = "blue"
    one_line_error(client.post("/api/demonstrations", json={"document": bad_step}), 422, "'blue'")
    one_line_error(client.get("/api/templates/set_table", params={"seed": -1}), 422, "seed")
    save_blocks_and_learn(client)
    plan = {"model": "model.json", "scene": scene_body(), "clutter": "yes"}
    one_line_error(client.post("/api/plan", json=plan), 422, "clutter")
    run = {"model": "model.json", "scene": scene_body(), "faults": "drop=7"}
    one_line_error(client.post("/api/runs", json=run), 422, "faults")
    unknown_block = scene_body()
    unknown_block["objects"]["blue"] = unknown_block["objects"].pop("red")
    answer = client.post("/api/plan", json={"model": "model.json", "scene": unknown_block})
    one_line_error(answer, 422, "needs red, which the scene lacks")


def test_the_limits_are_the_files_limits() -> None:
    from demoplan.documents import poses
    from demoplan.studio import requests

    assert requests.MAX_DISTANCE_M == poses.MAX_DISTANCE_M
    assert (requests.MIN_SIZE_M, requests.MAX_SIZE_M) == (poses.MIN_SIZE_M, poses.MAX_SIZE_M)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(x=st.floats(allow_nan=True, allow_infinity=True) | st.integers(-(10**30), 10**30))
def test_any_number_is_answered_or_refused_in_one_line(client: TestClient, x: float) -> None:
    layout = client.get("/api/templates/blocks").json()
    body = {"layout": layout, "object": "red", "position": [x, 0.1], "yaw": 0}
    text = json.dumps(body)  # NaN and Infinity as Python writes them
    answer = client.post("/api/drop", content=text, headers={"content-type": "application/json"})
    if math.isfinite(x) and abs(x) <= 1000:  # a JSON integer is a number too
        assert answer.status_code == 200
        assert answer.json()["pose"]["position"][0] == float(x)
    else:
        assert answer.status_code == 422
        assert "\n" not in answer.json()["detail"]


def test_requests_from_other_sites_are_refused(client: TestClient) -> None:
    one_line_error(
        client.get("/api/files", headers={"host": "attacker.example"}), 403, "attacker.example"
    )
    assert client.get("/api/files", headers={"host": "localhost:8765"}).status_code == 200
    assert client.get("/api/files", headers={"host": "[::1]:8765"}).status_code == 200
    body = {"document": blocks_demonstrations()[0]}
    other = {"origin": "http://attacker.example"}
    one_line_error(client.post("/api/demonstrations", json=body, headers=other), 403, "Origin")
    for elsewhere in ("http://127.0.0.1:1", "null", "https://127.0.0.1", "http://localhost"):
        one_line_error(
            client.post("/api/demonstrations", json=body, headers={"origin": elsewhere}),
            403,
            "Origin",
        )
    mine = {"origin": "http://127.0.0.1"}  # the page the client's requests come from
    assert client.post("/api/demonstrations", json=body, headers=mine).status_code == 201
    on_a_port = {"host": "localhost:8765", "origin": "http://localhost:8765"}
    assert client.get("/api/files", headers=on_a_port).status_code == 200
    form = {"content-type": "text/plain"}
    text = json.dumps(body)
    one_line_error(
        client.post("/api/demonstrations", content=text, headers=form), 415, "application/json"
    )
    assert client.get("/api/files").json()["demonstrations"] == ["demonstration-1.json"]


JSON_LEAVES = (
    st.none()
    | st.booleans()
    | st.integers(-(10**6), 10**6)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=8)
)
JSON_VALUES = st.recursive(
    JSON_LEAVES,
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4)
    ),
    max_leaves=10,
)


def _places(value: Any, where: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    yield where
    items = (
        value.items()
        if isinstance(value, dict)
        else enumerate(value)
        if isinstance(value, list)
        else ()
    )
    for key, inner in items:
        yield from _places(inner, (*where, key))


@st.composite
def mutated(draw: Any, base: dict[str, Any]) -> Any:
    """``base`` with one value anywhere in it replaced by any JSON value."""
    where = draw(st.sampled_from(list(_places(base))))
    value = draw(JSON_VALUES)
    if not where:
        return value
    copy = json.loads(json.dumps(base))
    inner = copy
    for key in where[:-1]:
        inner = inner[key]
    inner[where[-1]] = value
    return copy


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_any_mangled_request_is_answered_or_refused_in_one_line(
    client: TestClient, data: st.DataObject
) -> None:
    layout = client.get("/api/templates/kit").json()
    drop = {"layout": layout, "object": "pcb", "position": [0.3, 0.3], "yaw": 5}
    demonstration = {"document": blocks_demonstrations()[0], "name": None}
    path, base = data.draw(
        st.sampled_from(
            [
                ("/api/drop", drop),
                ("/api/scramble", {"layout": layout, "seed": 3}),
                ("/api/demonstrations", demonstration),
                ("/api/scenes", {"document": scene_body(), "name": None}),
            ]
        )
    )
    answer = client.post(path, json=data.draw(mutated(base)))  # a 500 raises here
    if answer.status_code >= 300:
        assert answer.status_code < 500
        one_line_error(answer, answer.status_code)


def test_a_large_body_is_refused_before_it_is_read(client: TestClient) -> None:
    big = b'{"document": {"steps": [], "x": "' + b"x" * (10 * 1024 * 1024) + b'"}}'
    headers = {"content-type": "application/json"}
    one_line_error(client.post("/api/demonstrations", content=big, headers=headers), 413, "KiB")

    def chunks() -> Iterator[bytes]:  # no Content-Length: refused while it streams in
        yield b'{"document": {"x": "'
        for _ in range(2048):
            yield b"x" * 1024
        yield b'"}}'

    one_line_error(client.post("/api/scenes", content=chunks(), headers=headers), 413, "KiB")
    assert list(work(client).iterdir()) == []


@pytest.mark.parametrize(
    "name", ["../x.json", "/etc/passwd", "..json", ".hidden.json", "a/b.json", "x.txt", "x" * 90]
)
def test_names_leading_out_of_the_work_folder_are_refused(client: TestClient, name: str) -> None:
    document = blocks_demonstrations()[0]
    answer = client.post("/api/demonstrations", json={"document": document, "name": name})
    assert 400 <= answer.status_code < 500
    one_line_error(answer, answer.status_code)
    learn = client.post("/api/learn", json={"files": [name], "output": "m.json"})
    assert 400 <= learn.status_code < 500
    learn_out = client.post("/api/learn", json={"files": None, "output": name})
    assert 400 <= learn_out.status_code < 500
    assert list(work(client).iterdir()) == []
    assert not (work(client).parent / "x.json").exists()


def test_a_name_with_an_escaped_slash_is_not_found(client: TestClient) -> None:
    assert client.get("/api/files/..%2F..%2Fetc%2Fpasswd").status_code in (404, 422)
    assert client.get("/api/files/%2Fetc%2Fpasswd").status_code in (404, 422)
    assert client.get("/api/media/..%2Fsecret.mp4").status_code in (404, 422)


def test_a_link_leading_out_is_neither_read_nor_written_through(
    client: TestClient, tmp_path: Path
) -> None:
    outside = tmp_path / "outside.json"
    outside.write_text(json.dumps({"format": "demoplan/scene-1", "objects": {}}))
    before = outside.read_text()
    (work(client) / "link.json").symlink_to(outside)
    one_line_error(client.get("/api/files/link.json"), 422, "link")
    assert client.get("/api/files").json()["scenes"] == []
    saved = client.post("/api/scenes", json={"document": scene_body(), "name": "link.json"})
    assert 400 <= saved.status_code < 500
    assert outside.read_text() == before
    learn = client.post("/api/learn", json={"files": ["link.json"], "output": "m.json"})
    one_line_error(learn, 422, "link")
    (work(client) / "film.mp4").symlink_to(outside)
    assert client.get("/api/media/film.mp4").status_code == 404


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(name=st.text(min_size=1, max_size=40) | st.from_regex(r"[A-Za-z0-9._/-]{1,20}\.json"))
def test_any_file_name_is_saved_inside_or_refused(client: TestClient, name: str) -> None:
    document = blocks_demonstrations()[0]
    answer = client.post("/api/demonstrations", json={"document": document, "name": name})
    assert answer.status_code in (201, 409, 422), answer.text
    if answer.status_code == 201:
        assert answer.json() == {"file": name}
        assert (work(client) / name).is_file()
        assert os.sep not in name and not name.startswith(".")
    else:
        assert "\n" not in answer.json()["detail"]
    for path in work(client).parent.iterdir():
        assert path == work(client), path  # nothing written beside the work folder


# --- the command ---


@pytest.mark.parametrize(("stop", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_the_command_prints_its_url_answers_and_stops_as_every_command(
    tmp_path: Path, stop: signal.Signals, code: int
) -> None:
    process = subprocess.Popen(
        [*COMMAND, "studio", "--no-browser", "--port", "0", "--workdir", str(tmp_path / "w")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        url = next(word for word in line.split() if word.startswith("http://127.0.0.1:"))
        with urllib.request.urlopen(url, timeout=60) as page:
            assert page.status == 200 and b"<html" in page.read().lower()
        with urllib.request.urlopen(url + "api/templates", timeout=60) as answer:
            ids = [t["id"] for t in json.loads(answer.read())["templates"]]
        assert ids == ["set_table", "blocks", "kit", "empty"]
        process.send_signal(stop)
        assert process.wait(timeout=60) == code
        assert process.stderr is not None
        assert process.stderr.read().strip() == "demoplan: interrupted"
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def test_the_folders_a_killed_recording_leaves_are_found_and_only_they(tmp_path: Path) -> None:
    from demoplan.execution.video_output import VideoOutput, partial_folders

    target = tmp_path / "run-0123.mp4"
    recording = VideoOutput(target)
    other = VideoOutput(tmp_path / "run-0123.mp4.mp4")  # another target's, named alike
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / ".run-0123.mp4.planted_.part").symlink_to(tmp_path / "elsewhere")  # never removed
    (tmp_path / ".run-0123.mp4.a_file_0.part").write_text("")  # a file, not a folder
    assert partial_folders(target) == [recording.recording.parent]
    recording.discard()
    assert partial_folders(target) == []
    assert partial_folders(other.target) == [other.recording.parent]
