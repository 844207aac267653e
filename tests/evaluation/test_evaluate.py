"""``demoplan evaluate``: seeded random layouts, one row per run, Ray equal to a
serial run, a killed worker's run retried or recorded, resume after Ctrl-C.

Both paper experiments are evaluated with Ray and serially, with faults in the
kinematic world: experiment 2 over ``DEMOPLAN_EVALUATE_SCENES`` random layouts
(default 10, as docs/execution.md says) × 2 seeds, experiment 1 (whose runs
take seconds each) over 3 × 2 — six runs still spread over both Ray workers,
and a run whose Ray row differs from its serial one, or a row lost or made
twice, fails on any of them. One Ray session with 2 CPUs serves the whole module
(its start-up costs seconds). A command's answer to bad input is asked in
process (``invoke``); a ``demoplan`` process of its own only where the
process is what is tested: Ctrl-C, a terminal, Ray missing from its path."""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.commands import evaluation as evaluation_command
from demoplan.commands.evaluation import engine_for, evaluate, run_one, settings_from_options
from demoplan.documents.demonstrations import load_demonstrations
from demoplan.errors import InputError, UsageError
from demoplan.evaluation.engine import RayEngine, SerialEngine
from demoplan.evaluation.results import JOURNAL, ROWS, read_rows, wilson_interval
from demoplan.evaluation.runs import RunRow, RunSpec
from demoplan.evaluation.scenes import (
    LayoutSettings,
    random_scene,
    random_scene_document,
    workspace_box,
)
from demoplan.fileio import dump_json
from demoplan.learning import learn
from demoplan.learning.modelfile import load_model, model_to_dict
from demoplan.model import TaskModel
from tests.support.cli import invoke
from tests.support.helpers import interrupt_stopped, stopped_when, wait_for_signal_handlers
from tests.support.lunch_box import lunch_demonstrations

ROOT = Path(__file__).resolve().parents[2]
EXPERIMENTS = {
    "exp1": ROOT / "examples" / "set_table",
    "exp2": ROOT / "examples" / "blocks" / "demonstrations.json",
}
SCENES = int(os.environ.get("DEMOPLAN_EVALUATE_SCENES", "10"))
RAY_SCENES = {"exp1": min(SCENES, 3), "exp2": SCENES}
"""Random layouts per experiment in test_ray_equals_a_serial_run (module docstring)."""
FAULTS = "drop=0.2,displace=0.1"


@pytest.fixture(scope="module")
def model_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("models")
    files = {}
    for key, demos in EXPERIMENTS.items():
        path = folder / f"{key}.json"
        path.write_text(dump_json(model_to_dict(learn(load_demonstrations([demos])))))
        files[key] = path
    return files


@pytest.fixture(scope="module")
def ray_session() -> Iterator[Any]:
    ray = pytest.importorskip("ray")
    ray.init(
        address="local",  # a new Ray: never a cluster that runs beside the tests
        num_cpus=2,
        include_dashboard=False,
        log_to_driver=False,
        configure_logging=False,
    )
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])  # the crashing runners
    yield ray
    ray.shutdown()


@pytest.fixture
def one_storyboard(monkeypatch: pytest.MonkeyPatch) -> None:
    """An evaluation in process draws the storyboard of its worst run only, not
    of its five worst: each is that run made again frame by frame, 2–8 s of CPU,
    most of an evaluation of a few kinematic runs. For tests of the rows, the
    engines, the journal and resuming; every step of an evaluation still runs
    (a storyboard drawn after the runs, its link in the page).
    test_the_worst_runs_link_their_storyboard_as_demoplan_run_frames_draws_it
    checks the five."""
    monkeypatch.setattr(evaluation_command, "STORYBOARDS", 1)


@pytest.fixture
def no_storyboards(monkeypatch: pytest.MonkeyPatch) -> None:
    """An evaluation in process draws no storyboard: for tests of what a
    storyboard does not touch (a folder refused, which runs a resume makes,
    a killed worker's run made again)."""
    _no_storyboard(monkeypatch)


def _no_storyboard(monkeypatch: pytest.MonkeyPatch) -> None:
    """The evaluations from here on draw no storyboard: for a second evaluation
    of the same runs in a test (one_storyboard's), whose worst run's storyboard
    would be drawn again, the same way, after its engine's session."""
    monkeypatch.setattr(evaluation_command, "STORYBOARDS", 0)


def _rows_file(folder: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in (folder / ROWS).read_text().splitlines()]


