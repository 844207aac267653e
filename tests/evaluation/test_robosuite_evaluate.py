"""``demoplan evaluate MODEL --sim robosuite:ENV --seeds N``: run k is robosuite's
environment after ``reset(k)``, judged by robosuite's ``_check_success()``
beside demoplan; the worst runs' storyboards are rendered by MuJoCo.

The runs need the ``robosuite`` extra (its own environment, as
tests/test_robosuite_run.py) and, on Ray, the ``scale`` extra; where they are
not installed those tests are skipped with the reason (failed with
``DEMOPLAN_REQUIRE_ROBOSUITE=1``). The refusals and the bookkeeping are tested
in any interpreter.
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.commands.evaluation import run_one, settings_from_options
from demoplan.evaluation.engine import RayEngine
from demoplan.evaluation.plan import plan_runs, read_settings, write_plan
from demoplan.evaluation.report import evaluation_markdown
from demoplan.evaluation.results import JOURNAL, ROWS, read_rows, summarise, wilson_interval
from demoplan.evaluation.runs import RunRow
from demoplan.learning.modelfile import load_model, model_to_dict
from tests.support.helpers import EXAMPLES, wait_for_signal_handlers
from tests.support.robosuite_data import RobosuiteDataError, skip_or_fail

INSTALLED = importlib.util.find_spec("robosuite") is not None
MISSING = (
    "robosuite is not installed: pip install 'demoplan[robosuite]' in its own "
    "environment (docs/execution.md)"
)
SEEDS = 2


def _require_robosuite() -> None:
    if not INSTALLED:
        if os.environ.get("DEMOPLAN_REQUIRE_ROBOSUITE") == "1":
            pytest.fail(MISSING)
        pytest.skip(MISSING)


def invoke(*args: str | Path) -> Any:
    return CliRunner().invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def blocks_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Any model: the blocks example's (the refusals come before robosuite)."""
    path = tmp_path_factory.mktemp("blocks") / "model.json"
    result = invoke("learn", EXAMPLES / "blocks" / "demonstrations.json", "-o", path)
    assert result.exit_code == 0, result.stderr
    return path


@pytest.fixture(scope="module")
def stack_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Stack's model learned from robosuite's recordings (tests/support/robosuite_tasks.py)."""
    _require_robosuite()
    from tests.support.robosuite_tasks import task_model

    folder = tmp_path_factory.mktemp("stack")
    try:
        model = task_model("Stack", folder)
    except RobosuiteDataError as exc:
        skip_or_fail(exc)
        raise
    path = folder / "stack.json"
    path.write_text(json.dumps(model_to_dict(model)))
    return path


@pytest.fixture(scope="module")
def serial(stack_model: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``evaluate --sim robosuite:Stack --seeds 2 --workers 0``'s folder."""
    out = tmp_path_factory.mktemp("serial") / "out"
    result = invoke(
        "evaluate", stack_model, "--sim", "robosuite:Stack", "--seeds", SEEDS, "--workers", "0",
        "--out", out, "--json",
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout) == json.loads((out / "summary.json").read_text())
    return out


def _rows(folder: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in (folder / ROWS).read_text().splitlines()]


# -- refusals and bookkeeping (any interpreter) ----------------------------------------------


@pytest.mark.parametrize(
    ("given", "named"),
    [
        (["SCENE"], "SCENE files"),
        (["--random-scenes", "2"], "--random-scenes"),
        (["--clutter", "1"], "--clutter"),
        (["--faults", "drop=0.2"], "--faults"),
    ],
)
def test_options_that_make_scenes_are_refused_in_one_line(
    blocks_model: Path, tmp_path: Path, given: list[str], named: str
) -> None:
    scene = EXAMPLES / "blocks" / "demonstrations.json"
    args = [scene if a == "SCENE" else a for a in given]
    out = tmp_path / "out"
    result = invoke(
        "evaluate", blocks_model, *args, "--sim", "robosuite:Stack", "--workers", "0", "--out", out
    )
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert named in result.stderr and "reset(seed)" in result.stderr
    assert not out.exists()


def test_an_unknown_environment_or_world_is_refused_in_one_line(
    blocks_model: Path, tmp_path: Path
) -> None:
    lift = invoke(
        "evaluate", blocks_model, "--sim", "robosuite:Lift", "--workers", "0",
        "--out", tmp_path / "a",
    )  # fmt: skip
    assert (lift.exit_code, lift.stderr.count("\n")) == (2, 1)
    assert "robosuite:Lift" in lift.stderr and "Stack" in lift.stderr
    scene = EXAMPLES / "blocks" / "demonstrations.json"
    other = invoke(
        "evaluate", blocks_model, scene, "--sim", "gazebo", "--workers", "0",
        "--out", tmp_path / "b",
    )  # fmt: skip
    assert (other.exit_code, other.stderr.count("\n")) == (2, 1)
    assert "robosuite:ENV" in other.stderr
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


