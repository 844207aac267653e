"""The code stays readable: no function body in src/demoplan is longer than
:data:`MAX_BODY_LINES` lines — a function doing several jobs is split into
one function per step, named after it.

A body runs from its first statement (the docstring, where there is one) to
its last line, so a long signature — a CLI command's typer options — does not
count, and a nested function counts towards the function around it too."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "demoplan"
MAX_BODY_LINES = 100

Function = ast.FunctionDef | ast.AsyncFunctionDef


def body_lines(function: Function) -> int:
    """Lines from ``function``'s first body statement to its last line."""
    assert function.end_lineno is not None
    return function.end_lineno - function.body[0].lineno + 1


def long_functions(source: str, limit: int = MAX_BODY_LINES) -> list[tuple[str, int, int]]:
    """(name, line, body lines) of every function in ``source`` whose body is
    longer than ``limit`` lines."""
    return [
        (node.name, node.lineno, body_lines(node))
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and body_lines(node) > limit
    ]


def _modules() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def test_no_function_body_is_longer_than_a_screen() -> None:
    modules = _modules()
    assert len(modules) > 50  # the walk found the package
    found = [
        f"{path.relative_to(PACKAGE.parent)}:{line}: {name} has a {length}-line body"
        for path in modules
        for name, line, length in long_functions(path.read_text(encoding="utf-8"))
    ]
    assert not found, (
        f"function bodies over {MAX_BODY_LINES} lines (split them into one function "
        "per step):\n" + "\n".join(found)
    )


def _function(signature_lines: int, body: int, *, docstring: bool = False) -> str:
    parameters = "".join(f"    p{i}: int = 0,\n" for i in range(signature_lines))
    statements = ['    """Doc."""\n'] if docstring else []
    statements += [f"    x{i} = {i}\n" for i in range(body - len(statements))]
    return f"def f(\n{parameters}) -> None:\n" + "".join(statements)


@pytest.mark.parametrize(
    ("signature_lines", "body", "docstring", "flagged"),
    [
        (0, 100, False, False),
        (0, 101, False, True),
        (0, 101, True, True),  # a docstring is part of the body
        (60, 90, False, False),  # a long signature (typer options) does not count
        (200, 101, False, True),
    ],
)
def test_the_rule_counts_the_body_not_the_signature(
    signature_lines: int, body: int, docstring: bool, flagged: bool
) -> None:
    source = _function(signature_lines, body, docstring=docstring)
    found = long_functions(source)
    assert bool(found) is flagged
    if flagged:
        assert found == [("f", 1, body)]


def test_a_nested_function_counts_towards_its_outer_one() -> None:
    inner = "".join(f"        y{i} = {i}\n" for i in range(60))
    outer = "".join(f"    x{i} = {i}\n" for i in range(45))
    source = f"def outer() -> None:\n{outer}    def inner() -> None:\n{inner}"
    assert long_functions(source) == [("outer", 1, 106)]
