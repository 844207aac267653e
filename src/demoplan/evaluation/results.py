"""An evaluation's rows on disk, and what they sum up to.

While an evaluation runs, each finished row is appended to the journal
``runs.partial.jsonl`` (flushed and synced, one JSON line a row: a crash loses
at most the line being written, which is ignored when read back). When it
ends — finished or stopped by Ctrl-C — the rows are written atomically to
``runs.jsonl``, in the order of the runs planned, and the journal is removed.
Resuming reads both files and skips every run that has a row: each run has
exactly one row, whatever stopped the evaluation.
"""

from __future__ import annotations

import json
import math
import os
from collections import Counter, defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from statistics import NormalDist
from typing import Any, TextIO, get_type_hints

from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model

from demoplan.errors import InputError
from demoplan.evaluation.runs import RunRow
from demoplan.execution.robosuite_run import is_robosuite
from demoplan.fileio import describe_validation_error, display_path, write_atomic

__all__ = [
    "JOURNAL",
    "ROWS",
    "Journal",
    "Judged",
    "Summary",
    "read_rows",
    "summarise",
    "wilson_interval",
    "write_rows",
]

ROWS = "runs.jsonl"
JOURNAL = "runs.partial.jsonl"


def _read_lines(path: Path) -> Iterable[tuple[int, dict[str, Any]]]:
    if not path.is_file():
        return
    with path.open(encoding="utf-8") as lines:
        for number, line in enumerate(lines, start=1):
            if not line.endswith("\n"):  # a torn last line: the run is made again
                return
            try:
                data = json.loads(line)
            except ValueError:
                raise InputError(
                    f"line {number} is not JSON; a run row expected", source=display_path(path)
                ) from None
            if not isinstance(data, dict) or "run_id" not in data:
                raise InputError(
                    f"line {number}: a run row with a run_id expected", source=display_path(path)
                )
            yield number, data


def read_rows(folder: Path) -> dict[str, RunRow]:
    """The rows an evaluation in ``folder`` finished (its result file and its
    journal), by run id; the first row of a run counts."""
    rows: dict[str, RunRow] = {}
    for name in (ROWS, JOURNAL):
        for number, data in _read_lines(folder / name):
            try:
                checked = _RowSchema.model_validate(data)
            except ValidationError as exc:
                raise describe_validation_error(
                    exc, display_path(folder / name), prefix=f"line {number}"
                ) from None
            row = RunRow(**checked.model_dump())
            rows.setdefault(row.run_id, row)
    return rows


def _row_schema() -> type[BaseModel]:
    """A row as written, each field checked by its type, strictly (``"yes"`` is
    no ``success``): a tampered row is one line naming the line and the field.
    Made from :class:`RunRow`'s own fields, so that the two never differ."""
    hints = get_type_hints(RunRow)
    declared: dict[str, Any] = {}
    for row_field in fields(RunRow):
        if row_field.default_factory is not MISSING:
            default: Any = Field(default_factory=row_field.default_factory)
        elif row_field.default is not MISSING:
            default = row_field.default
        else:
            default = ...
        declared[row_field.name] = (hints[row_field.name], default)
    config = ConfigDict(extra="ignore", strict=True, allow_inf_nan=False)
    schema: type[BaseModel] = create_model("RunRowSchema", __config__=config, **declared)
    return schema


_RowSchema = _row_schema()


