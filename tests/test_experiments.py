"""`demoplan experiments`: the paper's tables reproduced, end to end through the CLI."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.experiments import run_experiments
from demoplan.learning.modelfile import load_model


def test_experiments_command_reproduces_the_papers_tables(tmp_path: Path) -> None:
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["experiments", "--out", str(out)])
    assert result.exit_code == 0, result.output
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
    if importlib.util.find_spec("mujoco") is not None:  # Fig. 4, right: the robot builds it
        assert ("2", "Executed by the robot (MuJoCo)") in names
        assert ("2", "Executed on vision (top camera)") in names
        assert summary["execution"][0]["success"] is True
        board = out / "experiment2-blocks-mujoco" / "storyboard.png"
        assert board.read_bytes().startswith(b"\x89PNG")
    for stem in ("experiment1-set-table", "experiment2-blocks"):
        assert (out / f"{stem}-demonstrations.png").read_bytes().startswith(b"\x89PNG")
        assert (out / f"{stem}-plan.png").read_bytes().startswith(b"\x89PNG")
        assert load_model(out / f"{stem}.model.json").states
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temp files left


def test_a_mismatch_with_the_paper_is_reported(tmp_path: Path, monkeypatch: object) -> None:
    import demoplan.experiments as experiments

    changed = list(experiments.PAPER_TABLE_III)
    changed[0] = "A-B-C-D-E-G-F"
    monkeypatch.setattr(experiments, "PAPER_TABLE_III", tuple(changed))  # type: ignore[attr-defined]
    result = run_experiments(tmp_path)
    failed = [c for c in result.checks if not c.ok]
    assert [(c.name, c.paper, c.ours) for c in failed] == [
        ("Sequence 1", "A-B-C-D-E-G-F", "A-B-C-D-E-F-G")
    ]
    assert CliRunner().invoke(app, ["experiments", "--out", str(tmp_path)]).exit_code == 1
