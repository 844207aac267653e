"""Text is text on the terminal (docs/limits.md "Recordings", "Text is
text"): an object named with control characters — an escape sequence
(``\\x1b[2J`` clears the screen), ``\\r`` (overwrites the line), a C1 CSI
(``\\x9b``), a bidirectional override, a bell, a backspace, DEL — is printed
by ``learn``, ``show`` and ``show --json``, ``plan`` and ``run`` with every
such character written as its escape: no character that is not printable
but the line breaks reaches stdout or stderr, and the escaped name is there
to read (the JSON decodes back to the very name). TF frames and HDF5 keys
through ``segment`` and ``import``: tests/hostile/test_recordings.py.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.wording import printable
from tests.hostile.harness import Answer, check_clean, run
from tests.support.helpers import EXAMPLES

CONTROLS = ["\x1b[2J", "\r", "\x9b", "\u202e", "\x07", "\x08", "\x7f", "\x1b]0;x\x07", "\t", "\n"]
NAMES = st.lists(st.sampled_from(CONTROLS), min_size=1, max_size=3).map(
    lambda parts: "cube" + "".join(parts) + "A"
)


def shown_as_text(answer: Answer) -> None:
    for stream in (answer.stdout, answer.stderr):
        raw = sorted({c for c in stream if not c.isprintable() and c != "\n"})
        assert not raw, f"{raw!r} reached the terminal: {answer}\n{answer.stdout}"


def strings(value: Any) -> set[str]:
    """Every string of a JSON document, keys included."""
    if isinstance(value, dict):
        return set(value) | {s for item in value.values() for s in strings(item)}
    if isinstance(value, list):
        return {s for item in value for s in strings(item)}
    return {value} if isinstance(value, str) else set()


@settings(
    max_examples=3,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(name=NAMES)
def test_names_with_control_characters_are_printed_escaped(name: str) -> None:
    """The pyramid of three blocks with the red one renamed: learned, shown,
    planned (in a scene that names it otherwise: the plan is refused, naming it),
    run."""
    with tempfile.TemporaryDirectory(prefix="hostile-text-") as folder:
        cwd = Path(folder)
        demos = json.loads((EXAMPLES / "blocks" / "demonstrations.json").read_text())
        text = json.dumps(demos, ensure_ascii=False).replace('"red"', json.dumps(name))
        (cwd / "demos.json").write_text(text)
        shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", cwd / "scene.json")
        learned = run(["learn", "demos.json", "--paper", "-o", "model.json"], cwd)
        assert learned.code == 0, learned
        shown_as_text(learned)
        shown = run(["show", "model.json"], cwd)
        assert shown.code == 0, shown
        shown_as_text(shown)
        assert printable(name) in shown.stdout, shown.stdout
        as_json = run(["show", "model.json", "--json"], cwd)
        shown_as_text(as_json)
        assert name in strings(json.loads(as_json.stdout)), as_json.stdout
        for command in (["plan", "model.json", "scene.json"], ["run", "model.json", "scene.json"]):
            answer = run(command, cwd)
            check_clean(answer)
            shown_as_text(answer)
