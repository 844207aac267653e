"""Generated hostile content (issue 14): valid files of every format, mutated.

Hypothesis takes a valid demonstration file, model, scene, problem (XML) or
pose stream (CSV), replaces one value anywhere in it with something hostile
(NaN, ±1e308, a denormal, a 30-digit integer, an empty or 10,000-character
string, a name with a newline or rich markup, null, a list or object where a
number belongs), drops or adds a key, duplicates one, or cuts the file short —
and runs the command that reads it, in this process (fast). Whatever comes
in, the command must succeed or answer with one line naming the file and an
exit code of docs/cli.md — never a traceback or a warning — and leave the files
it was given as they were.
"""

from __future__ import annotations

import json
import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.hostile.harness import ERROR_PREFIX, EXIT_CODES, HANG_SECONDS, NOT_SEEN, fingerprint
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES

HOSTILE_VALUES: list[Any] = [
    float("nan"),
    float("inf"),
    1e308,
    -1e308,
    1e-320,
    0,
    -1,
    10**30,
    "",
    "x" * 10_000,
    "a\nb",
    "[bold]red[/bold]",
    "\x1b[31mred",
    None,
    True,
    [],
    {},
    [1e308, 1e308, 1e308],
    [0.1, "a", None],
    "demoplan/demonstration-99999999999999999999",
]
SETTINGS = settings(
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    derandomize=True,
)


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("generated")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", folder / "scene.json")
    shutil.copy(EXAMPLES / "planning" / "paper-example.xml", folder / "problem.xml")
    shutil.copy(EXAMPLES / "streams" / "set-table-1.csv", folder / "stream.csv")
    result = invoke("learn", folder / "demos.json", "--paper", "-o", folder / "model.json")
    assert result.exit_code == 0, result.output
    return folder


