"""Temporary: the installed ``demoplan`` script of an older editable install."""

from demoplan.cli.launcher import main

__all__ = ["main"]