@pytest.mark.parametrize("experiment", sorted(EXPERIMENTS))
@pytest.mark.usefixtures("one_storyboard")
def test_ray_equals_a_serial_run(
    experiment: str,
    model_files: dict[str, Path],
    ray_session: Any,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    scenes = RAY_SCENES[experiment]
    options = {"random_scenes": scenes, "seeds": 2, "faults": FAULTS, "sim": "kinematic"}
    chosen = settings_from_options(model_files[experiment], [], clutter=0, **options)  # type: ignore[arg-type]
    if experiment == "exp1":  # a set-table storyboard is ~5 s of CPU: exp2's is drawn
        _no_storyboard(monkeypatch)
    serial = evaluate(chosen, tmp_path / "serial", engine=SerialEngine())
    if experiment == "exp2":
        assert [b.endswith("storyboard.png") for b in serial.storyboards.values()] == [True]
    _no_storyboard(monkeypatch)  # the worst run's, drawn once (serial's): its rows are Ray's
    parallel = evaluate(chosen, tmp_path / "ray", engine=RayEngine(max_retries=1))
    assert serial.planned == parallel.planned == 2 * scenes
    for done in (serial, parallel):
        ids = [row["run_id"] for row in _rows_file(done.folder)]
        assert sorted(ids) == sorted(
            {f"random-{s}/seed-{2 * s + k}" for s in range(scenes) for k in (0, 1)}
        )
        assert not (done.folder / JOURNAL).exists()
    assert [r.outcome() for r in serial.rows] == [r.outcome() for r in parallel.rows]
    assert all(r.attempts == 1 for r in parallel.rows)
    assert sum(sum(r.injected.values()) for r in serial.rows) > 0  # faults were injected
    assert serial.summary.successes == serial.summary.runs  # recoverable faults only


def _crash_once(marker: Path, victim: str, model: TaskModel, spec: RunSpec) -> RunRow:
    """A run whose worker dies on its first attempt (the test's kill)."""
    if spec.run_id == victim and not marker.exists():
        marker.touch()
        os._exit(9)
    return run_one(model, spec)


def _hang_once(folder: Path, victim: str, model: TaskModel, spec: RunSpec) -> RunRow:
    """The victim's first attempt says its worker's process id and waits to be killed."""
    marker = folder / "pid"
    if spec.run_id == victim and not marker.exists():
        (folder / "pid.partial").write_text(str(os.getpid()))
        (folder / "pid.partial").rename(marker)
        time.sleep(120)
    return run_one(model, spec)


@pytest.mark.usefixtures("no_storyboards")
def test_a_worker_killed_from_outside_mid_run_makes_its_run_start_again(
    model_files: dict[str, Path], ray_session: Any, tmp_path: Path
) -> None:
    model = load_model(model_files["exp2"])
    chosen = settings_from_options(
        model_files["exp2"], [], random_scenes=4, seeds=2, faults=FAULTS, sim="kinematic", clutter=0
    )

    def kill_the_worker() -> None:
        while not (tmp_path / "pid").exists():
            time.sleep(0.02)
        os.kill(int((tmp_path / "pid").read_text()), signal.SIGKILL)

    killer = threading.Thread(target=kill_the_worker, daemon=True)
    killer.start()
    runner = partial(_hang_once, tmp_path, "random-2/seed-5", model)
    done = evaluate(chosen, tmp_path / "eval", engine=RayEngine(max_retries=2), runner=runner)
    killer.join(timeout=1)
    assert len(done.rows) == len({r.run_id for r in done.rows}) == done.planned == 8
    killed = {r.run_id: r for r in done.rows}["random-2/seed-5"]
    assert (killed.status, killed.attempts) == ("success", 2)
    serial = evaluate(chosen, tmp_path / "serial", engine=SerialEngine())
    assert [r.outcome() for r in done.rows] == [r.outcome() for r in serial.rows]


def _crash_always(victim: str, model: TaskModel, spec: RunSpec) -> RunRow:
    if spec.run_id == victim:
        os._exit(9)
    return run_one(model, spec)


@pytest.mark.usefixtures("no_storyboards")
def test_a_killed_worker_s_run_is_retried_or_an_error_row(
    model_files: dict[str, Path], ray_session: Any, tmp_path: Path
) -> None:
    model = load_model(model_files["exp2"])
    chosen = settings_from_options(
        model_files["exp2"], [], random_scenes=3, seeds=2, faults=FAULTS, sim="kinematic", clutter=0
    )
    once = partial(_crash_once, tmp_path / "killed", "random-1/seed-2", model)
    done = evaluate(chosen, tmp_path / "once", engine=RayEngine(max_retries=2), runner=once)
    assert (tmp_path / "killed").exists()
    assert len(done.rows) == len({r.run_id for r in done.rows}) == 6
    retried = {r.run_id: r for r in done.rows}["random-1/seed-2"]
    assert (retried.status, retried.attempts) == ("success", 2)
    always = partial(_crash_always, "random-2/seed-5", model)
    done = evaluate(chosen, tmp_path / "always", engine=RayEngine(max_retries=1), runner=always)
    assert len(done.rows) == len({r.run_id for r in done.rows}) == 6
    lost = {r.run_id: r for r in done.rows}["random-2/seed-5"]
    assert (lost.status, lost.attempts) == ("error", 2)
    assert "worker died" in lost.reason
    assert sum(r.status == "success" for r in done.rows) == 5


@pytest.mark.usefixtures("no_storyboards")
def test_resume_after_ctrl_c_makes_only_the_missing_runs(
    model_files: dict[str, Path], tmp_path: Path
) -> None:
    model = load_model(model_files["exp2"])
    chosen = settings_from_options(
        model_files["exp2"], [], random_scenes=3, seeds=2, faults=FAULTS, sim="kinematic", clutter=1
    )
    made: list[str] = []

    def runner(spec: RunSpec) -> RunRow:
        made.append(spec.run_id)
        return run_one(model, spec)

    def stop_after_two(row: RunRow, done: int, planned: int) -> None:
        if done == 2:
            raise KeyboardInterrupt

    out = tmp_path / "eval"
    with pytest.raises(KeyboardInterrupt):
        evaluate(chosen, out, runner=runner, on_row=stop_after_two)
    assert [r["run_id"] for r in _rows_file(out)] == made == ["random-0/seed-0", "random-0/seed-1"]
    with pytest.raises(UsageError, match="--resume"):
        evaluate(chosen, out, runner=runner)
    made.clear()
    drawn = (out / "scenes" / "random-2.json").read_text()
    (out / "scenes" / "random-2.json").unlink()  # as a stop while the scenes were written
    done = evaluate(None, out, resume=True, runner=runner)
    assert (out / "scenes" / "random-2.json").read_text() == drawn
    assert made == [f"random-{s}/seed-{2 * s + k}" for s in (1, 2) for k in (0, 1)]
    assert (done.made, done.planned) == (4, 6)
    assert [r["run_id"] for r in _rows_file(out)] == [
        f"random-{s}/seed-{2 * s + k}" for s in range(3) for k in (0, 1)
    ]
    assert set(read_rows(out)) == {r.run_id for r in done.rows}
    assert (out / "scenes" / "random-2.json").is_file()


def test_without_ray_evaluate_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(UsageError, match=r"demoplan\[scale\]"):
        engine_for(2, None)
    assert isinstance(engine_for(0, None), SerialEngine)
    with pytest.raises(UsageError, match="one of them"):
        engine_for(2, "ray://head:10001")


@settings(max_examples=40, deadline=None)
@given(
    experiment=st.sampled_from(sorted(EXPERIMENTS)),
    seed=st.integers(0, 2**31),
    clutter=st.integers(0, 2),
)
def test_a_random_layout_is_a_function_of_its_seed_and_can_be_grasped(
    experiment: str, seed: int, clutter: int
) -> None:
    from demoplan.model import footprint

    model = _model(experiment)
    layout = LayoutSettings(clutter=clutter)
    document = random_scene_document(model, seed, layout)
    assert document == random_scene_document(model, seed, layout)
    scene = random_scene(model, seed, layout)
    assert set(scene.names) >= set(model.object_types())
    assert len(scene.names) == len(model.object_types()) + clutter
    (x0, y0), (x1, y1) = workspace_box(model, layout.margin)
    outlines = {}
    for obj in scene.objects:
        assert obj.geometry is not None
        x, y, z = obj.pose.position
        assert x0 <= x <= x1 and y0 <= y <= y1
        outlines[obj.name] = (z, footprint(obj.geometry, obj.pose.position, obj.pose.yaw))
    on_table = [(n, o) for n, (z, o) in outlines.items() if z < 1e-9]
    reach = 2 * layout.finger_radius + 0.01 - 1e-6  # a gripper's reach apart
    for i, (a, first) in enumerate(on_table):
        for b, second in on_table[i + 1 :]:
            assert first.distance(second) >= reach, (a, b)
    for obj in scene.objects:  # a stacked object stands on a top of exactly its height
        z = obj.pose.position[2]
        if z > 1e-9:
            below = [
                o
                for o in scene.objects
                if o.geometry is not None
                and abs(o.pose.position[2] + o.geometry.size[2] - z) < 1e-6
                and outlines[o.name][1].intersects(outlines[obj.name][1])
            ]
            assert below, obj.name


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31), clutter=st.integers(0, 2))
def test_a_random_layout_moves_and_turns_the_lunch_box_keeping_its_shape(
    seed: int, clutter: int
) -> None:
    """The lunch box stood at three places in the demonstrations: a random
    layout moves and turns it (any yaw), keeps its shape and size, its whole
    outline in the workspace, and no object on the table within a gripper's
    reach of it; the layout is a function of its seed."""
    from demoplan.model import footprint

    model = _lunch_model()
    layout = LayoutSettings(clutter=clutter)
    document = random_scene_document(model, seed, layout)
    assert document == random_scene_document(model, seed, layout)
    box = document["landmarks"]["lunchbox"]
    assert (box["shape"], box["size"]) == ("box", [0.26, 0.18, 0.02])
    scene = random_scene(model, seed, layout)
    (pose,) = (p for name, p in scene.landmarks if name == "lunchbox")
    taught = [dict(d.landmarks)["lunchbox"] for d in model.demonstrations]
    assert all(math.dist(pose.position, t.position) > 1e-9 for t in taught)  # moved
    outline = footprint(dict(scene.landmark_geometry)["lunchbox"], pose.position, pose.yaw)
    (x0, y0), (x1, y1) = workspace_box(model, layout.margin)
    bx0, by0, bx1, by1 = outline.bounds
    assert x0 - 1e-9 <= bx0 and bx1 <= x1 + 1e-9 and y0 - 1e-9 <= by0 and by1 <= y1 + 1e-9
    reach = 2 * layout.finger_radius + 0.01 - 1e-6
    for obj in scene.objects:
        assert obj.geometry is not None
        if obj.pose.position[2] < 1e-9:
            at = footprint(obj.geometry, obj.pose.position, obj.pose.yaw)
            assert at.distance(outline) >= reach, obj.name


