"""The studio's Run view shows what the run observed (docs/studio.md "Run"),
in real headless Chromium: the table at every event is the world the run's
events carry (a dropped object where it fell), the run ends on its final
world, a run that did not reach its goal is never shown as a success, a
studio that stops leaves no run "running" on the page, and a page opened
again shows the run that ended last. Runs are kinematic with seeded faults;
the page's values are checked against the studio's API and the command
layer's own run of the same request.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from io import StringIO
from pathlib import Path
from typing import Any

import pytest
from fastapi import FastAPI
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.commands.execution import run
from demoplan.commands.learning import learn_files
from demoplan.execution.faults import Faults
from demoplan.execution.report import RunReport
from demoplan.studio import worker
from demoplan.studio.app import create_app
from demoplan.studio.jobs import LAST_RUN_FILE
from tests.support.studio_browser import ROOT, VIEWPORT, Studio, chromium_browser

BLOCKS = ROOT / "examples" / "blocks" / "demonstrations.json"
FIG4 = ROOT / "examples" / "scenes" / "pyramid-fig4.json"
DROPS = "drop=0.5"
DROPS_SEED = 1  # among its five failures, red dropped where it fell


@pytest.fixture
def workdir(tmp_path: Path) -> Path:
    """A work folder with the blocks' demonstrations, their model and Fig. 4's scene."""
    work = tmp_path / "work"
    work.mkdir()
    shutil.copyfile(BLOCKS, work / "blocks.json")
    shutil.copyfile(FIG4, work / "fig4.json")
    learn_files([work / "blocks.json"], output=work / "model.json")
    return work


@contextmanager
def serving(app: FastAPI) -> Iterator[tuple[str, threading.Event]]:
    """``app`` served by uvicorn in a thread on a free port: its address, and
    an event that stops it (as Ctrl-C does: the studio shuts down)."""
    import uvicorn

    config = uvicorn.Config(app, host="127.0.0.1", port=0, log_level="warning")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    stop = threading.Event()

    def stopper() -> None:
        stop.wait()
        server.should_exit = True

    threading.Thread(target=stopper, daemon=True).start()
    try:
        for _ in range(600):
            if server.started or not thread.is_alive():
                break
            time.sleep(0.05)
        assert server.started, "the studio server did not start"
        port = server.servers[0].sockets[0].getsockname()[1]
        yield f"http://127.0.0.1:{port}", stop
    finally:
        stop.set()
        thread.join(timeout=30)
        assert not thread.is_alive(), "the studio server did not stop"


@pytest.fixture(scope="module")
def module_chromium() -> Iterator[Any]:
    """One chromium for the module's tests (a launch is about a second of CPU)."""
    with chromium_browser() as launched:
        yield launched


@pytest.fixture
def browser(module_chromium: Any, tmp_path: Path) -> Iterator[Any]:
    """The module's chromium for one test, its artifacts folder made; every page
    the test opened (each in a context of its own: :func:`open_page`) is
    closed after it, so that none polls on through the next test."""
    (tmp_path / "art").mkdir(exist_ok=True)
    yield module_chromium
    for context in list(module_chromium.contexts):
        context.close()


def open_page(browser: Any, url: str, artifacts: Path) -> Studio:
    page = Studio(browser.new_page(viewport=VIEWPORT), artifacts)
    page.tab.goto(url)
    page.tab.wait_for_selector('body[data-ready="true"]')
    page.settle()
    return page


def api(url: str, path: str) -> dict[str, Any]:
    with urllib.request.urlopen(url + path, timeout=30) as answer:
        value: dict[str, Any] = json.loads(answer.read())
    return value


def start_run(page: Studio, faults: str, seed: int) -> str:
    """Fig. 4's scene loaded in the Plan view and run with ``faults`` from the
    Run view; the run's id."""
    page.view("Plan")
    page.tab.get_by_label("Scene file").select_option("fig4.json")
    page.button("Load scene").click()
    page.settle()
    page.view("Run")
    page.tab.get_by_label("Faults").fill(faults)
    page.tab.get_by_label("Run seed").fill(str(seed))
    with page.tab.expect_response(
        lambda r: r.url.endswith("/api/runs") and r.request.method == "POST"
    ) as started:
        page.button("Run").click()
    run_id: str = started.value.json()["run"]
    return run_id


def wait_until_over(page: Studio) -> None:
    page.tab.wait_for_selector(
        '#run-state:not([data-state="running"]):not([data-state="idle"])', timeout=120_000
    )
    page.settle()


