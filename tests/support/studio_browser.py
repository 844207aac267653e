"""Helpers for the studio's browser tests: a studio server in a thread, and
drags in world coordinates through the page's documented scale
(``data-metres-per-pixel``, ``data-origin`` on the table element)."""

from __future__ import annotations

import json
import os
import shutil
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from tests.support import browser

ROOT = Path(__file__).resolve().parents[2]
SCREENSHOTS = ROOT / "docs" / "images" / "studio"
VIEWPORT = {"width": 1280, "height": 800}


def chromium() -> str:
    """Debian's chromium with Playwright and the studio extra (tests/support/browser.py)."""
    return browser.chromium(
        ("uvicorn", "demoplan.studio.app"), "Playwright, Debian's chromium and the studio extra"
    )


@contextmanager
def studio_server(workdir: Path) -> Iterator[str]:
    """The studio app of ``workdir`` served by uvicorn in a thread on a free port."""
    import uvicorn

    from demoplan.studio.app import create_app

    config = uvicorn.Config(create_app(workdir), host="127.0.0.1", port=0, log_level="warning")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        for _ in range(600):
            if server.started or not thread.is_alive():
                break
            time.sleep(0.05)
        assert server.started, "the studio server did not start"
        port = server.servers[0].sockets[0].getsockname()[1]
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(timeout=30)


@contextmanager
def chromium_browser() -> Iterator[Any]:
    """Debian's chromium under Playwright, for the studio pages opened in it —
    one per test, or one a module's tests share (each page in a context of its
    own: its storage, cookies and cache fresh, as in a new browser)."""
    executable = chromium()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(
            executable_path=executable, args=browser.CHROMIUM_ARGS
        )
        try:
            yield launched
        finally:
            launched.close()


@contextmanager
def studio_page(workdir: Path, artifacts: Path, shared: Any = None) -> Iterator[Studio]:
    """A studio on ``workdir`` served in a thread and opened in a chromium tab
    of a new browser context, ready (``body[data-ready]``); the page may log no
    error while it is used. ``shared``: a browser of :func:`chromium_browser`
    to open it in (else one is launched for this page alone)."""
    if shared is None:
        with chromium_browser() as launched, studio_page(workdir, artifacts, launched) as page:
            yield page
        return
    with studio_server(workdir) as url:
        context = shared.new_context(viewport=VIEWPORT)
        try:
            tab = context.new_page()
            page = Studio(tab, artifacts)
            tab.goto(url)
            tab.wait_for_selector('body[data-ready="true"]')
            page.settle()
            yield page
            assert page.errors == []
        finally:
            context.close()


class Studio:
    """One browser tab on the studio, driven as a person would: by dragging."""

    def __init__(self, tab: Any, artifacts: Path) -> None:
        self.tab = tab
        self.artifacts = artifacts
        self.errors: list[str] = []
        tab.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        tab.on("pageerror", lambda e: self.errors.append(str(e)))

    # --- waiting and reading -------------------------------------------------
    def settle(self) -> None:
        self.tab.wait_for_selector('body[data-pending="0"]', state="attached")

    def alert(self) -> str:
        alert = self.tab.locator("#alert")
        return "" if alert.is_hidden() else alert.inner_text()

    def pose(self, name: str) -> tuple[float, float, float, float]:
        element = self.tab.locator(f'#table [data-object="{name}"]')
        values = [element.get_attribute(f"data-{k}") for k in ("x", "y", "z", "yaw")]
        x, y, z, yaw = (float(v) for v in values if v is not None)
        return x, y, z, yaw

    def steps(self) -> int:
        count: int = self.tab.locator('[data-testid="steps"] > li').count()
        return count

    def pixel(self, x: float, y: float) -> tuple[float, float]:
        """The viewport point of world point (x, y), from the documented scale."""
        table = self.tab.locator("#table")
        box = table.bounding_box()
        assert box is not None
        metres_per_pixel = float(table.get_attribute("data-metres-per-pixel") or "nan")
        origin_x, origin_y = (float(v) for v in (table.get_attribute("data-origin") or "").split())
        return (
            box["x"] + (x - origin_x) / metres_per_pixel,
            box["y"] + box["height"] - (y - origin_y) / metres_per_pixel,
        )

    # --- acting ------------------------------------------------------------------
    def drag(
        self,
        name: str,
        x: float,
        y: float,
        yaw: float | None = None,
        grab: tuple[float, float] = (0.0, 0.0),
    ) -> None:
        """Press on ``name`` (``grab`` metres from its centre), move it to (x, y)
        — turning it to ``yaw`` with ``[``/``]`` on the way (5°, Shift 1°) — and
        release it."""
        start_x, start_y, _, _ = self.pose(name)
        mouse = self.tab.mouse
        mouse.move(*self.pixel(start_x + grab[0], start_y + grab[1]))
        mouse.down()
        mouse.move(*self.pixel(x + grab[0], y + grab[1]), steps=4)
        if yaw is not None:
            self.turn(name, yaw)
        mouse.up()
        self.settle()

    def turn(self, name: str, yaw: float) -> None:
        for _ in range(120):
            now = self.pose(name)[3]
            difference = (yaw - now + 180) % 360 - 180
            if abs(difference) < 1e-6:
                return
            key = "BracketRight" if difference > 0 else "BracketLeft"
            self.tab.keyboard.press(key if abs(difference) >= 5 else f"Shift+{key}")
            self.settle()
        raise AssertionError(f"{name} did not turn to {yaw}°")

    def button(self, name: str) -> Any:
        return self.tab.get_by_role("button", name=name, exact=True)

    def view(self, name: str) -> None:
        self.tab.get_by_role("tab", name=name).click()
        self.settle()

    def load(self, file: str) -> None:
        self.tab.get_by_label("Work-folder file").select_option(file)
        self.button("Load file").click()
        self.settle()

    def screenshot(self, view: str) -> None:
        self.settle()
        self.tab.screenshot(path=str(self.artifacts / f"studio-{view}.png"))
        if os.environ.get("DEMOPLAN_STUDIO_SCREENSHOTS") == "1":
            SCREENSHOTS.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(self.artifacts / f"studio-{view}.png", SCREENSHOTS / f"{view}.png")


def scene_of_initial(demonstration: dict[str, Any]) -> dict[str, Any]:
    """A scene file standing where ``demonstration`` started (to load as a start)."""
    objects = {}
    for name, pose in demonstration["initial"].items():
        geometry = demonstration["objects"][name]
        objects[name] = {
            "position": pose["position"],
            "yaw": pose.get("yaw", 0),
            "size": geometry["size"],
            "shape": geometry["shape"],
        }
    return {"format": "demoplan/scene-1", "objects": objects}


def write_json(path: Path, value: Any) -> None:
    path.write_text(json.dumps(value, indent=1), encoding="utf-8")