def test_random_layouts_turn_the_lunch_box_every_way_and_keep_a_still_landmark() -> None:
    model = _lunch_model()
    yaws = [
        random_scene_document(model, seed)["landmarks"]["lunchbox"]["yaw"] for seed in range(20)
    ]
    assert min(yaws) < -90 and max(yaws) > 90  # turned every way, not only as taught
    still = learn(
        [replace(d, landmarks=model.demonstrations[0].landmarks) for d in lunch_demonstrations()]
    )
    boxes = [random_scene_document(still, seed)["landmarks"]["lunchbox"] for seed in range(3)]
    taught = dict(model.demonstrations[0].landmarks)["lunchbox"]
    for box in boxes:  # it stood still: where it stood, with its shape
        assert box["position"] == pytest.approx(list(taught.position))
        assert box["size"] == [0.26, 0.18, 0.02]


def _lunch_model() -> TaskModel:
    if "lunch" not in _MODELS:
        _MODELS["lunch"] = learn(lunch_demonstrations())
    return _MODELS["lunch"]


_MODELS: dict[str, TaskModel] = {}


def _model(experiment: str) -> TaskModel:
    if experiment not in _MODELS:
        _MODELS[experiment] = learn(load_demonstrations([EXPERIMENTS[experiment]]))
    return _MODELS[experiment]


