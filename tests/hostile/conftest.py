"""The hostile suite's report: cases per command and time, printed after the run."""

from __future__ import annotations

import re
from collections import defaultdict
from typing import Any

_reports: list[tuple[str, str, float, str]] = []  # (file, command, seconds, outcome)

# test_generated's tests run many hypothesis examples each: their command, as
# in the test's name, and how many examples (its max_examples, derandomized).
_GENERATED = {
    "test_learn_on_a_mutated_demonstration_file": ("learn", 70),
    "test_plan_in_a_mutated_scene": ("plan", 60),
    "test_problem_for_a_mutated_scene": ("problem", 30),
    "test_show_and_plan_with_a_mutated_model": ("show/plan", 60),
    "test_solve_a_mutated_problem": ("solve", 60),
    "test_segment_a_mutated_stream": ("segment", 40),
    # test_recordings (at most so many: hypothesis stops when a space is exhausted)
    "test_a_recording_pointing_to_another_file_is_refused_and_that_file_never_opened": (
        "import",
        12,
    ),
    "test_names_in_a_recording_become_safe_file_names_inside_the_output_folder": ("import", 12),
    "test_non_finite_huge_and_degenerate_model_numbers_are_refused": ("import", 12),
    "test_deeply_nested_models_are_refused_without_recursion": ("import", 6),
    "test_a_dataset_declaring_more_than_the_file_holds_is_refused_before_reading": ("import", 6),
    "test_tf_frame_names_with_escapes_are_printed_as_text": ("segment", 6),
    # test_open_audit: each example a whole command under strace
    "test_segment_opens_the_stream_only": ("segment", 4),
    "test_plan_opens_the_model_and_the_scene_only": ("plan", 4),
    "test_run_kinematic_with_frames_opens_its_inputs_only": ("run", 2),
    # issue 27's limits: test_many_objects, test_one_validation, test_video_encoder,
    # test_terminal_text
    "test_a_model_of_thousands_of_free_bodies_is_refused_before_its_states_are_read": (
        "import",
        4,
    ),
    "test_a_tf_tree_of_thousands_of_frames_is_refused_as_it_is_read": ("segment/learn", 4),
    "test_a_csv_stream_of_thousands_of_objects_is_refused": ("segment", 4),
    "test_positions_spread_beyond_a_tabletop_are_refused_at_every_door": ("import/segment", 8),
    "test_an_object_too_large_to_carry_is_refused_at_every_door": ("import/segment", 8),
    "test_an_encoder_that_fails_is_an_error_and_leaves_no_video": ("run --video", 4),
    "test_names_with_control_characters_are_printed_escaped": ("learn/show/plan/run", 3),
}


def pytest_runtest_logreport(report: Any) -> None:
    if "tests/hostile/" not in report.nodeid or report.when != "call":
        return
    path, _, name = report.nodeid.partition("::")
    function, _, param = name.partition("[")
    param = param.removesuffix("]")
    command = re.split(r"[-\s]", param, maxsplit=1)[0] if param else function
    if function == "test_twenty_pairs_of_simultaneous_updates_lose_no_demonstration":
        command = "learn --update"
    _reports.append((path.rsplit("/", 1)[-1], command, report.duration, report.outcome))


def pytest_terminal_summary(terminalreporter: Any) -> None:
    if not _reports:
        return
    cases: dict[str, int] = defaultdict(int)
    seconds: dict[str, float] = defaultdict(float)
    failed = 0
    generated = handwritten = 0
    for _, command, duration, outcome in _reports:
        if command in _GENERATED:
            command, count = _GENERATED[command]
            generated += count
        else:
            count = 1
            handwritten += 1
        cases[command] += count
        seconds[command] += duration
        failed += outcome == "failed"
    write = terminalreporter.write_line
    write("")
    write(
        f"hostile suite: {handwritten} hand-written cases and {generated} generated "
        f"examples, {failed} failed; per command (cases, seconds summed over workers):"
    )
    for command in sorted(cases, key=lambda c: -cases[c]):
        write(f"  {command:<16} {cases[command]:>5} cases  {seconds[command]:7.1f} s")