def _paths(value: Any, here: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every place in a JSON document (dict keys and list indices)."""
    found = [here] if here else []
    if isinstance(value, dict):
        for key, item in value.items():
            found += _paths(item, (*here, key))
    elif isinstance(value, list):
        for index, item in enumerate(value[:6]):  # the first few items of long lists
            found += _paths(item, (*here, index))
    return found


def _set(document: Any, path: tuple[Any, ...], change: Callable[[Any, Any], None]) -> Any:
    copy = json.loads(json.dumps(document))
    parent = copy
    for part in path[:-1]:
        parent = parent[part]
    change(parent, path[-1])
    return copy


@st.composite
def mutated_json(draw: st.DrawFn, document: dict[str, Any]) -> str:
    """The text of ``document`` with one hostile change."""
    kind = draw(
        st.sampled_from(["replace", "replace", "replace", "drop", "add", "duplicate", "cut"])
    )
    text = json.dumps(document)
    if kind == "cut":
        return text[: draw(st.integers(0, len(text) - 1))]
    if kind == "duplicate":
        # the first key of the top-level object again, with another value
        return '{"format": "x", ' + text[1:]
    path = draw(st.sampled_from(_paths(document)))
    if kind == "replace":
        value = draw(st.sampled_from(HOSTILE_VALUES))

        def replace(parent: Any, key: Any) -> None:
            parent[key] = value

        changed = _set(document, path, replace)
    elif kind == "drop":

        def drop(parent: Any, key: Any) -> None:
            del parent[key]

        changed = _set(document, path, drop)
    else:
        name = draw(st.sampled_from(["extra", "", "x\ny", "format"]))

        def add(parent: Any, key: Any) -> None:
            target = parent[key]
            if isinstance(target, dict):
                target[name] = draw(st.sampled_from(HOSTILE_VALUES))
            elif isinstance(target, list):
                target.append(draw(st.sampled_from(HOSTILE_VALUES)))

        changed = _set(document, path, add)
    return json.dumps(changed, allow_nan=True)


def _check(
    result: Any, started: float, hostile: Path, folder: Path, before: dict[str, str]
) -> None:
    shown = f"exit {result.exit_code}; stderr {result.stderr[-1500:]!r}"
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise AssertionError(f"uncaught {result.exception!r}; {shown}") from result.exception
    assert result.exit_code in EXIT_CODES, shown
    for text in NOT_SEEN:
        assert text not in result.stderr, shown
    if result.exit_code:
        lines = result.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith(ERROR_PREFIX), shown
        assert hostile.name in lines[0] or "--" in lines[0], f"names no file or option: {shown}"
        assert fingerprint(folder) == before, f"files changed: {shown}"
    assert time.monotonic() - started < HANG_SECONDS, shown


def _run(workspace: Path, name: str, text: str, args: Callable[[Path, Path], list[str]]) -> None:
    folder = Path(tempfile.mkdtemp(dir=workspace.parent))
    try:
        for item in ("model.json", "scene.json"):
            shutil.copy(workspace / item, folder / item)
        hostile = folder / name
        hostile.write_text(text, encoding="utf-8", errors="surrogateescape")
        before = fingerprint(folder)
        started = time.monotonic()
        result = invoke(*args(folder, hostile))
        _check(result, started, hostile, folder, before)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _document(workspace: Path, name: str) -> dict[str, Any]:
    data: dict[str, Any] = json.loads((workspace / name).read_text())
    return data


DEMOS = json.loads((EXAMPLES / "blocks" / "demonstrations.json").read_text())
SCENE = json.loads((EXAMPLES / "scenes" / "pyramid-fig4.json").read_text())


@given(text=mutated_json(DEMOS))
@settings(SETTINGS, max_examples=70)
def test_learn_on_a_mutated_demonstration_file(workspace: Path, text: str) -> None:
    _run(workspace, "demos.json", text, lambda f, h: ["learn", str(h), "-o", str(f / "out.json")])


@given(text=mutated_json(SCENE))
@settings(SETTINGS, max_examples=60)
def test_plan_in_a_mutated_scene(workspace: Path, text: str) -> None:
    _run(
        workspace, "hostile-scene.json", text, lambda f, h: ["plan", str(f / "model.json"), str(h)]
    )


@given(text=mutated_json(SCENE))
@settings(SETTINGS, max_examples=30)
def test_problem_for_a_mutated_scene(workspace: Path, text: str) -> None:
    _run(
        workspace,
        "hostile-scene.json",
        text,
        lambda f, h: ["problem", str(f / "model.json"), str(h), "-o", str(f / "out.xml")],
    )


@pytest.fixture(scope="module")
def model_document(workspace: Path) -> dict[str, Any]:
    return _document(workspace, "model.json")


@given(data=st.data())
@settings(SETTINGS, max_examples=60)
def test_show_and_plan_with_a_mutated_model(
    workspace: Path, model_document: dict[str, Any], data: st.DataObject
) -> None:
    text = data.draw(mutated_json(model_document))
    command = data.draw(st.sampled_from(["show", "plan"]))
    _run(
        workspace,
        "hostile-model.json",
        text,
        lambda f, h: (
            ["show", str(h)] if command == "show" else ["plan", str(h), str(f / "scene.json")]
        ),
    )


PROBLEM = (EXAMPLES / "planning" / "paper-example.xml").read_text()


@st.composite
def mutated_xml(draw: st.DrawFn) -> str:
    """The paper's example problem with one attribute value or element changed."""
    import re

    values = [m.span(1) for m in re.finditer(r'="([^"]*)"', PROBLEM)]
    kind = draw(st.sampled_from(["attribute", "attribute", "cut", "element"]))
    if kind == "cut":
        return PROBLEM[: draw(st.integers(0, len(PROBLEM) - 1))]
    if kind == "element":
        start = draw(st.sampled_from([m.start() for m in re.finditer(r"<[a-zA-Z]", PROBLEM)]))
        extra = draw(
            st.sampled_from(["<unknown/>", "<object/>", '<location name=""/>', "<!-- -->"])
        )
        return PROBLEM[:start] + extra + PROBLEM[start:]
    start, end = draw(st.sampled_from(values))
    value = draw(
        st.sampled_from(["", "nan", "1e308", "-1e308", "x" * 5000, "a b", "&amp;", "0", "-1"])
    )
    return PROBLEM[:start] + value + PROBLEM[end:]


@given(text=mutated_xml())
@settings(SETTINGS, max_examples=60)
def test_solve_a_mutated_problem(workspace: Path, text: str) -> None:
    _run(workspace, "hostile.xml", text, lambda f, h: ["solve", str(h), "--timeout", "2"])


STREAM = (EXAMPLES / "streams" / "set-table-1.csv").read_text().splitlines()


@st.composite
def mutated_csv(draw: st.DrawFn) -> str:
    """The recorded stream with one cell, line or header changed."""
    lines = list(STREAM)
    index = draw(st.integers(0, len(lines) - 1))
    cells = lines[index].split(",")
    column = draw(st.integers(0, len(cells) - 1))
    kind = draw(st.sampled_from(["cell", "cell", "cell", "drop-cell", "quote", "cut"]))
    if kind == "cut":
        return "\n".join(lines[:index])
    if kind == "drop-cell":
        del cells[column]
    elif kind == "quote":
        cells[column] = '"a\nb"'
    else:
        cells[column] = draw(
            st.sampled_from(["", "nan", "inf", "1e308", "-1e308", "x", "1e-320", "9" * 400, "a b"])
        )
    lines[index] = ",".join(cells)
    return "\n".join(lines) + "\n"


@given(text=mutated_csv())
@settings(SETTINGS, max_examples=40)
def test_segment_a_mutated_stream(workspace: Path, text: str) -> None:
    _run(
        workspace, "hostile.csv", text, lambda f, h: ["segment", str(h), "-o", str(f / "out.json")]
    )
