"""An evaluation's page (``report.html`` in its folder, from ``report.md``):
the success rate with its Wilson 95 % interval, per injected fault kind what
the executor detected, the distributions of replans and of final errors, and
the worst runs, each with the ``demoplan run`` command that repeats it and a
link to its storyboard (``worst/RUN_ID/storyboard.png``)."""

from __future__ import annotations

import html
from collections import Counter
from pathlib import Path

import numpy as np

from demoplan.evaluation.plan import EvaluationSettings
from demoplan.evaluation.results import Summary
from demoplan.evaluation.runs import RunRow
from demoplan.execution.robosuite_run import is_robosuite
from demoplan.experiments.report_html import markdown_to_html
from demoplan.fileio import write_atomic
from demoplan.wording import plural

__all__ = ["evaluation_markdown", "repeat_command", "write_report"]

ERROR_BINS_MM = (0.1, 1.0, 5.0, 10.0)
"""Upper bounds (mm) of the final-error histogram's bins; a last bin holds the rest."""


def _cell(text: object) -> str:
    """Text for a markdown table cell: HTML escaped, no pipe or line break."""
    return html.escape(str(text)).replace("|", "\\|").replace("\n", " ")


def _code(text: str) -> str:
    """Text for a code span in a table cell (markdown escapes the rest)."""
    return text.replace("`", "'").replace("|", "\\|").replace("\n", " ")


def _counts(counts: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in counts.items()) or "—"


def repeat_command(settings: EvaluationSettings, row: RunRow) -> str:
    """The ``demoplan run`` command that makes ``row``'s run again."""
    parts = ["demoplan run", settings.model]
    if not is_robosuite(row.sim):  # robosuite's reset(seed) is the scene
        parts.append(f"scenes/{row.scene}.json")
    parts.append(f"--sim {row.sim}")
    parts.append(f"--seed {row.seed} --timeout inf")
    if row.faults:
        parts.append(f"--faults {row.faults}")
    if settings.clutter:
        parts.append("--clutter")
    return " ".join(parts)


def _bar(n: int, most: int, width: int = 30) -> str:
    return "█" * max(1, round(width * n / most)) if n else ""


def _distributions(rows: list[RunRow], summary: Summary) -> list[str]:
    lines = ["## Replans", "", "| replans | runs | |", "|---:|---:|---|"]
    most = max(summary.replans.values(), default=1)
    lines += [f"| {k} | {v} | {_bar(v, most)} |" for k, v in summary.replans.items()]
    errors = [r.final_error_mm for r in rows if r.success and r.final_error_mm is not None]
    lines += ["", "## Final position errors (successful runs)", ""]
    if not errors:
        return [*lines, "No error measured."]
    median, p95 = np.percentile(errors, [50, 95])
    lines.append(
        f"The largest goal object's error per run: median {median:.3f} mm, "
        f"95th percentile {p95:.3f} mm, max {max(errors):.3f} mm."
    )
    bins = Counter(int(np.searchsorted(ERROR_BINS_MM, e, side="right")) for e in errors)
    labels = [f"< {b:g} mm" for b in ERROR_BINS_MM] + [f"≥ {ERROR_BINS_MM[-1]:g} mm"]
    most = max(bins.values())
    lines += ["", "| error | runs | |", "|---|---:|---|"]
    lines += [f"| {label} | {bins[i]} | {_bar(bins[i], most)} |" for i, label in enumerate(labels)]
    return lines


def _storyboard(board: str | None) -> str:
    if board is None:
        return "—"
    if board.startswith("no storyboard"):
        return _cell(board)
    return f"[storyboard]({board})"


def evaluation_markdown(
    settings: EvaluationSettings,
    rows: list[RunRow],
    summary: Summary,
    planned: int,
    storyboards: dict[str, str] | None = None,
) -> str:
    """The report's markdown; ``storyboards``: a worst run's storyboard (a path
    relative to the report) or why it has none, by run id."""
    boards = storyboards or {}
    low, high = summary.interval
    if is_robosuite(settings.sim):
        made = (
            f"{len(rows)} of {planned} runs made: robosuite's environment after "
            f"`reset(seed)` for seeds 0 … {settings.seeds - 1}, `--sim {settings.sim}`."
        )
    else:
        made = (
            f"{len(rows)} of {planned} runs made: {plural(len(settings.scenes), 'scene file')} "
            f"and {plural(settings.random_scenes, 'random layout')} × "
            f"{plural(settings.seeds, 'seed')}, "
            f"`--sim {settings.sim}`, faults `{settings.faults or 'none'}`"
            + (f", {settings.clutter} clutter objects per layout." if settings.clutter else ".")
        )
    lines = [
        f"# Evaluation of {_cell(Path(settings.model).name)}",
        "",
        made,
        "",
        f"**Success: {summary.successes} of {summary.runs} = {summary.rate:.1%}** "
        f"(95 % Wilson interval {low:.1%} – {high:.1%}); {summary.errors} runs ended in an error.",
        "",
    ]
    if summary.judged is not None:
        judged = summary.judged
        env_low, env_high = judged.env_interval
        env_rate = judged.env_successes / summary.runs if summary.runs else 0.0
        lines += [
            f"**robosuite's own check (`_check_success()`): {judged.env_successes} of "
            f"{summary.runs} = {env_rate:.1%}** (95 % Wilson interval {env_low:.1%} – "
            f"{env_high:.1%}); demoplan's executor reached its goal in "
            f"{judged.demoplan_successes}. A run succeeds only where both say so.",
            "",
        ]
    if summary.confusion:
        kinds = sorted({k for seen in summary.confusion.values() for k in seen} - {"runs"})
        lines += ["## Injected → detected", "", "Runs a fault kind was injected in, and in how"]
        lines += ["many of them each kind of failure was detected.", ""]
        lines += ["| injected | runs | " + " | ".join(kinds) + " |"]
        lines += ["|---|" + "---:|" * (len(kinds) + 1)]
        for kind, seen in summary.confusion.items():
            cells = [str(seen.get(k, 0)) for k in kinds]
            lines.append(f"| {kind} | {seen['runs']} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += _distributions(rows, summary)
    lines += ["", "## The worst runs", ""]
    lines += ["| run | status | replans | injected | detected | reason | repeat | storyboard |"]
    lines += ["|---|---|---:|---|---|---|---|---|"]
    for row in summary.worst:
        lines.append(
            f"| {_cell(row.run_id)} | {row.status} | {row.replans} | {_counts(row.injected)} | "
            f"{_counts(row.detected)} | {_cell(row.reason) or '—'} | "
            f"`{_code(repeat_command(settings, row))}` | {_storyboard(boards.get(row.run_id))} |"
        )
    return "\n".join(lines) + "\n"


def write_report(
    folder: Path,
    settings: EvaluationSettings,
    rows: list[RunRow],
    summary: Summary,
    planned: int,
    storyboards: dict[str, str] | None = None,
) -> Path:
    """``report.md`` and ``report.html`` in ``folder``; returns the page's path."""
    markdown = evaluation_markdown(settings, rows, summary, planned, storyboards)
    write_atomic(folder / "report.md", markdown)
    page = folder / "report.html"
    write_atomic(page, markdown_to_html(markdown, folder, "demoplan evaluate"))
    return page
