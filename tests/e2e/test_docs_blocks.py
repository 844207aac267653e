"""The comparison the docs test makes (tests/support/docs_blocks.py): what a block
shows against a real output — that it fails when the output changes."""

from __future__ import annotations

from pathlib import Path

from tests.support.docs_blocks import blocks, mismatch, without_time_limit

OUTPUT = """Candidate goals
┏━━━━━━━━━━━━━━━┳━━━━━━━━━┓
┃ goal          ┃ actions ┃
┡━━━━━━━━━━━━━━━╇━━━━━━━━━┩
│ 1 (pyramid-1) │ 10      │
│ 2 (pyramid-2) │ 8       │
└───────────────┴─────────┘
GRASP red loc3 grasp5
PUT_DOWN red freespace1 grasp5
demoplan: 8 actions, proved shortest
"""


def test_the_real_output_shown_whole_matches() -> None:
    shown = tuple(line for line in OUTPUT.splitlines() if "━" not in line and "─" not in line)
    assert mismatch(shown, OUTPUT) is None


def test_column_widths_and_borders_are_not_compared() -> None:
    shown = ("Candidate goals", "┃ goal ┃ actions ┃", "│ 1 (pyramid-1) │ 10 │", "…")
    assert mismatch(shown, OUTPUT) is None


def test_a_changed_number_fails() -> None:
    shown = ("Candidate goals", "┃ goal ┃ actions ┃", "│ 1 (pyramid-1) │ 12 │", "…")
    assert "expected '│ 1 (pyramid-1) │ 12 │'" in str(mismatch(shown, OUTPUT))


def test_output_beyond_the_lines_shown_needs_an_ellipsis() -> None:
    shown = ("Candidate goals", "┃ goal ┃ actions ┃")
    assert "goes on" in str(mismatch(shown, OUTPUT))
    assert mismatch((*shown, "…"), OUTPUT) is None


def test_an_ellipsis_line_skips_and_an_inline_one_is_any_text() -> None:
    assert mismatch(("Candidate goals", "…", "demoplan: 8 actions, …"), OUTPUT) is None
    assert mismatch(("Candidate goals", "│ …", "PUT_DOWN red … grasp5", "…"), OUTPUT) is None
    assert "ends before" in str(mismatch(("Candidate goals", "…", "no such line"), OUTPUT))


def test_the_block_must_start_at_the_first_line() -> None:
    assert mismatch(("GRASP red loc3 grasp5", "…"), OUTPUT) is not None
    assert mismatch(("…", "GRASP red loc3 grasp5", "…"), OUTPUT) is None


def test_console_and_shell_blocks_are_read_with_their_commands(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text(
        "Text.\n\n```console\n$ demoplan solve p.xml\nGRASP a b c\n…\n"
        "$ demoplan show m.json\n```\n\n"
        "```sh\n# a comment\ndemoplan import x.hdf5 -o d/\n```\n\n```\nnot run\n```\n"
        "```python\nprint(1)\n```\n"
    )
    found = blocks(page)
    assert [b.language for b in found] == ["console", "sh", "python"]
    console = found[0].commands
    assert [c.text for c in console] == ["demoplan solve p.xml", "demoplan show m.json"]
    assert console[0].expected == ("GRASP a b c", "…") and console[0].line == 4
    assert [c.text for c in found[1].commands] == ["demoplan import x.hdf5 -o d/"]


def test_only_planning_commands_on_the_default_budget_get_a_run_without_time_limit() -> None:
    """tests/e2e/test_docs_shell.py's second run of a command whose output the
    default wall-clock budget decides: ``--timeout inf`` for each planning
    command, nothing for a command that gives its own budget or plans nothing."""
    assert (
        without_time_limit("demoplan solve p.xml --search bfs --json | python -m json.tool")
        == "demoplan solve --timeout inf p.xml --search bfs --json | python -m json.tool"
    )
    assert (
        without_time_limit("demoplan run kit.json scene.json --seed 0   # faults")
        == "demoplan run --timeout inf kit.json scene.json --seed 0   # faults"
    )
    assert without_time_limit("demoplan plan kit.json scene.json --timeout 5") is None
    assert without_time_limit("demoplan learn demos.json -o kit.json") is None
    assert without_time_limit("demoplan planner") is None