def drawn(page: Studio) -> dict[str, tuple[float, float, float]]:
    """Every object drawn on the table: x, y (m), yaw (degrees) from its data-*."""
    found: dict[str, tuple[float, float, float]] = page.tab.eval_on_selector_all(
        "#table [data-object]",
        "els => Object.fromEntries(els.map(e => "
        "[e.dataset.object, [Number(e.dataset.x), Number(e.dataset.y), Number(e.dataset.yaw)]]))",
    )
    return {name: (x, y, yaw) for name, (x, y, yaw) in found.items()}


def assert_shows(page: Studio, world: dict[str, Any]) -> None:
    """The table draws exactly the objects standing in ``world`` (an object
    in the hand stands nowhere), each at its observed pose."""
    shown = drawn(page)
    objects = world["objects"]
    assert set(shown) == set(objects), (shown, world)
    assert world["held"] not in shown
    for name, pose in objects.items():
        x, y, yaw = shown[name]
        assert (x, y) == pytest.approx(tuple(pose["position"][:2]), abs=1e-6), name
        assert (yaw - pose["yaw"] + 180) % 360 - 180 == pytest.approx(0, abs=1e-5), name


def show_event(page: Studio, step: int) -> None:
    page.tab.get_by_label("Event", exact=True).fill(str(step))
    page.tab.wait_for_selector(f'#panel-run[data-step="{step}"]', state="attached")


def command_layer_run(workdir: Path, faults: Faults, seed: int) -> tuple[RunReport, list[str]]:
    """The same run through the command layer: its report and its events' texts."""
    texts: list[str] = []
    report = run(
        workdir / "model.json",
        FIG4,
        faults=faults,
        seed=seed,
        on_event=lambda event: texts.append(f"{event.kind}: {event.text}"),
    )
    return report, texts


@pytest.mark.slow
def test_every_event_shows_the_world_the_run_observed_and_the_run_ends_on_its_final_world(
    workdir: Path, tmp_path: Path, browser: Any
) -> None:
    with serving(create_app(workdir)) as (url, _):
        page = open_page(browser, url, tmp_path / "art")
        run_id = start_run(page, DROPS, DROPS_SEED)
        wait_until_over(page)
        status = api(url, f"/api/runs/{run_id}")
        events, result = status["events"], status["result"]
        assert status["state"] == "done" and result["success"] is True, status
        # the run ended: the last event (the end), the final world
        assert page.tab.locator("#run-step-out").inner_text() == f"{len(events)} / {len(events)}"
        assert_shows(page, result["world"])
        assert events[-1]["world"] == result["world"]
        assert page.tab.locator("#run-state").inner_text() == "done"

        # the command layer's run of the same request: the same events, the same end
        report, texts = command_layer_run(workdir, Faults(drop=0.5), DROPS_SEED)
        assert [f"{e['kind']}: {e['text']}" for e in events] == texts
        assert set(result["world"]["objects"]) == set(report.final.poses)
        for name, pose in report.final.poses.items():
            shown = result["world"]["objects"][name]
            assert shown["position"] == pytest.approx(list(pose.position), abs=1e-9)
            assert shown["yaw"] == pytest.approx(pose.yaw, abs=1e-5)
        # a dropped object is seen where it fell (the world's own record of the
        # fault), not at the target the plan had for it
        dropped = [f for f in report.injected if f.kind == "drop" and f.position is not None]
        failures = [e for e in events if e["kind"] == "failure"]
        assert any(e["text"].startswith("dropped: ") for e in failures)
        targets = {
            name: pose["position"]
            for e in events
            if e["targets"]
            for name, pose in e["targets"].items()
        }
        for fault in dropped:
            seen = [e["world"]["objects"].get(fault.object) for e in failures]
            fell = [p for p in seen if p and math.dist(p["position"], fault.position) < 1e-9]
            assert fell, (fault, seen)
            assert math.dist(fell[0]["position"][:2], targets[fault.object][:2]) > 1e-3

        # every event: the table is the world the event carries
        holding = 0
        for step, event in enumerate(events, start=1):
            show_event(page, step)
            assert event["world"] is not None, event
            assert_shows(page, event["world"])
            holding += event["world"]["held"] is not None
        assert holding > 0  # the PUT_DOWNs begin with the object in the hand
        assert page.errors == []


