"""The one way tests call the command line in process: typer's runner on the
``demoplan`` application, every argument as its text (paths, numbers).

typer's runner converts the application into its click command on every call
(each command's signature read again: ~27 ms of CPU, 418 times in the quick
loop); the conversion of ``demoplan``'s application is made once per process
and the same command serves every call, as one process's click command would."""

from __future__ import annotations

from pathlib import Path

import typer.main
import typer.testing
from typer.testing import CliRunner, Result

from demoplan.cli import app
from tests.support.forkserver import converting_once

# what CliRunner.invoke converts with
typer.testing._get_command = converting_once(app, typer.main.get_command)


def invoke(*args: str | Path | float) -> Result:
    """``demoplan ARGS`` in this process: its exit code, stdout and stderr apart."""
    return CliRunner().invoke(app, [str(a) for a in args])


def exit_and_output(*args: str | Path | float) -> tuple[int, str, str]:
    """:func:`invoke`'s exit code, stdout and stderr."""
    result = invoke(*args)
    return result.exit_code, result.stdout, result.stderr
