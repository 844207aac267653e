"""Results several test files share (tests/support/background.py), computed once per
session: under pytest-xdist in a process of their own that the controller
starts as soon as the workers have collected a test that reads one.

And the order the tests are handed out in: pytest-xdist gives each worker the
next test of the collection as it finishes its own (``--maxschedchunk=1`` in
pyproject.toml: without it a worker is handed a quarter of its share at once,
and the first quarter held every long test), so a long test collected late
can leave one worker running it alone at the end. The long ones go first,
longest first, so that the two workers take turns at them; the tests that
read a shared result next (by then it is ready); the rest, short, fill in
and end the run."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import pytest
from hypothesis import settings
from hypothesis.internal.conjecture import providers as hypothesis_providers

import demoplan.perception.opencv  # noqa: F401  (cv2 first loaded without leaving "" in LD_LIBRARY_PATH)
from demoplan.planning.problem import Problem
from tests.support import background, forkserver
from tests.support.fixed_problems import load_fixed
from tests.support.shared_experiments import ExperimentsRun

settings.register_profile("repeatable", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("repeatable")
"""Every property draws the same examples on every run (seeded from the test's
name): a run of the suite passes or fails on the code, not on the draw. To look
for new failing draws, ``python -m pytest --hypothesis-profile explore``; a
draw found that way is kept as a named case of its test (tests/README.md)."""


_EMPTY_CONSTANTS = hypothesis_providers.Constants()
_all_local_constants = hypothesis_providers._get_local_constants


def _local_constants_unless_repeatable() -> Any:
    """Hypothesis (6.131 on) also draws, now and then, the literals of the modules
    the process has imported so far (cached in .hypothesis/constants): which
    modules a test worker has imported depends on the tests it ran before, so a
    derandomized property drew other examples from one run to the next (two draws
    failing on the code before, found so, are named cases in
    tests/perception/test_perception_regions.py). The repeatable profile draws
    without them; ``--hypothesis-profile explore`` keeps them."""
    if settings.default.derandomize:
        return _EMPTY_CONSTANTS
    return _all_local_constants()


hypothesis_providers._get_local_constants = _local_constants_unless_repeatable

LONG_FIRST = (
    # The longest tests, longest first: each test's wall seconds (its own and
    # its processes') in the quiet run at 30abf1b (.ci/run, 2 workers) that
    # took 6 s or more, less what later commits cut (the filmed demonstrations'
    # frames, BFS, one-move videos: tests/README.md; redrawing hard-parking and
    # the fork server's out-of-time case, 17 and 11 s then, take about a second
    # since the planning families' collision facts and the fork server's
    # request were fixed). Under --maxschedchunk=1
    # (pyproject.toml) each worker takes the next one as it finishes its own,
    # so the two workers end on short tests together.
    "tests/e2e/test_docs_shell.py::test_the_documents_blocks_run_and_print_what_they_show[docs/execution.md]",
    "tests/e2e/test_docs_shell.py::test_the_documents_blocks_run_and_print_what_they_show[README.md]",
    "tests/hostile/test_ray_addresses.py::test_a_running_head_is_joined",
    "tests/e2e/test_docs_shell.py::test_the_documents_blocks_run_and_print_what_they_show[docs/tutorial.md]",
    "tests/evaluation/test_evaluate.py::test_ray_equals_a_serial_run",
    "tests/e2e/test_docs_shell.py::test_the_documents_blocks_run_and_print_what_they_show[docs/perception.md]",
    "tests/evaluation/test_evaluate.py::test_ctrl_c_keeps_the_finished_rows",
    "tests/studio/test_studio_browser.py::test_blocks_taught_planned_from_fig4",
    "tests/e2e/test_docs_shell.py::test_the_documents_blocks_run_and_print_what_they_show[docs/segmentation.md]",
    "tests/studio/test_studio_own_objects_browser.py::test_a_lunch_box_of_my_own",
    "tests/execution/test_robosuite_run.py::test_stack_learned_from_the_recordings",
    "tests/planning/test_pddl.py::test_fast_downward_optimal_lengths_match",
    "tests/studio/test_studio_own_task_browser.py::test_tools_and_a_cup_into_a_turned_caddy",
    "tests/evaluation/test_evaluate.py::test_a_killed_worker_s_run",
    "tests/hostile/test_concurrency.py::",
    "tests/studio/test_studio_browser.py::test_the_paper_set_table_is_taught_by_dragging",
    "tests/planning/test_search.py::test_an_unproved_plan_comes_with_its_bound",
    "tests/evaluation/test_robosuite_evaluate.py::test_stack_over_seeds_here",
    "tests/evaluation/test_evaluate.py::test_a_worker_killed_from_outside",
    "tests/evaluation/test_robosuite_evaluate.py::test_a_ray_worker_makes_the_rows",
    "tests/evaluation/test_evaluate.py::test_the_worst_runs_link_their_storyboard",
    "tests/execution/test_robosuite_pickplace.py::test_one_pickplace_seed_end_to_end",
    "tests/execution/test_arm_mass.py::test_the_check_agrees_with_the_physics_at_length",
    "tests/studio/test_studio_api.py::test_two_arm_runs_one_after_the_other",
    "tests/planning/test_planning_limits.py::test_the_state_limit_stops_a_search",
    "tests/hostile/test_open_audit.py::test_segment_opens_the_stream_only",
    "tests/hostile/test_recordings.py::test_a_recording_pointing_to_another_file",
    "tests/studio/test_studio_run_view.py::test_every_event_shows_the_world",
    "tests/hostile/test_many_objects.py::test_a_tf_tree_of_thousands_of_frames",
    "tests/hostile/test_open_audit.py::test_plan_opens_the_model_and_the_scene_only",
    "tests/hostile/test_video_encoder.py::test_an_encoder_that_fails",
    "tests/planning/test_parts.py::test_two_problems_that_never_meet",
    "tests/hostile/test_full_disk.py::test_a_full_disk_under_file_outputs",
    "tests/scenes/test_free_space.py::test_kitting_recovers_from_drops_and_blocks",
    "tests/studio/test_studio_run_view.py::test_a_page_opened_again_shows_the_last_run",
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
    "tests/frontends/test_interrupt.py",
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
    "tests/evaluation/test_evaluate.py::test_a_terminal_sees_runs_done",
    "tests/evaluation/test_evaluate.py::test_the_worst_runs_link_their_storyboard",
    "tests/evaluation/test_ray_engine.py::",
    # Single tests of 2 s of CPU or more: 20 s or more of a quick loop's
    # --durations on two cores shared with a load of about 20 (its CPU time was
    # a ninth of its summed durations); each package keeps its other tests.
    "tests/e2e/test_breakfast.py::test_a_kit_tray_placed_anywhere_stays_and_is_filled_where_it_stands",
    "tests/e2e/test_breakfast.py::test_the_breakfast_is_laid_out_on_the_turned_tray",
    "tests/evaluation/test_evaluate.py::test_a_journal_torn_by_a_killed_evaluation_is_resumed",
    "tests/evaluation/test_evaluate.py::test_out_is_a_new_or_empty_folder",
    "tests/execution/test_arm_mass.py::test_household_weights_go_by_the_tool_that_carries_them",
    "tests/execution/test_arm_mass.py::test_the_arm_changes_tools_between_objects",
    "tests/execution/test_arm_mass.py::test_the_check_agrees_with_the_physics",
    "tests/execution/test_behaviour_tree.py::test_the_tree_ticks_with_the_arm",
    "tests/execution/test_execution.py::test_a_storyboard_keeps_every_failure_frame",
    "tests/execution/test_execution.py::test_faults_are_reported_as_they_happened_and_detected_as_their_kind",
    "tests/execution/test_execution.py::test_monte_carlo_recoverable_faults_always_finish",
    "tests/execution/test_execution.py::test_run_json_report",
    "tests/execution/test_physics.py::test_run_records_a_video_from_a_fixed_camera",
    "tests/execution/test_stable_names.py::test_in_a_run_where_an_object_was_put_is_where_it_is_grasped_from",
    "tests/learning/test_clustering.py::test_kmeans_is_as_good_as_scikit_learn_on_arbitrary_data",
    "tests/learning/test_constraint_graph.py::test_drawn_edges_are_constraints_whose_closure_is_the_goals_order",
    "tests/learning/test_learning_real.py::test_update_with_a_repeated_demonstration_changes_nothing_and_says_so",
    "tests/learning/test_rule_edges.py::test_the_plates_of_a_table_for_two_are_placed_by_one_rule",
    "tests/perception/test_calibration.py::test_bad_inputs_refused_in_one_line",
    "tests/perception/test_calibration.py::test_calibrate_writes_camera_file_and_overlay",
    "tests/perception/test_calibration.py::test_oblique_views_give_blocks_within_5mm",
    "tests/perception/test_perception.py::test_experiment_2_on_vision_in_mujoco",
    "tests/perception/test_perception_false_blocks.py::test_a_board_crossed_by_cables_is_no_block",
    "tests/perception/test_perception_families.py::test_a_family_photograph_meets_the_issue_thresholds",
    "tests/perception/test_perception_photos.py::test_blocks_on_a_gridded_board_are_found_to_5_mm",
    "tests/perception/test_perception_sequence.py::test_cli_reads_a_video",
    "tests/perception/test_perception_sequence.py::test_cli_writes_a_demonstration_that_learn_accepts",
    "tests/perception/test_perception_sequence.py::test_experiment_2_from_camera_frames_learns_table_iv",
    "tests/perception/test_perception_sequence.py::test_generated_demonstrations_are_recovered",
    "tests/perception/test_perception_sequence.py::test_the_hand_is_found_and_no_block_is_taken_for_it",
    "tests/planning/test_parts.py::test_two_problems_that_never_meet_are_solved_as_parts",
    "tests/planning/test_pddl.py::test_a_grasp_shared_by_an_object_a_place_refuses_does_not_block_one_it_takes",
    "tests/planning/test_pddl.py::test_fast_downward_agrees_under_the_order_rule",
    "tests/planning/test_pddl.py::test_fast_downward_optimal_lengths_match",
    "tests/planning/test_pddl.py::test_pyperplan_agrees_with_demoplan",
    "tests/planning/test_pddl_roles.py::test_every_binding_has_the_exported_problem_with_its_instances_in_the_roles",
    "tests/planning/test_pddl_roles.py::test_fast_downward_agrees_on_half_built_towers",
    "tests/planning/test_pddl_roles.py::test_fast_downward_reads_the_grounded_export_with_roles",
    "tests/planning/test_plateau.py::test_a_plan_the_dive_finds_is_valid_and_shortest",
    "tests/planning/test_search.py::test_generated_problems_match_bfs",
    "tests/scenes/test_free_space.py::test_kitting_recovers_from_drops_and_blocks",
    "tests/scenes/test_free_space.py::test_the_family_recovers_from_drops_and_blocks",
    "tests/scenes/test_geometry_pairs.py::test_collision_facts_are_the_rule_pair_by_pair",
    "tests/scenes/test_geometry_pairs.py::test_exclusions_are_the_rule_pair_by_pair",
    "tests/scenes/test_plan_time_checks.py::test_food_in_world_yaw_hanging_over_the_turned_box_is_refused",
    "tests/scenes/test_plan_time_checks.py::test_food_that_turns_with_the_box_lies_on_it",
    "tests/scenes/test_scene_plan.py::test_fast_downward_agrees_on_scene_problems",
    # Tests added since, measured at 2 s of CPU or more in the quick loop at
    # 3101cfe (-p tests.support.cpu_times): robosuite's runs (and every test
    # reading its evaluation's module fixture, which the first of them would
    # otherwise pay), the tight phase's proofs over the benchmark families,
    # storyboards and figures drawn frame by frame, whole perceptions of a
    # photograph or a camera file.
    "tests/cli/test_lean_perceive.py::test_a_real_photograph_through_the_executable",
    "tests/e2e/test_breakfast.py::test_the_breakfast_recovers_from_drops_and_blocks_on_20_seeds",
    "tests/evaluation/test_robosuite_evaluate.py::test_a_ray_worker_makes_the_rows_a_serial_run",
    "tests/evaluation/test_robosuite_evaluate.py::test_ctrl_c_keeps_the_finished_rows",
    "tests/evaluation/test_robosuite_evaluate.py::test_resume_makes_the_missing_run",
    "tests/evaluation/test_robosuite_evaluate.py::test_stack_over_seeds_here_rows_rates",
    "tests/evaluation/test_robosuite_evaluate.py::test_the_camera_shows_the_cubes",
    "tests/execution/test_colours.py::test_kinematic_frames_and_storyboard_draw_the_given_colours",
    "tests/execution/test_robosuite_pickplace.py::test_a_run_robosuite_judges_failed",
    "tests/execution/test_robosuite_pickplace.py::test_one_pickplace_seed_end_to_end",
    "tests/experiments/test_figure_labels.py::test_a_box_moves_only_as_far_as_it_must",
    "tests/experiments/test_figure_labels.py::test_kinematic_storyboard_frames_keep_their_names",
    "tests/experiments/test_figure_labels.py::test_placed_boxes_never_overlap_and_stay_inside",
    "tests/learning/test_learning_families.py::test_the_order_of_the_demonstrations_does_not_matter",
    "tests/perception/test_perception_budget.py::test_a_budget_running_out_anywhere_in_a_real",
    "tests/perception/test_perception_instances.py::test_the_blocks_experiment_with_a_second_red",
    "tests/perception/test_perception_occlusion.py::test_a_top_a_fingertip_is_over",
    "tests/perception/test_perception_regions.py::test_a_lone_black_white_or_grey_cube",
    "tests/perception/test_perception_regions.py::test_a_white_top_on_a_blue_table",
    "tests/perception/test_perception_sequence.py::test_cli_with_a_camera_file",
    "tests/perception/test_perception_sequence.py::test_no_frames_and_still_pictures_are_one_line",
    "tests/planning/test_plan_shortening.py::test_a_shortened_plan_is_valid_no_longer",
    "tests/planning/test_search.py::test_an_unproved_plan_comes_with_its_bound",
    "tests/planning/test_search.py::test_every_bound_stays_below_the_moves_left",
    "tests/planning/test_solve_cli.py::test_max_nodes_limit_exits_4[astar]",
    "tests/planning/test_tight.py::test_a_play_out_tries_other_parking_places[crowded-distractors-20",
    "tests/planning/test_tight.py::test_crowded_stacks_are_proved_at_the_start[20]",
    "tests/planning/test_tight.py::test_refutations_found_in_a_sweep_hold_by_exhaustive_search",
    "tests/planning/test_tight.py::test_the_benchmark_families_are_proved_at_the_start[20-parking",
    "tests/planning/test_tight.py::test_the_benchmark_families_are_proved_at_the_start[30-parking",
    "tests/plotting/test_roles_display.py::test_the_no_plan_figures_reason_is_wrapped",
    "tests/plotting/test_roles_display.py::test_the_two_line_labels_get_room_beside",
    "tests/segmentation/test_tf_tree.py::test_objects_under_moving_links_come_back",
    "tests/studio/test_studio_run_view.py::test_the_worlds_a_run_streams_are_what_the_world_saw",
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
    forkserver.stop_servers()  # this process's (tests/hostile/harness.py starts it)
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
