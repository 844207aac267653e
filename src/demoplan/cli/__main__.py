"""``python -m demoplan.cli``: the typer application."""

from demoplan.cli.application import main

main()