@settings(max_examples=200, deadline=None)
@given(n=st.integers(0, 10_000), data=st.data())
def test_the_wilson_interval_holds_the_rate(n: int, data: st.DataObject) -> None:
    k = data.draw(st.integers(0, n))
    low, high = wilson_interval(k, n)
    assert 0.0 <= low <= high <= 1.0
    if n:
        assert low - 1e-12 <= k / n <= high + 1e-12


NO_STORYBOARDS = (
    "import runpy, demoplan.commands.evaluation as command; command.STORYBOARDS = 0; "
    "runpy.run_module('demoplan', run_name='__main__', alter_sys=True)"
)
"""``python -m demoplan`` whose evaluations draw no storyboard, for a process
whose storyboards a test does not read (each is its run made again frame by
frame; the step is drawn in process by the tests that use one_storyboard, and
its five by
test_the_worst_runs_link_their_storyboard_as_demoplan_run_frames_draws_it)."""


def _demoplan(
    *args: str, env: dict[str, str] | None = None, storyboards: bool = True
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, *(["-m", "demoplan"] if storyboards else ["-c", NO_STORYBOARDS]), *args],
        capture_output=True,
        text=True,
        env={**os.environ, **(env or {})},
        timeout=300,
    )


@pytest.mark.parametrize("workers", ["0", "2"])  # here, and on a local Ray of its own
def test_ctrl_c_keeps_the_finished_rows_and_resume_makes_the_others(
    model_files: dict[str, Path], tmp_path: Path, workers: str
) -> None:
    if workers != "0":
        pytest.importorskip("ray")
    out = tmp_path / "eval"
    # The evaluation runs in short steps, stopped between them (stopped_when), and
    # the signal goes while it is stopped after its third row: it cannot finish
    # first however long a loaded machine pauses this test, so 40 runs suffice
    # (more than the three kept plus Ray's eight in flight).
    scenes = "20"
    args = ["--random-scenes", scenes, "--seeds", "2", "--faults", FAULTS, "--workers", workers]
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "demoplan",
            "evaluate",
            str(model_files["exp2"]),
            *args,
            "--out",
            str(out),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    wait_for_signal_handlers(process)
    journal = out / JOURNAL

    def three_rows() -> bool:
        return journal.exists() and journal.read_text().count("\n") >= 3

    assert stopped_when(process, three_rows), "the evaluation ended before Ctrl-C"
    interrupt_stopped(process)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 130, f"exit {process.returncode}: {err[-500:]}"
    assert f"--resume {out}" in err
    total = 2 * int(scenes)
    kept = (out / ROWS).read_text().splitlines()
    assert 3 <= len(kept) < total
    assert not journal.exists()
    done = _demoplan(
        "evaluate", "--resume", str(out), "--workers", workers, "--json", storyboards=False
    )
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["runs"] == total
    rows = (out / ROWS).read_text().splitlines()
    ids = [json.loads(line)["run_id"] for line in rows]
    assert len(ids) == len(set(ids)) == total
    assert set(kept) <= set(rows)  # the finished rows kept as they were