class Journal:
    """The journal rows are appended to as runs finish."""

    def __init__(self, folder: Path) -> None:
        self.path = folder / JOURNAL
        if (
            self.path.is_file()
        ):  # a torn last line (a killed evaluation) goes: its run is made again
            kept = self.path.read_bytes().rfind(b"\n") + 1
            with self.path.open("r+b") as torn:
                torn.truncate(kept)
        self._file: TextIO = self.path.open("a", encoding="utf-8")

    def add(self, row: RunRow) -> None:
        self._file.write(json.dumps(row.to_json(), sort_keys=True) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()


def write_rows(folder: Path, rows: dict[str, RunRow], order: Sequence[str]) -> Path:
    """``runs.jsonl``, atomically: the rows of ``order``'s runs that have one,
    in that order, then any others; the journal is then removed."""
    ranked = [rows[i] for i in order if i in rows]
    ranked += [row for i, row in rows.items() if i not in set(order)]
    text = "".join(json.dumps(row.to_json(), sort_keys=True) + "\n" for row in ranked)
    target = folder / ROWS
    write_atomic(target, text)
    (folder / JOURNAL).unlink(missing_ok=True)
    return target


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """The Wilson score interval of a success rate ((0, 1) for no runs).

    The normal quantile comes from the standard library (exact to double precision,
    like SciPy's): importing ``scipy.stats`` costs ~1.3 s in every process that reads
    an evaluation."""
    if n == 0:
        return 0.0, 1.0
    z = NormalDist().inv_cdf(0.5 + confidence / 2)
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


@dataclass(frozen=True, slots=True)
class Judged:
    """The runs robosuite's ``_check_success()`` passed (``env_successes``, with
    its Wilson 95 % interval) and those demoplan's executor ended at a goal; a
    run's ``success`` needs both. An error row counts as failed in each."""

    env_successes: int
    env_interval: tuple[float, float]
    demoplan_successes: int

    def to_json(self, runs: int) -> dict[str, Any]:
        return {
            "env_successes": self.env_successes,
            "env_success_rate": self.env_successes / runs if runs else 0.0,
            "env_wilson_95": list(self.env_interval),
            "demoplan_successes": self.demoplan_successes,
        }


@dataclass(frozen=True, slots=True)
class Summary:
    """What an evaluation's rows sum up to. ``confusion[kind]``: the runs a
    fault of ``kind`` was injected in (``runs``) and the failure kinds the
    executor detected in them (counts of runs)."""

    runs: int
    successes: int
    errors: int
    interval: tuple[float, float]
    replans: dict[int, int]
    confusion: dict[str, dict[str, int]] = field(default_factory=dict)
    worst: tuple[RunRow, ...] = ()
    judged: Judged | None = None
    """robosuite's and demoplan's verdicts apart (``--sim robosuite:ENV``); else None."""

    @property
    def rate(self) -> float:
        return self.successes / self.runs if self.runs else 0.0

    def to_json(self) -> dict[str, Any]:
        judged = {} if self.judged is None else self.judged.to_json(self.runs)
        return judged | {
            "runs": self.runs,
            "successes": self.successes,
            "errors": self.errors,
            "success_rate": self.rate,
            "wilson_95": list(self.interval),
            "replans": {str(k): v for k, v in sorted(self.replans.items())},
            "confusion": self.confusion,
            "worst": [row.run_id for row in self.worst],
        }


def _badness(row: RunRow) -> tuple[int, int, float]:
    rank = {"error": 0, "failed": 1}.get(row.status, 2)
    return rank, -row.replans, -(row.final_error_mm or 0.0)


def summarise(rows: Iterable[RunRow], worst: int = 10) -> Summary:
    """Success rate with its Wilson 95 % interval, the replans' distribution,
    the confusion table injected → detected, the ``worst`` runs."""
    listed = list(rows)
    successes = sum(r.success for r in listed)
    confusion: dict[str, Counter[str]] = defaultdict(Counter)
    for row in listed:
        for kind in row.injected:
            confusion[kind]["runs"] += 1
            confusion[kind].update(row.detected.keys())
    return Summary(
        runs=len(listed),
        successes=successes,
        errors=sum(r.status == "error" for r in listed),
        interval=wilson_interval(successes, len(listed)),
        replans=dict(sorted(Counter(r.replans for r in listed).items())),
        confusion={k: dict(sorted(v.items())) for k, v in sorted(confusion.items())},
        worst=tuple(sorted(listed, key=_badness)[:worst]),
        judged=_judged(listed),
    )


def _judged(rows: list[RunRow]) -> Judged | None:
    """robosuite's verdicts apart, where the runs were made in robosuite."""
    if not any(is_robosuite(r.sim) for r in rows):
        return None
    env = sum(r.env_success is True for r in rows)
    return Judged(
        env_successes=env,
        env_interval=wilson_interval(env, len(rows)),
        demoplan_successes=sum(r.demoplan_success is True for r in rows),
    )
