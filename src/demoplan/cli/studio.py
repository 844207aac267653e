"""``studio``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from demoplan.cli.common import app, reported_errors


@app.command()
def studio(
    workdir: Annotated[
        Path,
        typer.Option(
            help="The work folder: demonstrations, scenes and models are read and written "
            "here only (made if missing)."
        ),
    ] = Path(),
    host: Annotated[
        str,
        typer.Option(help="The address to listen on (loopback: only this machine can connect)."),
    ] = "127.0.0.1",
    port: Annotated[
        int, typer.Option(min=0, max=65535, help="The port to listen on (0: a free one).")
    ] = 0,
    no_browser: Annotated[
        bool, typer.Option("--no-browser", help="Print the URL only; do not open a browser.")
    ] = False,
) -> None:
    """Teach, learn, plan and run in the browser: a local web page (the paper's
    virtual environment, §V.A). Prints its URL; Ctrl-C stops it."""
    with reported_errors():
        from demoplan.studio.server import serve

        serve(workdir, host=host, port=port, open_browser=not no_browser)
