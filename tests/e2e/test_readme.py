"""The README's tour runs as written (a new user's first commands)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.e2e.test_docs_shell import DOCUMENTS
from tests.support.docs_blocks import blocks

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
COMMAND = re.compile(r"^\$ (demoplan .*?)(?:\s+#.*)?$")


def tour_commands() -> list[str]:
    return [command for command, _ in tour()]


def tour() -> list[tuple[str, list[str]]]:
    """Every `$ demoplan …` line of the README with the output lines shown under it."""
    shown: list[tuple[str, list[str]]] = []
    for line in (ROOT / "README.md").read_text().splitlines():
        if m := COMMAND.match(line):
            shown.append((m.group(1), []))
        elif line.startswith("```") or line.startswith("$ "):
            if shown and shown[-1][1] is not None:
                shown.append(("", []))  # output after this is no command's
        elif shown:
            shown[-1][1].append(line)
    return [(command, lines) for command, lines in shown if command]


def verbatim(lines: list[str]) -> list[str]:
    """The shown lines that must appear as they are: table rows and plan actions, not
    lines the README shortens with an ellipsis."""
    return [
        line
        for line in lines
        if "…" not in line and line.startswith(("│", "┃", "GRASP ", "PUT_DOWN ", "Constraints ("))
    ]


def test_the_tour_has_commands() -> None:
    assert len(tour_commands()) >= 12


def test_tour_commands_run_where_the_docs_test_checks_their_output() -> None:
    """Every `$ demoplan …` line of the README is a command of a console block
    that tests/e2e/test_docs_shell.py runs, in order in one working folder holding
    the examples (later ones use what earlier ones wrote), requiring exit 0 and
    the output the README shows line by line — the lines shown here verbatim
    among them. (It ran them a second time here, 36 s on two cores.)"""
    run = [command for block in blocks(README) for command in block.commands]
    assert README in DOCUMENTS
    by_text = {m.group(1): c for c in run if (m := COMMAND.match(f"$ {c.text}"))}
    checked = 0
    for command, shown in tour():
        assert command in by_text, command
        expected = {line.rstrip() for line in by_text[command].expected}
        for line in verbatim(shown):
            assert line.rstrip() in expected, (command, line)
            checked += 1
    assert list(by_text) == tour_commands()  # every one, in the README's order
    assert len(tour_commands()) >= 12
    assert checked >= 10  # the tour shows Tables III and V, and the chosen plan


def test_python_example_prints_what_its_comments_say(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The README's Python example (learning Experiment 2 with the paper's settings)
    runs and prints Table V's sequences and the five constraints its comments show."""
    (block,) = [b for b in python_blocks() if "TaskModelLearner" in b]
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), {})
    printed = capsys.readouterr().out.splitlines()
    promised = [m.group(1) for m in re.finditer(r"^print\(.*?\)\s+# (\(.*\))", block, re.M)]
    assert len(promised) == 2
    assert printed[: len(promised)] == promised
    assert (tmp_path / "blocks.model.json").exists()


def python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)


def test_the_one_import_loop_prints_what_its_comments_say(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The README's `import demoplan` example: learn, plan and run Experiment 2 —
    every commented print shows the start of what it prints."""
    (block,) = [b for b in python_blocks() if b.startswith("import demoplan")]
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), {})
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] == "[10, 8]"
    assert printed[1] == "GRASP red loc3 grasp5" and len(printed) == 1 + 8 + 1
    assert printed[-1] == "True goal of demonstration 2 (pyramid-2) reached"