@pytest.mark.slow
def test_a_run_that_does_not_reach_its_goal_is_shown_failed_with_its_reason(
    workdir: Path, tmp_path: Path, browser: Any
) -> None:
    with serving(create_app(workdir)) as (url, _):
        page = open_page(browser, url, tmp_path / "art")
        run_id = start_run(page, "grasp=1", 0)
        wait_until_over(page)
        status = api(url, f"/api/runs/{run_id}")
        report, _ = command_layer_run(workdir, Faults(grasp=1), 0)
        assert report.success is False
        assert status["result"]["success"] is False
        assert status["result"]["reason"] == report.reason
        assert (status["result"]["status"], status["result"]["exit_code"]) == ("failed", 4)
        assert status["events"][-1]["status"] == "failed"
        badge = page.tab.locator("#run-state")
        assert badge.get_attribute("data-state") == "failed"
        assert badge.inner_text() == "failed"
        timeline = page.tab.locator('[data-testid="timeline"] > li')
        texts = timeline.all_inner_texts()
        assert len(texts) == len(status["events"])
        assert not any("✓" in text for text in texts)
        end = page.tab.locator('[data-testid="timeline"] > li[data-kind="done"]')
        assert end.inner_text() == f"✗ FAILED: {report.reason}"
        assert "done" not in (end.get_attribute("class") or "").split()
        colour = "el => getComputedStyle(el.querySelector('button')).color"
        failure = page.tab.locator('[data-testid="timeline"] > li[data-kind="failure"]').first
        assert end.evaluate(colour) == failure.evaluate(colour)  # the failures' red
        summary = page.tab.locator("#run-summary").inner_text()
        assert summary.startswith("Failed: ") and report.reason in summary
        assert_shows(page, status["result"]["world"])
        assert page.errors == []


@pytest.mark.slow
def test_a_new_run_is_never_shown_as_the_last_one_while_it_starts(
    workdir: Path, tmp_path: Path, browser: Any
) -> None:
    """A run that ended green, then Run again with every grasp failing: from
    the click on, the badge reads ``running`` and the timeline is empty —
    before, the last run's green ``done`` and its events stood until the
    request was answered (held back here for a second), so that a page read
    then (or a test waiting for ``data-state`` to leave ``running``) took the
    new, failing run for a success. A request refused (bad faults) puts the
    last run back."""
    with serving(create_app(workdir)) as (url, _):
        page = open_page(browser, url, tmp_path / "art")
        start_run(page, "", 0)
        wait_until_over(page)
        badge = page.tab.locator("#run-state")
        assert badge.get_attribute("data-state") == "done"
        events = page.tab.locator('[data-testid="timeline"] > li').count()

        def slowly(route: Any) -> None:
            time.sleep(1.0)
            route.continue_()

        page.tab.route("**/api/runs", slowly)
        page.tab.get_by_label("Faults").fill("grasp=1")
        page.button("Run").click()
        assert badge.get_attribute("data-state") == "running"
        assert badge.inner_text() == "running"
        assert page.tab.locator('[data-testid="timeline"] > li').count() == 0
        wait_until_over(page)
        assert badge.get_attribute("data-state") == "failed"
        # the failures one from the next: "…; step 2: grasp: …", not run together
        summary = page.tab.locator("#run-summary").inner_text()
        assert re.search(r"failures detected: step 1: grasp: [^;]+; step 2: grasp: ", summary)
        page.tab.get_by_label("Faults").fill("bogus=2")
        page.button("Run").click()
        page.settle()
        assert "bogus=2" in page.alert()
        assert badge.get_attribute("data-state") == "failed"
        assert page.tab.locator('[data-testid="timeline"] > li').count() > 0
        assert events > 0


@pytest.mark.slow
def test_the_badge_leaves_running_when_the_studio_stops(
    workdir: Path, tmp_path: Path, browser: Any
) -> None:
    app = create_app(workdir)
    # a run that never ends by itself: a worker that waits for the studio to go
    app.state.jobs.worker = (sys.executable, "-c", "import sys; sys.stdin.buffer.read()")
    with serving(app) as (url, stop):
        page = open_page(browser, url, tmp_path / "art")
        start_run(page, "", 0)
        badge = page.tab.locator("#run-state")
        page.tab.wait_for_selector('#run-state[data-state="running"]')
        stop.set()  # the studio stops (Ctrl-C): the page's polls find no server
        page.tab.wait_for_selector(
            '#run-state:not([data-state="running"])', state="attached", timeout=60_000
        )
        assert badge.get_attribute("data-state") in ("error", "cancelled")
        assert badge.inner_text() == badge.get_attribute("data-state")
        summary = page.tab.locator("#run-summary").inner_text()
        if badge.get_attribute("data-state") == "error":
            assert summary.startswith("Stopped: the run's end is unknown: ")
            assert "does not answer" in summary
        assert page.button("Run").is_enabled() and page.button("Cancel").is_disabled()


