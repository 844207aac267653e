"""The command layer: one function per thing a user does — learn, show,
segment, import, calibrate, perceive, plan, problem, solve, pddl, run, experiments,
and for the studio the targets in a scene and what a picked-up object carries —
each taking typed arguments (values, or the files that hold them) and
returning a frozen value (the model and what an update changed, the plan with
every candidate and its reason, the run report…), never printing, never
exiting. The command line (:mod:`demoplan.cli`) parses options and renders
these values; :mod:`demoplan.api` re-exports learn, plan and run; a browser
front end calls the same functions. Failures are the exceptions of
:mod:`demoplan.errors`, each with its exit code.

Names are imported on first use, so that ``demoplan solve`` (which needs only
:mod:`~demoplan.commands.solving`) does not pay for NumPy.
"""

from __future__ import annotations

import importlib
from typing import Any

_WHERE = {
    "learn_files": "learning",
    "learn_model": "learning",
    "show": "learning",
    "segment": "recordings",
    "import_recording": "recordings",
    "perceive": "perception",
    "calibrate": "perception",
    "run": "execution",
    "plan": "planning",
    "write_problem": "planning",
    "solve_problem": "solving",
    "export_pddl": "solving",
    "reproduce_experiments": "experiments",
    "targets": "scenes",
    "carried_by": "scenes",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        module = importlib.import_module(f"demoplan.commands.{_WHERE[name]}")
        return getattr(module, name)
    raise AttributeError(f"module 'demoplan.commands' has no attribute {name!r}")