def test_evaluate_s_usage_errors_are_one_line(model_files: dict[str, Path], tmp_path: Path) -> None:
    blocker = tmp_path / "no-ray" / "ray"
    blocker.mkdir(parents=True)
    (blocker / "__init__.py").write_text("raise ImportError('ray is not installed')\n")
    path = f"{blocker.parent}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"
    model = str(model_files["exp2"])
    no_ray = _demoplan(
        "evaluate",
        model,
        "--random-scenes",
        "1",
        "--out",
        str(tmp_path / "a"),
        env={"PYTHONPATH": path},
    )
    assert no_ray.returncode == 2
    assert no_ray.stderr.count("\n") == 1
    assert "pip install 'demoplan[scale]'" in no_ray.stderr
    both = invoke("evaluate", model, "--resume", str(tmp_path / "a"))
    assert (both.exit_code, both.stderr.count("\n")) == (2, 1)
    nothing = invoke("evaluate", model, "--out", str(tmp_path / "b"), "--workers", "0")
    assert (nothing.exit_code, nothing.stderr.count("\n")) == (2, 1)
    assert "no scenes" in nothing.stderr
    too_many = invoke(
        "evaluate", model, "--random-scenes", "500001", "--seeds", "2", "--out", str(tmp_path / "c")
    )
    assert (too_many.exit_code, too_many.stderr.count("\n")) == (2, 1)
    assert "--random-scenes: 1,000,002 runs (scenes × seeds); at most 1,000,000" in too_many.stderr
    scene = tmp_path / "scene.json"
    scene.write_text((ROOT / "examples" / "scenes" / "pyramid-fig4.json").read_text())
    for seeds, named in (("99999999999999999999", "--seeds"), ("600000", "--seeds")):
        args = ("evaluate", model, str(scene), "--random-scenes", "1", "--seeds", seeds)
        many_seeds = invoke(*args, "--out", str(tmp_path / "c"))
        # the seeds made them many: named, not --random-scenes (as before)
        assert (many_seeds.exit_code, many_seeds.stderr.count("\n")) == (2, 1)
        assert f"{named}: " in many_seeds.stderr and "random" not in many_seeds.stderr
    clutter = invoke(
        "evaluate", model, "--random-scenes", "1", "--clutter", "21", "--out", str(tmp_path / "d")
    )
    assert (clutter.exit_code, clutter.stderr.count("\n")) == (2, 1)
    assert "--clutter: at most 20 expected" in clutter.stderr
    assert not (tmp_path / "c").exists() and not (tmp_path / "d").exists()


