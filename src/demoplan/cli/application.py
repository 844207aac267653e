"""The typer application: every command module registered on one app."""

from __future__ import annotations

from demoplan.cli import (  # noqa: F401 - commands
    evaluation,
    execution,
    export,
    learning,
    planning,
    recordings,
    report,
    studio,
)
from demoplan.cli.common import app
from demoplan.cli.render import fitted_table, states_table

__all__ = ["app", "fitted_table", "main", "states_table"]


def main() -> None:
    """Run the typer application (the ``demoplan`` executable is
    :func:`demoplan.cli.launcher.main`)."""
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