@pytest.mark.skipif(INSTALLED, reason="robosuite is installed here")
def test_without_robosuite_the_error_says_what_to_install_and_writes_nothing(
    blocks_model: Path, tmp_path: Path
) -> None:
    out = tmp_path / "out"
    result = invoke(
        "evaluate", blocks_model, "--sim", "robosuite:Stack", "--workers", "0", "--out", out
    )
    assert (result.exit_code, result.stderr.count("\n")) == (2, 1)
    assert "pip install 'demoplan[robosuite]'" in result.stderr
    assert not out.exists()


@pytest.mark.parametrize("seeds", [1, 7])
def test_each_run_is_the_environment_after_reset_of_its_seed(
    blocks_model: Path, tmp_path: Path, seeds: int
) -> None:
    """No scene files: the settings alone, read back on resume, plan run k as seed k."""
    chosen = settings_from_options(
        blocks_model,
        [],
        random_scenes=0,
        seeds=seeds,
        faults=None,
        sim="robosuite:NutAssembly",
        clutter=0,
    )
    write_plan(tmp_path, load_model(blocks_model), chosen)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["evaluation.json"]
    assert read_settings(tmp_path) == chosen
    specs = plan_runs(tmp_path, chosen)
    assert [s.run_id for s in specs] == [f"NutAssembly/seed-{k}" for k in range(seeds)]
    assert {(s.layout, s.sim, s.faults, s.clutter) for s in specs} == {
        (None, "robosuite:NutAssembly", "", False)
    }


def _judged_row(index: int, env: bool, goal: bool) -> RunRow:
    success = env and goal
    return RunRow(
        f"Stack/seed-{index}", "Stack", index, "robosuite:Stack", "",
        "success" if success else "failed", success, env_success=env, demoplan_success=goal,
    )  # fmt: skip


@given(st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=60))
@settings(max_examples=60, deadline=None)
def test_robosuite_s_rate_is_counted_apart_and_a_success_needs_both(
    verdicts: list[tuple[bool, bool]],
) -> None:
    rows = [_judged_row(i, env, goal) for i, (env, goal) in enumerate(verdicts)]
    summary = summarise(rows)
    judged = summary.judged
    assert judged is not None
    env = sum(e for e, _ in verdicts)
    assert judged.env_successes == env
    assert judged.demoplan_successes == sum(g for _, g in verdicts)
    assert summary.successes == sum(e and g for e, g in verdicts) <= env
    assert judged.env_interval == wilson_interval(env, len(rows))
    data = summary.to_json()
    assert data["env_success_rate"] == env / len(rows)
    chosen = settings_from_options(
        EXAMPLES / "blocks" / "demonstrations.json", [], random_scenes=0, seeds=len(rows),
        faults=None, sim="robosuite:Stack", clutter=0,
    )  # fmt: skip
    page = evaluation_markdown(chosen, rows, summary, len(rows))
    assert f"`_check_success()`): {env} of {len(rows)}" in page
    assert "scenes/" not in page  # the repeat commands take no SCENE


def test_runs_in_demoplan_s_own_worlds_have_no_robosuite_verdict() -> None:
    row = RunRow("a/seed-0", "a", 0, "kinematic", "", "success", True)
    assert summarise([row]).judged is None
    assert "env_success_rate" not in summarise([row]).to_json()


# -- runs in robosuite (its extra) -----------------------------------------------------------


def test_stack_over_seeds_here_rows_rates_and_rendered_storyboards(serial: Path) -> None:
    rows = _rows(serial)
    assert [r["run_id"] for r in rows] == [f"Stack/seed-{k}" for k in range(SEEDS)]
    for row in rows:
        assert row["sim"] == "robosuite:Stack"
        assert isinstance(row["env_success"], bool) and isinstance(row["demoplan_success"], bool)
        assert row["success"] == (row["env_success"] and row["demoplan_success"])
        assert row["simulated_s"] > 0
    summary = json.loads((serial / "summary.json").read_text())
    env = sum(r["env_success"] for r in rows)
    assert summary["env_successes"] == env
    assert summary["successes"] == sum(r["success"] for r in rows)
    assert summary["env_wilson_95"] == list(wilson_interval(env, len(rows)))
    assert env == SEEDS  # Stack learned from the recordings: robosuite counts every seed
    page = (serial / "report.html").read_text()
    assert "robosuite" in page and "--sim robosuite:Stack --seed 0" in page
    for row in rows:
        folder = serial / "worst" / row["run_id"]
        assert f"worst/{row['run_id']}/storyboard.png" in page
        frames = sorted(folder.glob("frame-*.png"))
        assert len(frames) == row["actions"] + 2  # the start, each action, the end
        start, end = (_image(frames[0]), _image(frames[-1]))
        assert np.abs(start - end).mean() > 1.0  # the cube moved, the hand came and went
        board = _image(folder / "storyboard.png")
        assert board.std() > 20.0  # not a blank picture


