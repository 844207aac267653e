"""``evaluate``: many seeded runs of a task model, here or on Ray, as a table of rows
(docs/execution.md "Evaluation")."""

from __future__ import annotations

import importlib.util
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from demoplan.commands.execution import run
from demoplan.errors import InputError, UsageError
from demoplan.evaluation.engine import Engine, RayEngine, SerialEngine, require_ray
from demoplan.evaluation.plan import (
    SETTINGS,
    EvaluationSettings,
    check_settings,
    plan_runs,
    read_settings,
    scene_documents,
    write_plan,
)
from demoplan.evaluation.report import write_report
from demoplan.evaluation.results import (
    Journal,
    Summary,
    read_rows,
    summarise,
    write_rows,
)
from demoplan.evaluation.runs import RUN_SETTINGS, RunRow, RunSpec, execute_run
from demoplan.execution.faults import parse_faults
from demoplan.execution.robosuite_run import is_robosuite
from demoplan.execution.robosuite_scene import check_installed, environment_name
from demoplan.fileio import display_path, dump_json, write_atomic
from demoplan.learning.modelfile import load_model
from demoplan.model import TaskModel

__all__ = ["Evaluation", "engine_for", "evaluate", "run_one"]

SIMS = ("kinematic", "mujoco", "arm")
STORYBOARDS = 5
"""The worst runs whose storyboard an evaluation makes (each run made again)."""
WORST = "worst"
"""The folder of those storyboards, one ``RUN_ID/`` folder each (``demoplan run --frames``)."""


@dataclass(frozen=True, slots=True)
class Evaluation:
    """An evaluation's outcome: its folder, every row (in the runs' order),
    what they sum up to, the runs this call made (the others were done) of
    those planned, and its page (``report.html``)."""

    folder: Path
    rows: tuple[RunRow, ...]
    summary: Summary
    made: int
    planned: int
    report: Path
    storyboards: dict[str, str]
    """Each worst run's storyboard (a path in ``folder``), or why it has none."""


def engine_for(workers: int | None, address: str | None, max_retries: int = 2) -> Engine:
    """``--workers 0``: the runs here, one after the other; else Ray (local, or ``address``)."""
    if workers is not None and address is not None:
        raise UsageError("--workers starts a local Ray, --address joins a cluster: one of them")
    if workers == 0:
        return SerialEngine()
    require_ray()
    return RayEngine(workers=workers, address=address, max_retries=max_retries)


def run_one(model: TaskModel, spec: RunSpec) -> RunRow:
    """One evaluated run, made as ``demoplan run`` makes it (:func:`execute_run`
    with :func:`demoplan.commands.execution.run`)."""
    return execute_run(run, model, spec)


def _check_robosuite(settings: EvaluationSettings) -> None:
    """``--sim robosuite:ENV``: a known environment, and none of the options that
    make or change scenes (robosuite's ``reset(seed)`` makes each run's)."""
    environment_name(settings.sim)  # a usage error names the environments
    given = [
        ("SCENE files", bool(settings.scenes)),
        ("--random-scenes", settings.random_scenes > 0),
        ("--clutter", settings.clutter > 0),
        ("--faults", bool(settings.faults)),
    ]
    if refused := [name for name, on in given if on]:
        raise UsageError(
            f"{', '.join(refused)}: not with --sim {settings.sim} (each run's scene is "
            "robosuite's environment after reset(seed), which injects nothing); --seeds N expected"
        )


def _check(settings: EvaluationSettings) -> None:
    if is_robosuite(settings.sim):
        _check_robosuite(settings)
        return
    parse_faults(settings.faults)  # a usage error names what is wrong
    if settings.sim not in SIMS:
        raise UsageError(
            f"--sim {settings.sim}: one of {', '.join(SIMS)} or robosuite:ENV expected"
        )
    if not settings.scenes and settings.random_scenes <= 0:
        raise UsageError("no scenes: SCENE files or --random-scenes N expected")
    if settings.seeds <= 0 or settings.clutter < 0 or settings.random_scenes < 0:
        raise UsageError("--seeds ≥ 1, --random-scenes ≥ 0 and --clutter ≥ 0 expected")


def _check_new_folder(out: Path) -> None:
    """``--out``: a new or empty folder (an evaluation's: ``--resume``); nothing of
    anyone else's is overwritten."""
    if (out / SETTINGS).exists():
        raise UsageError(
            f"{display_path(out)} holds an evaluation: --resume {display_path(out)} to "
            "finish it, or another --out"
        )
    if out.exists() and not out.is_dir():
        raise InputError(
            "exists and is not a folder; a new or empty folder expected", source=display_path(out)
        )
    if out.is_dir() and any(out.iterdir()):
        raise InputError(
            "is not empty and holds no evaluation; a new or empty folder expected",
            source=display_path(out),
        )


