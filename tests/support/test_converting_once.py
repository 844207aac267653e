"""The tests' runner and fork server convert demoplan's application into its click
command once (tests/support/forkserver.py ``converting_once``): every later call gets
that command, any other application is converted as typer does."""

from __future__ import annotations

import typer
import typer.main
import typer.testing

from demoplan.cli import app
from tests.support.cli import invoke
from tests.support.forkserver import converting_once


def test_the_application_is_converted_once_and_others_each_time() -> None:
    calls: list[typer.Typer] = []

    def convert(instance: typer.Typer) -> object:
        calls.append(instance)
        return object()

    other = typer.Typer()
    get_command = converting_once(app, convert)
    first = get_command(app)
    assert get_command(app) is first
    assert get_command(other) is not get_command(other)
    assert calls == [app, other, other]


def test_the_runner_uses_one_command_for_every_call() -> None:
    invoke("--help")
    command = typer.testing._get_command(app)
    invoke("--version")
    assert typer.testing._get_command(app) is command
    assert command.name == typer.main.get_command(app).name
