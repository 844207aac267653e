"""Debian's chromium driven by Playwright, for the pages' tests (the report's,
the studio's): skipped where either is missing, unless
DEMOPLAN_REQUIRE_BROWSER=1 (CI, whose .ci/run installs both)."""

from __future__ import annotations

import importlib
import os
import shutil
from collections.abc import Sequence

import pytest

CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def chromium(needs: Sequence[str] = (), what: str = "Playwright and Debian's chromium") -> str:
    """The chromium executable; ``needs``: modules the test imports besides
    Playwright (``what`` names them all in the message)."""
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    try:
        for module in ("playwright.sync_api", *needs):
            importlib.import_module(module)
    except ImportError:
        found = None
    if found is None:
        if os.environ.get("DEMOPLAN_REQUIRE_BROWSER") == "1":
            pytest.fail(f"{what} are required (DEMOPLAN_REQUIRE_BROWSER=1)")
        pytest.skip(f"missing on this machine: {what}")
    return found
