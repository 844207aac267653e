"""``experiments``: the paper's experiments reproduced and the report written."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from demoplan.experiments import ExperimentsResult, run_experiments
from demoplan.fileio import staged_folder

__all__ = ["REPORT_FILES", "reproduce_experiments"]

REPORT_FILES = re.compile(r"report\.(md|html)$|summary\.json$|experiment\d")
"""The files a report folder holds (an earlier report's are replaced)."""


def reproduce_experiments(
    out: Path, *, progress: Callable[[str], object] | None = None
) -> ExperimentsResult:
    """Reproduce the paper's experiments (Tables II–V, §IV.C, §V) into the
    folder ``out``: the whole report or none of it — built beside ``out``,
    then put in its place (an earlier report is replaced; a folder of
    anything else is refused). ``progress(text)`` hears each stage."""
    with staged_folder(out, lambda name: bool(REPORT_FILES.match(name))) as building:
        result = run_experiments(building, progress=progress)
    return replace(
        result,
        report=out / result.report.name,
        html=None if result.html is None else out / result.html.name,
    )
