"""``experiments``: the paper reproduced, the report written."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from demoplan.cli.common import (
    app,
    plain_text,
    reported_errors,
    stderr,
    stdout,
)


@app.command()
def experiments(
    out: Annotated[Path, typer.Option(help="Folder for the report.")] = Path("demoplan-report"),
    open_report: Annotated[
        bool,
        typer.Option("--open", help="Open report.html in the web browser when done."),
    ] = False,
) -> None:
    """Reproduce the paper's experiments and write a report: report.md and a
    self-contained report.html (tables, figures, models)."""
    from demoplan.commands.experiments import reproduce_experiments

    with reported_errors():
        with stdout.status("Running the paper's experiments…") as status:
            result = reproduce_experiments(out, progress=lambda text: status.update(text))
        report = result.report
        table = Table(title="Paper vs. demoplan", title_justify="left")
        for column in ("Experiment", "Check", "Paper", "demoplan", "Match"):
            table.add_column(column)
        for check in result.checks:
            cells = (check.experiment, check.name, check.paper, check.ours)
            table.add_row(*map(plain_text, cells), "yes" if check.ok else "NO")
        stdout.print(table)
        stdout.print(f"Report: {report}", markup=False, highlight=False)
        if result.html is not None:
            page = result.html
            stdout.print(f"Report page: {page}", markup=False, highlight=False)
            if open_report and not _open_in_browser(page):
                stderr.print(
                    f"demoplan: note: no web browser to open {page} (open it by hand)",
                    markup=False,
                    highlight=False,
                )
        differing = [c for c in result.checks if not c.ok]
        if differing:
            names = ", ".join(f"{c.experiment.split(' (')[0]} {c.name}" for c in differing)
            stderr.print(
                f"demoplan: error: {len(differing)} results differ from the paper ({names}); "
                f"see {report}",
                markup=False,
                highlight=False,
            )
            raise typer.Exit(1)


def _open_in_browser(page: Path) -> bool:
    """Open a file in the user's web browser; False where there is none."""
    import webbrowser

    try:
        return webbrowser.open(page.resolve().as_uri())
    except webbrowser.Error:
        return False
