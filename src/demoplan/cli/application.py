"""The typer application: every command module registered on one app."""

from __future__ import annotations

from demoplan.cli import execution, learning, planning, recordings, report  # noqa: F401 - commands
from demoplan.cli.common import app
from demoplan.cli.render import fitted_table, states_table
from demoplan.commands.execution import FRAME_FILES
from demoplan.commands.experiments import REPORT_FILES

__all__ = ["FRAME_FILES", "REPORT_FILES", "app", "fitted_table", "main", "states_table"]


def main() -> None:
    """Run the typer application (the ``demoplan`` executable is
    :func:`demoplan.cli.launcher.main`)."""
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
