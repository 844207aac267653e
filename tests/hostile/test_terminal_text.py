"""Text is text on the terminal, and an object's name is a word of a plan
(docs/limits.md "Text is text", docs/formats.md "Object names"): an object
named with control characters — an escape sequence (``\\x1b[2J`` clears the
screen), ``\\r`` (overwrites the line), a C1 CSI (``\\x9b``), a
bidirectional override, a bell, a backspace, DEL, a tab, a newline — is
refused where it is read, by ``learn`` of the demonstrations, by ``show``,
``plan`` and ``run`` of a model file it was written into, and by ``plan`` of
a scene naming it: one line naming the file and the field, every such
character written as its escape (no character that is not printable but the
line breaks reaches stdout or stderr). Before, ``learn`` wrote the model and
``plan`` printed the name escaped. TF frames and HDF5 keys through
``segment`` and ``import``: tests/hostile/test_recordings.py.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.wording import printable
from tests.hostile.harness import Answer, check_refused, run
from tests.support.helpers import EXAMPLES

CONTROLS = ["\x1b[2J", "\r", "\x9b", "\u202e", "\x07", "\x08", "\x7f", "\x1b]0;x\x07", "\t", "\n"]
NAMES = st.lists(st.sampled_from(CONTROLS), min_size=1, max_size=3).map(
    lambda parts: "cube" + "".join(parts) + "A"
)


def shown_as_text(answer: Answer) -> None:
    for stream in (answer.stdout, answer.stderr):
        raw = sorted({c for c in stream if not c.isprintable() and c != "\n"})
        assert not raw, f"{raw!r} reached the terminal: {answer}\n{answer.stdout}"


def renamed(path: Path, old: str, new: str) -> str:
    """The JSON document at ``path`` with every string ``old`` (keys included) made ``new``."""
    return json.dumps(json.loads(path.read_text()), ensure_ascii=False).replace(
        json.dumps(old), json.dumps(new)
    )


def refused_naming(answer: Answer, file: str, name: str) -> None:
    check_refused(answer, [file])
    shown_as_text(answer)
    assert printable(name) in answer.stderr, answer
    assert "object name" in answer.stderr, answer


@settings(
    max_examples=3,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(name=NAMES)
def test_names_with_control_characters_are_refused_where_they_are_read(name: str) -> None:
    """The pyramid of three blocks with the red one renamed: ``learn`` refuses
    the demonstrations (no model written); the learned model and the Fig. 4
    scene with the name edited in are refused by ``show``, ``show --json``,
    ``plan`` and ``run``, the escaped name in the one line."""
    with tempfile.TemporaryDirectory(prefix="hostile-text-") as folder:
        cwd = Path(folder)
        (cwd / "demos.json").write_text(
            renamed(EXAMPLES / "blocks" / "demonstrations.json", "red", name)
        )
        learned = run(["learn", "demos.json", "--paper", "-o", "model.json"], cwd)
        refused_naming(learned, "demos.json", name)
        assert not (cwd / "model.json").exists()
        shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", cwd / "good.json")
        good = run(["learn", "good.json", "--paper", "-o", "good-model.json"], cwd)
        assert good.code == 0, good
        (cwd / "model.json").write_text(renamed(cwd / "good-model.json", "red", name))
        (cwd / "scene.json").write_text(
            renamed(EXAMPLES / "scenes" / "pyramid-fig4.json", "red", name)
        )
        shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", cwd / "good-scene.json")
        for command, file in (
            (["show", "model.json"], "model.json"),
            (["show", "model.json", "--json"], "model.json"),
            (["plan", "model.json", "good-scene.json"], "model.json"),
            (["run", "model.json", "good-scene.json"], "model.json"),
            (["plan", "good-model.json", "scene.json"], "scene.json"),
        ):
            refused_naming(run(command, cwd), file, name)
