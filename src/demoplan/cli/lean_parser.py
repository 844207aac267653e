"""The argument parser of the lean paths (``solve``, ``perceive``;
:mod:`demoplan.cli.launcher`): argparse that, where it would print a usage
error, leaves the command line to typer instead, whose errors are the
documented ones."""

from __future__ import annotations

import argparse

__all__ = ["DeclinedError", "LeanParser"]


class DeclinedError(Exception):
    """The lean parser leaves this command line to typer."""


class LeanParser(argparse.ArgumentParser):
    """argparse raising :class:`DeclinedError` where it would print an error."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise DeclinedError(message)