@pytest.fixture(scope="module")
def finished_evaluation(
    model_files: dict[str, Path], tmp_path_factory: pytest.TempPathFactory
) -> Path:
    """A finished ``demoplan evaluate`` folder (one random scene), which tests copy."""
    out = tmp_path_factory.mktemp("finished") / "eval"
    with pytest.MonkeyPatch.context() as monkeypatch:
        _no_storyboard(monkeypatch)  # the tests read its settings file
        made = invoke(
            "evaluate",
            str(model_files["exp2"]),
            "--random-scenes",
            "1",
            "--workers",
            "0",
            "--out",
            out,
        )
    assert made.exit_code == 0, made.stderr
    return out


@pytest.mark.parametrize(
    ("field", "value", "expected"),
    [
        (
            "random_scenes",
            10**12,
            "1,000,000,000,000 runs (scenes × seeds); at most 1,000,000 expected",
        ),
        ("random_scenes", "many", "Input should be a valid integer (got 'many')"),
        ("seeds", 0, "Input should be greater than or equal to 1 (got 0)"),
        ("clutter", True, "Input should be a valid integer (got True)"),
    ],
)
def test_a_settings_file_out_of_bounds_is_refused_on_resume(
    finished_evaluation: Path, tmp_path: Path, field: str, value: Any, expected: str
) -> None:
    out = tmp_path / "eval"
    shutil.copytree(finished_evaluation, out)
    settings = json.loads((out / "evaluation.json").read_text())
    settings[field] = value
    (out / "evaluation.json").write_text(json.dumps(settings))
    resumed = invoke("evaluate", "--resume", str(out), "--workers", "0")
    assert resumed.exit_code == 1
    assert resumed.stderr.startswith(f"demoplan: error: {out / 'evaluation.json'}: {field}: ")
    assert expected in resumed.stderr and resumed.stderr.count("\n") == 1


def test_every_run_repeats_with_demoplan_run_and_the_page_sums_them_up(
    model_files: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from demoplan.budget import Budget
    from demoplan.commands.execution import run
    from demoplan.evaluation.report import repeat_command
    from demoplan.execution.executor import ExecutionSettings
    from demoplan.execution.faults import parse_faults

    chosen = settings_from_options(  # 4 runs of seconds each, a drop among their faults
        model_files["exp1"], [], random_scenes=2, seeds=2, faults=FAULTS, sim="kinematic", clutter=1
    )
    _no_storyboard(monkeypatch)  # the page's rows and repeat commands are read, no storyboard
    done = evaluate(chosen, tmp_path / "eval")
    for row in done.rows:
        report = run(
            model_files["exp1"],
            done.folder / "scenes" / f"{row.scene}.json",
            faults=parse_faults(row.faults),
            seed=row.seed,
            clutter=True,
            settings=ExecutionSettings(budget=Budget(timeout=float("inf"))),  # --timeout inf
        )
        assert (report.success, report.replans, len(report.actions)) == (
            row.success,
            row.replans,
            row.actions,
        )
        command = repeat_command(chosen, row)
        assert f"scenes/{row.scene}.json --sim kinematic --seed {row.seed} --timeout inf" in command
        assert command.endswith("--clutter")
    page = done.report.read_text()
    low, high = done.summary.interval
    assert f"{low:.1%} – {high:.1%}" in page
    assert "Injected → detected" in page and "<td>drop</td>" in page
    assert page.count("demoplan run ") == len(done.rows)  # 4 runs: every one among the worst
    scene = json.loads((done.folder / "scenes" / "random-0.json").read_text())
    assert "clutter-1" in scene["objects"]


def test_bad_input_is_one_line_naming_the_file_and_writes_nothing(
    model_files: dict[str, Path], tmp_path: Path
) -> None:
    lacking = tmp_path / "lacking.json"
    lacking.write_text(
        json.dumps(
            {
                "format": "demoplan/scene-1",
                "objects": {"wood": {"position": [0.3, 0.04, 0.0]}},
            }
        )
    )
    out = tmp_path / "out"
    done = invoke(
        "evaluate", str(model_files["exp2"]), str(lacking), "--workers", "0", "--out", str(out)
    )
    assert (done.exit_code, done.stderr.count("\n")) == (1, 1)
    assert str(lacking) in done.stderr and "green" in done.stderr
    assert not out.exists()
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "evaluation.json").write_text("{oops")
    done = invoke("evaluate", "--resume", str(broken), "--workers", "0")
    assert (done.exit_code, done.stderr.count("\n")) == (1, 1)
    assert "evaluation.json" in done.stderr


