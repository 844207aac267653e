"""Results several test files share (tests/support/background.py), computed once per
session: under pytest-xdist in a process of their own that the controller
starts as soon as the workers have collected a test that reads one.

And the order the tests are handed out in: pytest-xdist gives each worker the
next tests of the collection as it finishes its own, so a long test collected
late can leave one worker running it alone at the end. The long ones go
first; the tests that read a shared result next (by then it is ready); the
rest, short, fill in and end the run."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import pytest

import demoplan.perception.opencv  # noqa: F401  (cv2 first loaded without leaving "" in LD_LIBRARY_PATH)
from demoplan.planning.problem import Problem
from tests.support import background
from tests.support.fixed_problems import load_fixed
from tests.support.shared_experiments import ExperimentsRun

LONG_FIRST = (
    # Each 20 s to 90 s on two cores (the slowest of a full run's --durations):
    "tests/execution/test_arm_mass.py::test_the_check_agrees_with_the_physics_at_length",
    "tests/e2e/test_docs_shell.py::",
    "tests/hostile/test_concurrency.py::",
    "tests/execution/test_arm.py::test_an_obstacle_on_a_thin_parts_target",
    "tests/hostile/test_open_audit.py::test_run_with_video_and_frames_opens_its_inputs_only",
    "tests/evaluation/test_evaluate.py::test_ctrl_c_keeps_the_finished_rows",
    "tests/execution/test_arm.py::test_experiment_",
    "tests/execution/test_arm.py::test_kitting_on_the_arm",
    "tests/scenes/test_free_space.py::test_the_family_recovers_from_drops_and_blocks",
    "tests/planning/test_pddl.py::test_fast_downward_optimal_lengths_match",
)
SHARED_FIXTURES = ("experiments_run",)


def _rank(item: pytest.Item) -> int:
    """0, 1, …: the LONG_FIRST entries; then tests marked slow; then those that
    read a shared result; then the rest."""
    for rank, prefix in enumerate(LONG_FIRST):
        if item.nodeid.startswith(prefix):
            return rank
    reads_shared = any(name in SHARED_FIXTURES for name in getattr(item, "fixturenames", ()))
    if reads_shared:
        return len(LONG_FIRST) + 1
    if item.get_closest_marker("slow") is not None:
        return len(LONG_FIRST)
    return len(LONG_FIRST) + 2


SLOW = (
    # Whole folders and files: each test starts demoplan processes, a browser,
    # Ray or a MuJoCo arm run (and every test that reads the shared experiments
    # run, minutes: SHARED_FIXTURES).
    "tests/hostile/",  # one or more demoplan processes per case (about a thousand)
    "tests/e2e/test_docs_shell.py",
    "tests/e2e/test_docs_generated.py",
    "tests/e2e/test_interrupt.py",
    "tests/cli/test_launcher.py",
    "tests/segmentation/test_segment_cli.py",
    "tests/e2e/test_self_contained.py",
    "tests/planning/test_planning_limits.py",
    "tests/execution/test_arm.py",
    "tests/execution/test_arm_flat.py",
    "tests/execution/test_arm_layouts.py",
    "tests/execution/test_drops.py",
    "tests/execution/test_landmark_physics.py",
    "tests/execution/test_robosuite_run.py",
    "tests/segmentation/test_real_recordings.py",
    "tests/perception/test_perception_real_photos.py",
    # Single tests: Ray, the CLI's processes, long physics.
    "tests/evaluation/test_evaluate.py::test_ray_equals_a_serial_run",
    "tests/evaluation/test_evaluate.py::test_a_worker_killed_from_outside",
    "tests/evaluation/test_evaluate.py::test_a_killed_worker_s_run",
    "tests/evaluation/test_evaluate.py::test_resume_after_ctrl_c",
    "tests/evaluation/test_evaluate.py::test_ctrl_c_keeps_the_finished_rows",
    "tests/evaluation/test_evaluate.py::test_evaluate_s_usage_errors",
    "tests/evaluation/test_evaluate.py::test_a_settings_file_out_of_bounds",
    "tests/evaluation/test_evaluate.py::test_every_run_repeats_with_demoplan_run",
    "tests/evaluation/test_evaluate.py::test_bad_input_is_one_line",
    "tests/evaluation/test_evaluate.py::test_a_terminal_sees_runs_done",
    "tests/evaluation/test_evaluate.py::test_the_worst_runs_link_their_storyboard",
    "tests/evaluation/test_evaluate.py::test_a_model_without_shapes_is_refused",
)
"""Tests marked ``slow`` here (beside those marked in their files), by their
node id (a folder, a file, or a file and a test name's start):
``python -m pytest -m "not slow"`` is the quick loop (tests/README.md)."""

ROOT = Path(__file__).resolve().parents[1]


def _node(item: pytest.Item) -> str:
    """``tests/…/test_x.py::test_name[…]``, wherever pytest was started."""
    file = Path(str(item.path)).resolve().relative_to(ROOT).as_posix()
    return f"{file}::{item.name}"


@pytest.hookimpl(tryfirst=True)  # before -m deselects by marker
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        reads_shared = any(n in SHARED_FIXTURES for n in getattr(item, "fixturenames", ()))
        if reads_shared or _node(item).startswith(SLOW):
            item.add_marker(pytest.mark.slow)
    items.sort(key=_rank)  # stable: each group in collection order


_started: dict[str, subprocess.Popen[bytes] | None] = {}
_folder: list[Path] = []  # the controller's folder for the jobs (under xdist)


def _is_xdist_controller(config: pytest.Config) -> bool:
    return (
        not hasattr(config, "workerinput")
        and config.pluginmanager.hasplugin("xdist")
        and bool(config.getoption("numprocesses", None))
        and config.getoption("dist", "no") != "no"
    )


def pytest_configure(config: pytest.Config) -> None:
    if _is_xdist_controller(config):
        _folder.append(Path(tempfile.mkdtemp(prefix="demoplan-tests-shared-")))


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node: Any) -> None:
    if _folder:
        node.workerinput["demoplan_shared"] = str(_folder[0])


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_node_collection_finished(node: Any, ids: list[str]) -> None:
    for name in background.needed(ids):
        if _folder and name not in _started:
            _started[name] = background.start(name, _folder[0])


def pytest_unconfigure(config: pytest.Config) -> None:
    for process in _started.values():  # only ours, by their Popen objects
        if process is not None:
            background.stop(process)
    _started.clear()
    if _folder:
        shutil.rmtree(_folder.pop(), ignore_errors=True)


_computed_here: dict[str, Any] = {}


def shared_result(
    name: str, config: pytest.Config, tmp_path_factory: pytest.TempPathFactory
) -> Any:
    """Job ``name``'s result: the controller's job's if it started one, else
    one this process runs (once per session)."""
    workerinput = getattr(config, "workerinput", {})
    if "demoplan_shared" in workerinput:
        found = background.result(name, Path(workerinput["demoplan_shared"]))
        if found is not None:
            return found
    if name not in _computed_here:
        _computed_here[name] = background.run_now(name, tmp_path_factory.mktemp(name))
    return _computed_here[name]


@pytest.fixture(scope="session")
def experiments_run(
    pytestconfig: pytest.Config, tmp_path_factory: pytest.TempPathFactory
) -> ExperimentsRun:
    """``demoplan experiments`` run once per session (tests/support/shared_experiments.py)."""
    run: ExperimentsRun = shared_result("experiments", pytestconfig, tmp_path_factory)
    return run


@pytest.fixture(scope="session")
def hard_parking() -> Problem:
    """A parking problem no search solves in a minute, checked in as a file
    (tests/data/hard-parking.xml, tests/support/fixed_problems.py)."""
    return load_fixed("hard-parking")
