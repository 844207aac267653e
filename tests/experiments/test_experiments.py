"""`demoplan experiments`: the paper's tables reproduced, end to end through the CLI."""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.experiments import run_experiments
from demoplan.fileio import MANIFEST
from demoplan.learning.modelfile import load_model
from tests.support.browser import CHROMIUM_ARGS, chromium
from tests.support.shared_experiments import RECORDED_STAGES, ExperimentsRun


@pytest.fixture(scope="module")
def report(experiments_run: ExperimentsRun) -> Path:
    """The folder ``demoplan experiments`` wrote (run once for the session,
    tests/support/shared_experiments.py)."""
    out = experiments_run.report  # --out report, run in its parent folder
    assert experiments_run.exit_code == 0, experiments_run.stderr
    assert "Report page: report/report.html" in experiments_run.output
    return out


def test_experiments_command_reproduces_the_papers_tables(report: Path) -> None:
    out = report
    summary = json.loads((out / "summary.json").read_text())
    checks = summary["checks"]
    assert checks and all(c["ok"] for c in checks)
    names = {(c["experiment"].split()[1], c["name"]) for c in checks}
    assert ("1", "State J") in names and ("2", "State D") in names
    report = (out / "report.md").read_text()
    assert "**NO**" not in report
    # Provenance first: how the data were made, before any table a reader could
    # take for independent evidence.
    assert report.index("## Where the data come from") < report.index("| Check |")
    assert "drawn at random until learning" in report
    assert "Constraints (32)" in report and "Constraints (5)" in report
    planning = {p["experiment"].split()[1]: p for p in summary["planning"]}
    assert [c["actions"] for c in planning["2"]["candidates"]] == [10, 8]  # 5 and 4 moves
    assert planning["2"]["chosen"] == 1
    assert ("2", "Plan moves per goal (Fig. 4 scene)") in names
    assert planning["1"]["actions"] and "planning in a new scene" in report
    assert ("1", "Stream segmented into the demonstration's steps") in names
    assert (out / "experiment1-stream.csv").exists()
    if all(importlib.util.find_spec(m) for m in ("mujoco", "mink", "dm_control")):
        # Fig. 4, right: the arm carries out both experiments, touching nothing else
        assert ("1", "Executed by the arm (MuJoCo)") in names
        assert ("2", "Executed by the arm (MuJoCo)") in names
        assert ("2", "Executed on vision (top camera)") in names
        for run in summary["execution"]:
            assert run["success"] is True and run["collisions"] == [], run
        for stem in ("experiment1-set-table", "experiment2-blocks"):
            board = out / f"{stem}-arm" / "storyboard.png"
            assert board.read_bytes().startswith(b"\x89PNG")
    for stem in ("experiment1-set-table", "experiment2-blocks"):
        assert (out / f"{stem}-demonstrations.png").read_bytes().startswith(b"\x89PNG")
        assert (out / f"{stem}-plan.png").read_bytes().startswith(b"\x89PNG")
        assert load_model(out / f"{stem}.model.json").states
    # No temporary file left; the one dotfile is the manifest of what was written.
    hidden = sorted(p.name for p in out.iterdir() if p.name.startswith("."))
    assert hidden == [MANIFEST]
    listed = json.loads((out / MANIFEST).read_text())["files"]
    assert set(listed) == {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()} - {
        MANIFEST
    }


def test_the_report_measures_table_ii_on_fresh_draws(report: Path) -> None:
    """Beside the provenance: fresh draws of Experiment 1's structure learned at
    every precision. At 0.3 mm both readings give Table II every time (as the
    property tests over 1,800 draws found); at the coarsest the paper's fixed
    3 mm ties lose it more often than the estimated precision does."""
    summary = json.loads((report / "summary.json").read_text())["precision"]
    draws, paper, default = summary["draws"], summary["paper_states"], summary["default_places"]
    assert summary["sigmas_mm"][0] == 0.3 and draws >= 10
    assert paper[0] == default[0] == draws
    assert sum(paper) < sum(default)
    text = (report / "report.md").read_text()
    assert text.index("### Fresh draws") < text.index("## Experiment 1")
    assert "![Table II over fresh draws" in text and (report / "experiment1-precision.png").exists()
    assert "## Timings" in text
    if all(importlib.util.find_spec(m) for m in ("imageio_ffmpeg", "mujoco", "mink")):
        # Fig. 4, right, as videos: both arm runs, embedded in the page too.
        for stem in ("experiment1-set-table", "experiment2-blocks"):
            assert (report / f"{stem}-arm.mp4").read_bytes()[4:8] == b"ftyp"
            assert f'<video controls width="480" src="{stem}-arm.mp4">' in text
        page = (report / "report.html").read_text()
        assert page.count('src="data:video/mp4;base64,') == 2


