"""``evaluate``: many seeded runs, here or on Ray, summed up."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from demoplan.cli.common import SimName, app, print_json, reported_errors, stderr, stdout
from demoplan.errors import UsageError

if TYPE_CHECKING:
    from demoplan.commands.evaluation import Evaluation
    from demoplan.evaluation.runs import RunRow


@contextmanager
def _progress(
    show: bool,
) -> Iterator[tuple[Callable[..., None] | None, Callable[..., None] | None]]:
    """A live bar on stderr (a terminal only): runs done, successes so far, the ETA."""
    if not show:
        yield None, None
        return
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
    )

    bar = Progress(
        TextColumn("evaluating"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[ok]}"),
        TimeRemainingColumn(),
        console=stderr,
        transient=True,
    )
    task = bar.add_task("runs", total=None, ok="")
    successes = [0, 0]  # successes, rows seen

    def on_start(done: int, planned: int) -> None:
        bar.update(task, completed=done, total=planned)

    def on_row(row: RunRow, done: int, planned: int) -> None:
        successes[0] += row.success
        successes[1] += 1
        bar.update(task, completed=done, ok=f"{successes[0]}/{successes[1]} succeeded")

    with bar:
        yield on_start, on_row


def _print_summary(done: Evaluation) -> None:
    summary = done.summary
    low, high = summary.interval
    table = Table(title=f"Evaluation in {done.folder}", title_justify="left")
    for column in ("runs", "succeeded", "rate", "95 % interval", "errors", "made now"):
        table.add_column(column, justify="right")
    table.add_row(
        str(summary.runs),
        str(summary.successes),
        f"{summary.rate:.1%}",
        f"{low:.1%} – {high:.1%}",
        str(summary.errors),
        f"{done.made} of {done.planned}",
    )
    stdout.print(table)
    if summary.judged is not None:
        judged = summary.judged
        env_low, env_high = judged.env_interval
        stdout.print(
            f"robosuite's check: {judged.env_successes} of {summary.runs} "
            f"({env_low:.1%} – {env_high:.1%}); demoplan's goal reached: "
            f"{judged.demoplan_successes}; succeeded counts runs where both say so",
            markup=False,
            highlight=False,
        )
    replans = ", ".join(f"{k}: {v}" for k, v in summary.replans.items())
    stdout.print(f"replans (count: runs): {replans}", markup=False, highlight=False)
    if summary.confusion:
        confusion = Table(title="Injected → detected (runs)", title_justify="left")
        kinds = sorted({k for seen in summary.confusion.values() for k in seen} - {"runs"})
        for column in ("injected", "runs", *kinds):
            confusion.add_column(column, justify="left" if column == "injected" else "right")
        for kind, seen in summary.confusion.items():
            confusion.add_row(kind, str(seen["runs"]), *(str(seen.get(k, 0)) for k in kinds))
        stdout.print(confusion)
    failed = [row for row in summary.worst if not row.success]
    for row in failed:
        stdout.print(f"{row.status}: {row.run_id}: {row.reason}", markup=False, highlight=False)
    stdout.print(
        f"wrote {done.folder / 'runs.jsonl'} and {done.report}", markup=False, highlight=False
    )


@app.command()
def evaluate(
    model_path: Annotated[
        Path | None,
        typer.Argument(metavar="MODEL", help="A model file (from learn); not with --resume."),
    ] = None,
    scene_paths: Annotated[
        list[Path] | None,
        typer.Argument(metavar="SCENE", help="Scene files to run in (none with robosuite:ENV)."),
    ] = None,
    random_scenes: Annotated[
        int, typer.Option(min=0, help="Also N random start layouts from the model's workspace.")
    ] = 0,
    clutter: Annotated[
        int, typer.Option(min=0, help="Clutter objects on goal targets in each random layout.")
    ] = 0,
    faults: Annotated[
        str | None,
        typer.Option(help="Faults to inject, kind=probability,... (as for run)."),
    ] = None,
    seeds: Annotated[
        int,
        typer.Option(
            min=1, help="Runs per scene (scene j: seeds jK … jK+K-1; robosuite: seeds 0 … K-1)."
        ),
    ] = 1,
    sim: Annotated[
        str,
        typer.Option(
            help="The simulated world (as for run): kinematic, mujoco, arm or robosuite:ENV "
            "(run k: robosuite's ENV after reset(k); no SCENE, --random-scenes, --clutter "
            "or --faults)."
        ),
    ] = SimName.kinematic.value,
    workers: Annotated[
        int | None,
        typer.Option(
            min=0, help="Local Ray workers (default: the cores); 0: one after the other, no Ray."
        ),
    ] = None,
    address: Annotated[
        str | None,
        typer.Option(
            help="Join this Ray cluster (host:port, ray://host:port or auto); it has "
            "30 s to answer."
        ),
    ] = None,
    out: Annotated[
        Path | None, typer.Option(help="Folder for the rows, scenes and summary.")
    ] = None,
    resume: Annotated[
        Path | None,
        typer.Option(help="Finish the evaluation in this folder: only runs with no row."),
    ] = None,
    json_output: Annotated[bool, typer.Option("--json", help="Print the summary as JSON.")] = False,
) -> None:
    """Evaluate a model over many seeded runs (scenes × seeds, faults), here or on Ray."""
    from demoplan.commands.evaluation import engine_for, settings_from_options
    from demoplan.commands.evaluation import evaluate as evaluate_runs

    with reported_errors():
        settings: Any = None
        if resume is not None:
            if model_path is not None or scene_paths or out is not None:
                raise UsageError("--resume DIR takes no MODEL, SCENE or --out (DIR holds them)")
            folder = resume
        else:
            if model_path is None or out is None:
                raise UsageError("MODEL and --out DIR expected (or --resume DIR)")
            folder = out
            settings = settings_from_options(
                model_path,
                scene_paths or [],
                random_scenes=random_scenes,
                seeds=seeds,
                faults=faults,
                sim=sim,
                clutter=clutter,
            )
        engine = engine_for(workers, address)
        try:
            with _progress(stderr.is_terminal and not json_output) as (on_start, on_row):
                done = evaluate_runs(
                    settings,
                    folder,
                    resume=resume is not None,
                    engine=engine,
                    on_start=on_start,
                    on_row=on_row,
                )
        except KeyboardInterrupt:  # the finished rows are written: say how to go on
            rows = folder / "runs.jsonl"
            kept = f"the finished runs are in {rows}" if rows.exists() else "no run had finished"
            if (folder / "evaluation.json").exists():  # else nothing was begun
                where = (
                    f" --address {address}"
                    if address is not None
                    else f" --workers {workers}"
                    if workers is not None
                    else ""
                )
                stderr.print(
                    f"demoplan: {kept}; --resume {folder}{where} makes the others",
                    markup=False,
                    highlight=False,
                )
            raise
        if json_output:
            print_json(done.summary.to_json())
        else:
            _print_summary(done)