def _image(path: Path) -> np.ndarray:
    import matplotlib.image

    image: np.ndarray = matplotlib.image.imread(path)[..., :3] * 255.0
    return image


def test_the_camera_shows_the_cubes_where_robosuite_has_them() -> None:
    """The frames' picture: each cube's pixels (MuJoCo's segmentation of the same
    view) are its colour — red cubeA, green cubeB — against the table."""
    _require_robosuite()
    import mujoco

    from demoplan.execution.robosuite_frames import CAMERA, HEIGHT, WIDTH, SceneCamera
    from demoplan.execution.robosuite_scene import make_environment

    env = make_environment("Stack", 3)
    camera = SceneCamera(env)
    segmenter = mujoco.Renderer(env.sim.model._model, HEIGHT, WIDTH)
    try:
        picture = camera.picture()
        assert picture is not None, camera.failure
        segmenter.enable_segmentation_rendering()
        options = mujoco.MjvOption()
        options.geomgroup[0] = 0
        segmenter.update_scene(env.sim.data._data, camera=CAMERA, scene_option=options)
        segments = segmenter.render()
        model = env.sim.model._model
        for body, channel in (("cubeA_main", 0), ("cubeB_main", 1)):
            index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
            geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == index]
            mask = np.isin(segments[..., 0], geoms) & (segments[..., 1] == mujoco.mjtObj.mjOBJ_GEOM)
            assert mask.sum() > 100, body
            colour = picture[mask].mean(axis=0)
            assert colour[channel] > 1.5 * np.delete(colour, channel).max(), (body, colour)
            assert picture[~mask].mean() > colour.mean()  # the white table around them
    finally:
        segmenter.close()
        camera.close()
        env.close()


def test_resume_makes_the_missing_run_and_it_repeats_its_row(serial: Path, tmp_path: Path) -> None:
    folder = tmp_path / "resumed"
    shutil.copytree(serial, folder)
    rows = _rows(folder)
    (folder / ROWS).write_text(json.dumps(rows[0]) + "\n")
    result = invoke("evaluate", "--resume", folder, "--workers", "0", "--json")
    assert result.exit_code == 0, result.stderr
    again = read_rows(folder)
    assert again[rows[1]["run_id"]].outcome() == RunRow.from_json(rows[1]).outcome()
    assert len(_rows(folder)) == SEEDS


def test_ctrl_c_keeps_the_finished_rows_and_says_how_to_resume(
    stack_model: Path, tmp_path: Path
) -> None:
    """As in demoplan's own worlds: SIGINT after the first row (of 50 planned)
    ends with exit 130, the finished rows written and the resume command named."""
    out = tmp_path / "eval"
    command = [sys.executable, "-m", "demoplan", "evaluate", str(stack_model)]
    command += ["--sim", "robosuite:Stack", "--seeds", "50", "--workers", "0", "--out", str(out)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wait_for_signal_handlers(process)
    journal = out / JOURNAL
    while process.poll() is None and (not journal.exists() or not journal.read_text()):
        time.sleep(0.05)
    assert process.poll() is None, "the evaluation ended before Ctrl-C"
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=300)
    assert process.returncode == 130, f"exit {process.returncode}: {err[-500:]}"
    assert f"--resume {out} --workers 0" in err
    kept = _rows(out)
    assert 1 <= len(kept) < 50
    assert [r["run_id"] for r in kept] == [f"Stack/seed-{k}" for k in range(len(kept))]
    assert not journal.exists() and not (out / "worst").exists()


def test_a_ray_worker_makes_the_rows_a_serial_run_makes(serial: Path, stack_model: Path) -> None:
    """The runs as Ray tasks on a local Ray of one worker (robosuite built and
    judged in the worker): the serial evaluation's rows, timing aside."""
    pytest.importorskip("ray", reason="evaluating on Ray needs the 'scale' extra")
    chosen = read_settings(serial)
    specs = plan_runs(serial, chosen)
    engine = RayEngine(workers=1)
    with engine.session():
        rows = list(engine.rows(specs, partial(run_one, load_model(stack_model))))
    serial_rows = read_rows(serial)
    assert {r.run_id: r.outcome() for r in rows} == {i: r.outcome() for i, r in serial_rows.items()}
    assert all(r.attempts == 1 for r in rows)