class _NoSession(SerialEngine):
    """An engine that must not be started: a cluster started for a scene that is
    then refused cost 5–10 s of Ray's start-up for nothing."""

    def session(self) -> Any:
        raise AssertionError("the engine was started before the scenes were read")


@pytest.mark.parametrize("content", ["", "{oops", '{"format": "demoplan/scene-1", "objects": {}}'])
def test_a_bad_scene_is_refused_before_any_engine_starts(
    model_files: dict[str, Path], tmp_path: Path, content: str
) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text(content)
    chosen = settings_from_options(
        model_files["exp2"],
        [bad],
        random_scenes=1,
        seeds=1,
        faults=None,
        sim="kinematic",
        clutter=0,
    )
    with pytest.raises(InputError) as refused:
        evaluate(chosen, tmp_path / "out", engine=_NoSession())
    assert "bad.json" in str(refused.value)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("experiment", sorted(EXPERIMENTS))
def test_some_layouts_stack_objects_and_some_do_not(experiment: str) -> None:
    model = _model(experiment)
    stacked = [
        any(o.pose.position[2] > 0 for o in random_scene(model, seed).objects) for seed in range(20)
    ]
    assert any(stacked) and not all(stacked)
    never = LayoutSettings(stack_probability=0.0)
    assert not any(
        o.pose.position[2] > 0 for s in range(5) for o in random_scene(model, s, never).objects
    )


@pytest.mark.usefixtures("no_storyboards")
def test_out_is_a_new_or_empty_folder(model_files: dict[str, Path], tmp_path: Path) -> None:
    chosen = settings_from_options(
        model_files["exp2"], [], random_scenes=1, seeds=1, faults="", sim="kinematic", clutter=0
    )
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "runs.jsonl").write_text("my own notes\n")
    with pytest.raises(InputError, match="not empty"):
        evaluate(chosen, mine)
    assert (mine / "runs.jsonl").read_text() == "my own notes\n"
    with pytest.raises(InputError, match="not a folder"):
        evaluate(chosen, mine / "runs.jsonl")
    empty = tmp_path / "empty"
    empty.mkdir()
    assert evaluate(chosen, empty).planned == 1


def test_a_terminal_sees_runs_done_successes_and_the_time_left(
    model_files: dict[str, Path], tmp_path: Path
) -> None:
    import pty

    master, terminal = pty.openpty()
    args = ["--random-scenes", "5", "--seeds", "2", "--workers", "0", "--out", str(tmp_path / "o")]
    process = subprocess.Popen(  # no storyboard (NO_STORYBOARDS)
        [sys.executable, "-c", NO_STORYBOARDS, "evaluate", str(model_files["exp2"]), *args],
        stdout=subprocess.PIPE,
        stderr=terminal,
        env={**os.environ, "COLUMNS": "120", "TERM": "xterm"},
    )
    os.close(terminal)
    seen = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the terminal closed
            break
        if not chunk:
            break
        seen += chunk
    assert process.wait(timeout=120) == 0
    text = seen.decode(errors="replace")
    assert "evaluating" in text and "10/10" in text
    assert "10/10 succeeded" in text
    assert re.search(r"\d:\d\d:\d\d", text)  # the time left


@pytest.mark.usefixtures("no_storyboards")
def test_a_journal_torn_by_a_killed_evaluation_is_resumed(
    model_files: dict[str, Path], tmp_path: Path
) -> None:
    chosen = settings_from_options(
        model_files["exp2"], [], random_scenes=2, seeds=2, faults=FAULTS, sim="kinematic", clutter=0
    )
    out = tmp_path / "eval"
    full = evaluate(chosen, out)
    lines = (out / ROWS).read_text().splitlines(keepends=True)
    (out / ROWS).unlink()  # as if killed (SIGKILL) while writing its third row
    (out / JOURNAL).write_text("".join(lines[:2]) + lines[2][:40])
    done = evaluate(None, out, resume=True)
    assert done.made == 2
    assert [r.outcome() for r in done.rows] == [r.outcome() for r in full.rows]
    assert not (out / JOURNAL).exists()