def test_a_mismatch_with_the_paper_is_reported(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, experiments_run: ExperimentsRun
) -> None:
    import demoplan.experiments as experiments

    changed = list(experiments.PAPER_TABLE_III)
    changed[0] = "A-B-C-D-E-G-F"
    monkeypatch.setattr(experiments, "PAPER_TABLE_III", tuple(changed))
    # The arm (most of the minutes) is given the very same model and scene as in
    # the session's run, which the replay checks: its runs are that run's. So are
    # the segmentation and the fresh draws (called with the same arguments; they
    # read neither table the test changes): learning and planning run again.
    monkeypatch.setattr(experiments, "execute_experiment", experiments_run.replaying_the_arm())
    for stage in RECORDED_STAGES:
        monkeypatch.setattr(experiments, stage, experiments_run.replaying(stage))
    result = run_experiments(tmp_path)
    failed = [c for c in result.checks if not c.ok]
    assert [(c.name, c.paper, c.ours) for c in failed] == [
        ("Sequence 1", "A-B-C-D-E-G-F", "A-B-C-D-E-F-G")
    ]
    # The command on that result (not a second run of the experiments, which
    # takes minutes): exit 1, one line naming what differs.
    monkeypatch.setattr(experiments, "run_experiments", lambda folder, progress=None: result)
    answer = CliRunner().invoke(app, ["experiments", "--out", str(tmp_path / "again")])
    assert answer.exit_code == 1, answer.output
    assert "1 results differ from the paper (Experiment 1 Sequence 1)" in answer.output


# The HTML page: Debian's chromium driven by Playwright (skipped where either is
# missing, unless DEMOPLAN_REQUIRE_BROWSER=1 as in CI, whose .ci/run installs both).
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"


def test_the_report_page_is_one_file_with_every_image_inside(report: Path) -> None:
    page = (report / "report.html").read_text(encoding="utf-8")
    markdown = (report / "report.md").read_text(encoding="utf-8")
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", markdown)
    assert len(images) >= 5
    assert page.count('src="data:image/png;base64,') == len(images)
    assert "<table>" in page and "Where the data come from" in page


def test_embedded_files_get_their_media_type_whatever_the_machine_s_mime_tables(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The page is the same on every machine: the media types are the
    report's own, not the machine's ``/etc/mime.types`` (which the command
    would otherwise open; a table mapping ``.png`` to text is not followed)."""
    import mimetypes

    from demoplan.experiments.report_html import markdown_to_html

    for name in ("a.png", "b.SVG", "c.jpeg", "d.bin"):
        (tmp_path / name).write_bytes(b"x")
    (tmp_path / "e.mp4").write_bytes(b"x")
    markdown = '![a](a.png) ![b](b.SVG) ![c](c.jpeg) ![d](d.bin)\n\n<video src="e.mp4"></video>\n'
    page = markdown_to_html(markdown, tmp_path, "t")
    kinds = re.findall(r'src="data:([^;]+);base64,', page)
    assert kinds == ["image/png", "image/svg+xml", "image/jpeg", "application/octet-stream"] + [
        "video/mp4"
    ]
    monkeypatch.setattr(mimetypes, "guess_type", lambda *a, **k: ("text/plain", None))
    assert markdown_to_html(markdown, tmp_path, "t") == page


def test_the_report_page_opens_in_headless_chromium(report: Path) -> None:
    executable = chromium()
    from playwright.sync_api import sync_playwright

    errors: list[str] = []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS)
        try:
            tab = browser.new_page(viewport={"width": 1200, "height": 900})
            tab.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            tab.on("pageerror", lambda e: errors.append(str(e)))
            tab.goto((report / "report.html").as_uri())
            tab.wait_for_load_state("load")
            broken = tab.evaluate(
                "Array.from(document.images)"
                ".filter(i => !i.complete || i.naturalWidth === 0).map(i => i.alt)"
            )
            count = tab.evaluate("document.images.length")
            heading = tab.inner_text("h1")
            ARTIFACTS.mkdir(exist_ok=True)
            tab.screenshot(path=str(ARTIFACTS / "report-page.png"), full_page=False)
        finally:
            browser.close()
    assert count >= 5
    assert broken == []
    assert errors == []
    assert "the paper's experiments reproduced" in heading
