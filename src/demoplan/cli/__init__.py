"""The ``demoplan`` command line (docs/cli.md).

Commands only parse options, call the command layer (:mod:`demoplan.commands`)
and render what it returns with rich. ``--json`` output goes to stdout and
nothing else does; a domain error becomes one line on stderr and the exit
code of docs/cli.md. The typer application is assembled in
:mod:`demoplan.cli.application` and imported on first use, so that the lean launcher
(:mod:`demoplan.cli.launcher`) does not pay for it.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["app", "fitted_table", "main", "states_table"]


def __getattr__(name: str) -> Any:
    if name in __all__:
        return getattr(importlib.import_module("demoplan.cli.application"), name)
    raise AttributeError(f"module 'demoplan.cli' has no attribute {name!r}")
