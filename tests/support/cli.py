"""The one way tests call the command line in process: typer's runner on the
``demoplan`` application, every argument as its text (paths, numbers)."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner, Result

from demoplan.cli import app


def invoke(*args: str | Path | float) -> Result:
    """``demoplan ARGS`` in this process: its exit code, stdout and stderr apart."""
    return CliRunner().invoke(app, [str(a) for a in args])


def exit_and_output(*args: str | Path | float) -> tuple[int, str, str]:
    """:func:`invoke`'s exit code, stdout and stderr."""
    result = invoke(*args)
    return result.exit_code, result.stdout, result.stderr
