"""``python -m demoplan.cli``: the typer application."""

from demoplan.cli import main

main()