def test_rows_added_after_a_torn_line_read_back(tmp_path: Path) -> None:
    from demoplan.evaluation.results import Journal

    rows = [RunRow(f"s/seed-{k}", "s", k, "kinematic", "", "success", True) for k in range(3)]
    text = "".join(json.dumps(r.to_json()) + "\n" for r in rows[:2])
    (tmp_path / JOURNAL).write_text(text + text[:30])  # a row torn by a kill
    journal = Journal(tmp_path)
    journal.add(rows[2])
    journal.close()
    assert list(read_rows(tmp_path).values()) == rows


def test_the_worst_runs_link_their_storyboard_as_demoplan_run_frames_draws_it(
    model_files: dict[str, Path], tmp_path: Path
) -> None:
    from html.parser import HTMLParser

    from demoplan.budget import Budget
    from demoplan.commands.execution import run
    from demoplan.execution.executor import ExecutionSettings
    from demoplan.execution.faults import parse_faults

    pytest.importorskip("matplotlib")
    chosen = settings_from_options(
        model_files["exp2"],
        [],
        random_scenes=1,
        seeds=2,
        faults="grasp=0.9",
        sim="kinematic",
        clutter=0,
    )
    done = evaluate(chosen, tmp_path / "eval")
    assert not any(r.success for r in done.summary.worst)  # failures, each with a storyboard
    assert set(done.storyboards) == {r.run_id for r in done.summary.worst[:5]}

    found: list[str] = []

    class Links(HTMLParser):
        def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
            found.extend(v or "" for k, v in attrs if tag == "a" and k == "href")

    Links().feed(done.report.read_text())
    linked = [h for h in found if h.endswith("storyboard.png")]
    assert linked == [f"worst/{r.run_id}/storyboard.png" for r in done.summary.worst[:5]]
    assert all((done.folder / h).is_file() for h in linked)
    assert all(f"]({h})" in (done.folder / "report.md").read_text() for h in linked)
    row = done.summary.worst[0]
    again = tmp_path / "again"
    run(
        model_files["exp2"],
        done.folder / "scenes" / f"{row.scene}.json",
        faults=parse_faults(row.faults),
        seed=row.seed,
        frames=again,
        settings=ExecutionSettings(budget=Budget(timeout=float("inf"))),  # --timeout inf
    )
    made = done.folder / "worst" / row.run_id
    assert sorted(p.name for p in again.iterdir()) == sorted(p.name for p in made.iterdir())
    assert (again / "storyboard.png").read_bytes() == (made / "storyboard.png").read_bytes()
    resumed = evaluate(None, done.folder, resume=True)  # nothing to make: the storyboards kept
    assert resumed.storyboards == done.storyboards


def test_without_matplotlib_the_worst_runs_say_they_have_no_storyboard(
    model_files: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import importlib.util

    found = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util,
        "find_spec",
        lambda name, *a: None if name == "matplotlib" else found(name, *a),
    )
    chosen = settings_from_options(
        model_files["exp2"], [], random_scenes=1, seeds=1, faults="", sim="kinematic", clutter=0
    )
    done = evaluate(chosen, tmp_path / "eval")
    assert done.storyboards == {"random-0/seed-0": "no storyboard: matplotlib is not installed"}
    assert not (done.folder / "worst").exists()
    assert "no storyboard: matplotlib is not installed" in done.report.read_text()


def test_a_model_without_shapes_is_refused_for_random_layouts_in_one_line(tmp_path: Path) -> None:
    """A model learned from demonstrations that give no object's shape (as an
    import of robosuite's recordings gives for its meshes) cannot be scattered:
    one line naming the model file, exit 1, nothing written (it was a KeyError)."""
    data = json.loads(EXPERIMENTS["exp2"].read_text())
    for demo in data["demonstrations"]:
        demo.pop("objects", None)
    demos = tmp_path / "no-shapes.json"
    demos.write_text(json.dumps(data))
    model = tmp_path / "model.json"
    assert invoke("learn", str(demos), "-o", str(model)).exit_code == 0
    out = tmp_path / "eval"
    done = invoke(
        "evaluate", str(model), "--random-scenes", "1", "--workers", "0", "--out", str(out)
    )
    assert done.exit_code == 1
    assert done.stderr.startswith(f"demoplan: error: {model}: demonstrations: ")
    assert "no shape or size" in done.stderr and done.stderr.count("\n") == 1
    assert "Traceback" not in done.stderr
    assert not out.exists()
