"""The shell and Python blocks of the documentation, and how a real output is
compared with what a block shows (for tests/e2e/test_docs_shell.py).

A ```console block holds commands, each on a line starting with ``$ ``,
followed by the output the reader should see. The output shown must be the
real one, line by line, with two allowances:

- a line that is only ``…`` (or ``│ …``, in a table; possibly followed by a
  remark in parentheses) stands for any number of lines, and ``…`` inside a line for any text;
- table borders (lines of box-drawing characters only) and runs of spaces
  are not compared, so a column's width may change.

Lines the block does not show are allowed only where it says ``…``: a block
that shows some output must show it from its first line, and end with ``…``
if the command prints more. A command whose block shows no output at all is
only required to succeed. ```sh / ```bash blocks are commands without output.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ELLIPSIS = "…"
_FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```", re.S | re.M)
_BORDER = re.compile(r"^[\s━─┏┓┗┛┳┻┣┫╋┡┩╇┃│└┘┌┐├┤┬┴┼═╞╡╪]*$")
_SKIP_LINE = re.compile(r"^[│┃]?\s*…\s*[│┃]?(\s+\(.*\))?$")


@dataclass(frozen=True, slots=True)
class Command:
    """One command of a block, and the output lines the block shows for it."""

    text: str
    expected: tuple[str, ...]
    line: int  # in the markdown file


@dataclass(frozen=True, slots=True)
class Block:
    path: Path
    language: str
    line: int
    commands: tuple[Command, ...]
    source: str  # the block's text (Python blocks)

    @property
    def where(self) -> str:
        return f"{self.path.relative_to(ROOT)}:{self.line}"


def documents() -> list[Path]:
    """README.md, docs/*.md and the examples' READMEs."""
    return [
        ROOT / "README.md",
        *sorted((ROOT / "docs").glob("*.md")),
        *sorted((ROOT / "examples").rglob("README.md")),
    ]


def blocks(path: Path) -> list[Block]:
    text = path.read_text(encoding="utf-8")
    found = []
    for match in _FENCE.finditer(text):
        language, body = match.group(1), match.group(2)
        first = text.count("\n", 0, match.start()) + 2  # the block's first line
        if language == "console":
            found.append(Block(path, language, first - 1, _console(body, first), body))
        elif language in ("sh", "bash"):
            commands = tuple(
                Command(line.strip(), (), first + k)
                for k, line in enumerate(body.splitlines())
                if line.strip() and not line.lstrip().startswith("#")
            )
            found.append(Block(path, language, first - 1, commands, body))
        elif language == "python":
            found.append(Block(path, language, first - 1, (), body))
    return found


def _console(body: str, first: int) -> tuple[Command, ...]:
    commands: list[Command] = []
    text: str | None = None
    start = 0
    expected: list[str] = []
    for k, line in enumerate(body.splitlines()):
        if line.startswith("$ "):
            if text is not None:
                commands.append(Command(text, tuple(expected), start))
            text, start, expected = line[2:], first + k, []
        elif text is not None:
            expected.append(line)
    if text is not None:
        commands.append(Command(text, tuple(expected), start))
    return tuple(commands)


def _normal(line: str) -> str:
    return " ".join(line.split())


def _pattern(line: str) -> re.Pattern[str]:
    parts = [re.escape(part) for part in _normal(line).split(ELLIPSIS)]
    return re.compile(".*".join(parts))


def mismatch(expected: tuple[str, ...], output: str) -> str | None:
    """Why ``output`` is not what the block shows (None when it is)."""
    shown = [line for line in expected if line.strip() and not _BORDER.match(line)]
    if not shown:
        return None
    real = [_normal(line) for line in output.splitlines() if not _BORDER.match(line)]
    at = 0
    skipping = False
    for line in shown:
        if _SKIP_LINE.match(line.strip()):
            skipping = True
            continue
        pattern = _pattern(line)
        if skipping:
            while at < len(real) and not pattern.fullmatch(real[at]):
                at += 1
        if at >= len(real):
            return f"the output ends before {line.strip()!r}"
        if not pattern.fullmatch(real[at]):
            return f"expected {line.strip()!r}, the output has {real[at]!r}"
        at += 1
        skipping = False
    if at < len(real) and not skipping:
        return f"the output goes on after the lines shown: {real[at]!r} (end the block with …)"
    return None


_PLANNING = re.compile(r"\bdemoplan (plan|solve|run|export)\b")


def without_time_limit(command: str) -> str | None:
    """``command`` with ``--timeout inf`` for each planning command in it, if it
    plans on the default wall-clock budget (None otherwise)."""
    if "--timeout" in command or not _PLANNING.search(command):
        return None
    return _PLANNING.sub(r"demoplan \1 --timeout inf", command)