def evaluate(
    settings: EvaluationSettings | None,
    out: Path,
    *,
    resume: bool = False,
    engine: Engine | None = None,
    on_row: Callable[[RunRow, int, int], object] | None = None,
    on_start: Callable[[int, int], object] | None = None,
    runner: Callable[[RunSpec], RunRow] | None = None,
) -> Evaluation:
    """Carry out ``settings``' runs and write their rows in ``out`` (``runs.jsonl``,
    ``summary.json``, ``report.html``, the scenes, the settings). ``resume``: ``out`` holds an
    evaluation (its settings; ``settings`` is then None): make only the runs
    with no row. ``on_start(done, planned)`` hears the counts before the first
    run, ``on_row(row, done, planned)`` each row as it comes. A Ctrl-C
    (KeyboardInterrupt) stops the runs and, before it goes on, writes every
    finished row. ``runner``: what makes a run (default: :func:`run_one`
    with the settings' model). With ``--sim robosuite:ENV`` (robosuite
    installed) run k is robosuite's environment after ``reset(k)``, judged by
    robosuite too (the rows' ``env_success``)."""
    if resume:
        settings = read_settings(out)
    elif settings is None:
        raise UsageError("settings, or --resume with an evaluation's folder, expected")
    else:
        _check_new_folder(out)
    assert settings is not None
    _check(settings)
    if is_robosuite(settings.sim):
        check_installed(settings.sim)  # before anything is written
    model = load_model(settings.model)
    documents = scene_documents(model, settings)  # a bad scene: refused before any cluster
    engine = engine or SerialEngine()
    with engine.session():  # a cluster that does not answer: nothing written
        write_plan(out, model, settings, documents)  # on resume: the scenes a stop left unwritten
        specs = plan_runs(out, settings)
        rows = read_rows(out)
        order = [spec.run_id for spec in specs]
        todo = [spec for spec in specs if spec.run_id not in rows]
        if on_start is not None:
            on_start(len(specs) - len(todo), len(specs))
        journal = Journal(out)
        try:
            for row in engine.rows(todo, runner or partial(run_one, model)):
                if row.run_id in rows:  # never a duplicate row
                    continue
                rows[row.run_id] = row
                journal.add(row)
                if on_row is not None:
                    on_row(row, len(rows), len(specs))
        finally:
            journal.close()
            write_rows(out, rows, order)
    ordered = tuple(rows[i] for i in order if i in rows)
    summary = summarise(ordered)
    write_atomic(out / "summary.json", dump_json(summary.to_json()))
    boards = make_storyboards(out, settings, summary.worst[:STORYBOARDS])
    page = write_report(out, settings, list(ordered), summary, len(specs), boards)
    return Evaluation(out, ordered, summary, len(todo), len(specs), page, boards)


def make_storyboards(
    out: Path, settings: EvaluationSettings, worst: Sequence[RunRow]
) -> dict[str, str]:
    """Each of ``worst``'s storyboards: its run made again (a run is a function of
    its scene file, seed, faults and sim; in robosuite of its seed) with
    ``--frames out/worst/RUN_ID``, here, one after the other; a storyboard
    already there is kept. By run id: the storyboard's path relative to
    ``out``, or ``"no storyboard: WHY"``."""
    if importlib.util.find_spec("matplotlib") is None:
        return {row.run_id: "no storyboard: matplotlib is not installed" for row in worst}
    boards: dict[str, str] = {}
    for row in worst:
        folder = out / WORST / row.run_id
        board = folder / "storyboard.png"
        if not board.is_file():
            try:
                run(
                    settings.model,
                    None if is_robosuite(row.sim) else out / "scenes" / f"{row.scene}.json",
                    sim=row.sim,
                    faults=parse_faults(row.faults),
                    seed=row.seed,
                    clutter=settings.clutter > 0,
                    frames=folder,
                    settings=RUN_SETTINGS,
                )
            except InputError as exc:  # a run that is refused (an error row) draws nothing
                boards[row.run_id] = f"no storyboard: {exc.message}"
                continue
            except Exception as exc:  # nor one that crashes (its row says so)
                boards[row.run_id] = f"no storyboard: {type(exc).__name__}: {exc}"
                continue
        boards[row.run_id] = board.relative_to(out).as_posix()
    return boards


def settings_from_options(
    model: Path,
    scenes: Sequence[Path],
    *,
    random_scenes: int,
    seeds: int,
    faults: str | None,
    sim: str,
    clutter: int,
) -> EvaluationSettings:
    """The settings of ``evaluate MODEL SCENE… --random-scenes …`` (paths made absolute:
    ``--resume`` may run from elsewhere)."""
    settings = EvaluationSettings(
        model=str(model.resolve()),
        scenes=tuple(str(s.resolve()) for s in scenes),
        random_scenes=random_scenes,
        seeds=seeds,
        faults=faults or "",
        sim=sim,
        clutter=clutter,
    )
    check_settings(settings)
    return settings