@pytest.mark.slow
def test_a_page_opened_again_shows_the_last_run_of_the_work_folder(
    workdir: Path, tmp_path: Path, browser: Any
) -> None:
    artifacts = tmp_path / "art"
    with serving(create_app(workdir)) as (url, _):
        page = open_page(browser, url, artifacts)
        run_id = start_run(page, DROPS, DROPS_SEED)
        wait_until_over(page)
        status = api(url, f"/api/runs/{run_id}")
        page.tab.close()
    assert (workdir / LAST_RUN_FILE).is_file()
    # a studio started again on the work folder, a page opened anew
    with serving(create_app(workdir)) as (url, _):
        record = api(url, "/api/last-run")
        assert record["run"] == run_id and record["events"] == status["events"]
        page = open_page(browser, url, artifacts)
        page.view("Run")
        events = status["events"]
        timeline = page.tab.locator('[data-testid="timeline"] > li')
        kinds = [timeline.nth(k).get_attribute("data-kind") for k in range(timeline.count())]
        assert kinds == [e["kind"] for e in events]
        assert timeline.last.inner_text() == f"✓ {events[-1]['text']}"
        assert page.tab.locator("#run-state").get_attribute("data-state") == "done"
        assert page.tab.locator("#run-step-out").inner_text() == f"{len(events)} / {len(events)}"
        assert_shows(page, status["result"]["world"])
        show_event(page, 1)  # the start it ran from
        assert_shows(page, events[0]["world"])
        assert page.errors == []


def test_a_record_that_is_not_a_run_is_refused_in_one_line(workdir: Path) -> None:
    from fastapi.testclient import TestClient

    with TestClient(create_app(workdir), base_url="http://127.0.0.1") as client:
        answer = client.get("/api/last-run")
        assert answer.status_code == 200 and answer.json() is None  # none yet
        (workdir / LAST_RUN_FILE).write_text('{"format": "demoplan/studio-run-1"}')
        answer = client.get("/api/last-run")
        assert answer.status_code == 404
        detail = answer.json()["detail"]
        assert detail.startswith(f"run: {LAST_RUN_FILE} is not a run's record")
        assert "\n" not in detail
        assert LAST_RUN_FILE not in client.get("/api/files").json()["demonstrations"]


@pytest.fixture(scope="module")
def blocks_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("model")
    learn_files([BLOCKS], output=folder / "model.json")
    return folder / "model.json"


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    drop=st.sampled_from([0.0, 0.3, 0.6, 1.0]),
    misplace=st.sampled_from([0.0, 0.4]),
    seed=st.integers(0, 10_000),
)
def test_the_worlds_a_run_streams_are_what_the_world_saw(
    blocks_model: Path, drop: float, misplace: float, seed: int
) -> None:
    """The worker's events (as streamed, before the end) against the command
    layer's run of the same request: the same events; the end's world is the
    report's final observation; a dropped or misplaced object is seen, at the
    failure, where the world put it; a PUT_DOWN begins with its object in the
    hand, a GRASP with the hand empty."""
    scene = json.loads(FIG4.read_text(encoding="utf-8"))
    scene.pop("format")
    request = {
        "model": str(blocks_model),
        "scene": scene,
        "sim": "kinematic",
        "faults": f"drop={drop},misplace={misplace}",
        "seed": seed,
    }
    protocol = StringIO()
    outcome = worker._run(request, protocol)
    streamed = [json.loads(line)["event"] for line in protocol.getvalue().splitlines()]
    report, texts = command_layer_run(
        blocks_model.parent, Faults(drop=drop, misplace=misplace), seed
    )
    assert [f"{e['kind']}: {e['text']}" for e in streamed] == texts
    assert [e | {"success": report.success} if e["kind"] == "done" else e for e in streamed] == (
        outcome["events"]
    )
    final = streamed[-1]["world"]
    assert final == outcome["result"]["world"]
    assert final["held"] == report.final.held
    assert set(final["objects"]) == set(report.final.poses)
    for name, pose in report.final.poses.items():
        assert final["objects"][name]["position"] == pytest.approx(list(pose.position), abs=1e-12)
    worlds = [e["world"]["objects"] for e in streamed]
    for fault in report.injected:  # the world's own record of where it put them
        if fault.position is not None:
            assert any(
                seen.get(fault.object, {}).get("position") == list(fault.position)
                for seen in worlds
            ), fault
    for event in streamed:  # the failure's own words: "X stands at (x, y, z), …"
        words = re.fullmatch(r"(?:dropped|misplaced): (\S+) stands at \(([^)]*)\).*", event["text"])
        if event["kind"] == "failure" and words:
            seen = event["world"]["objects"][words[1]]["position"]
            assert [f"{v:.3f}" for v in seen] == words[2].split(", "), event
    for event in streamed:
        if event["kind"] == "action":
            kind, name = event["text"].split()[:2]
            assert event["world"]["held"] == (name if kind == "PUT_DOWN" else None), event
            assert (name in event["world"]["objects"]) == (kind == "GRASP"), event
