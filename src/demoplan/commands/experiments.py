"""``experiments``: the paper's experiments reproduced and the report written."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from demoplan.experiments import ExperimentsResult, run_experiments
from demoplan.fileio import staged_folder

__all__ = ["reproduce_experiments"]


def reproduce_experiments(
    out: Path, *, progress: Callable[[str], object] | None = None
) -> ExperimentsResult:
    """Reproduce the paper's experiments (Tables II–V, §IV.C, §V) into the
    folder ``out``: the whole report or none of it — built beside ``out``,
    then put in its place. An earlier report is replaced when its
    manifest proves demoplan wrote every file in it; a folder holding
    anything else is refused, never removed (:func:`~demoplan.fileio.staged_folder`).
    ``progress(text)`` hears each stage."""
    with staged_folder(out, "demoplan experiments") as building:
        result = run_experiments(building, progress=progress)
    return replace(
        result,
        report=out / result.report.name,
        html=None if result.html is None else out / result.html.name,
    )
