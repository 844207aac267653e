"""One run of ``demoplan experiments`` for the whole test session.

The command takes minutes (the arm's two runs in MuJoCo are most of it), and
several tests read what it writes: the report (tests/experiments/test_experiments.py) and
every figure as it was written (tests/experiments/test_figure_labels.py). They share this
run, made through the command's entry point with the figures observed as they are saved
(:func:`demoplan.plotting.observing_saved_figures`), in a process of its own
beside the tests (tests/support/background.py, the fixture ``experiments_run``).

The same run is the hostile suite's ``experiments --open`` without a web
browser (tests/hostile/test_new_options.py): it is made as that test made it,
through the command's entry point in a process of its own, with stderr apart.

The run is audited too (tests/hostile/test_open_audit.py): the job runs under
``strace -f`` where strace works, with a user's file planted beside the
report before it starts (:func:`plant_the_users_file`), and the run records
what its harness itself writes and the environment it was given.

The arm's runs are recorded with their inputs (:class:`ArmRun`), and so are
the segmentation of the recorded stream and the precision study (:class:`Recorded`):
a test that runs the experiments again with a changed paper table (the
mismatch test) may replay them where they are given the very same inputs —
none of them reads the paper's tables that the test changes.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from matplotlib.colors import to_hex
from matplotlib.patches import Rectangle
from matplotlib.transforms import Bbox

from tests.support.background import JobFolder


@dataclass
class AxesRecord:
    """What one axes of a written figure showed, in display coordinates."""

    frame: Bbox
    ylabel: str
    texts: list[tuple[str, Bbox]]
    rectangles: list[tuple[str, float, bool, str, float, float]]
    """Each rectangle: face colour (or edge colour if unfilled), alpha, filled,
    line style, and its bottom and top in data coordinates."""


def text_box(text: Any, renderer: Any) -> Bbox:
    """A text's letters and the box drawn around them (the constraint graphs' circles)."""
    box = text.get_window_extent(renderer)
    patch = text.get_bbox_patch()
    if patch is not None:
        box = Bbox.union([box, patch.get_window_extent(renderer)])
    return box.frozen()


def _rectangles(ax: Any) -> list[tuple[str, float, bool, str, float, float]]:
    found = []
    for patch in ax.patches:
        if isinstance(patch, Rectangle):
            colour = patch.get_facecolor() if patch.get_fill() else patch.get_edgecolor()
            box = patch.get_bbox()
            found.append(
                (
                    to_hex(colour),
                    patch.get_alpha() or 1.0,
                    bool(patch.get_fill()),
                    str(patch.get_linestyle()),
                    float(box.y0),
                    float(box.y1),
                )
            )
    return found


def axes_records(figure: Any, renderer: Any) -> list[AxesRecord]:
    """Every visible axes of ``figure`` as the renderer placed it."""
    return [
        AxesRecord(
            frame=ax.get_window_extent(renderer).frozen(),
            ylabel=ax.get_ylabel(),
            texts=[
                (t.get_text(), text_box(t, renderer))
                for t in ax.texts
                if t.get_visible() and t.get_text()
            ],
            rectangles=_rectangles(ax),
        )
        for ax in figure.axes
        if ax.get_visible()
    ]


@dataclass(frozen=True)
class ArmRun:
    """One call of :func:`demoplan.experiments.runs.execute_experiment` in the
    shared run: its inputs and what it returned (its files are in the report
    folder, ``frames`` and ``frames``.mp4)."""

    model: Any
    scene: Any
    frames: str
    vision: bool
    result: Any
    reports: tuple[tuple[str, Any], ...] = ()
    """Each of its runs of :func:`demoplan.execution.runner.run_task`, in order,
    with its perception: the filmed run (``"state"``), then with ``vision``
    the run on what the top camera sees (``"camera"``) — the arm's run
    reports, which tests/execution/test_arm.py reads instead of running the
    same runs again."""


@dataclass(frozen=True)
class Recorded:
    """One call of a stage without the arm in the shared run —
    :func:`demoplan.experiments.runs.segment_experiment` or
    :func:`~demoplan.experiments.runs.precision_study`: its arguments after the
    report folder, and what it returned (its files are in the report folder,
    by the names the result gives)."""

    arguments: tuple[Any, ...]
    keywords: dict[str, Any]
    result: Any

    def files(self) -> tuple[str, ...]:
        """The files the stage wrote into the report folder."""
        names = (getattr(self.result, "stream_file", None), self.result.figure)
        return tuple(name for name in names if name is not None)


RECORDED_STAGES = ("segment_experiment", "precision_study")
"""The stages of ``demoplan.experiments`` besides the arm that the shared run
records and :meth:`ExperimentsRun.replaying` gives back."""


USERS_FILE = "experiment1-notes.txt"
USERS_NOTES = "the user's notes"
CAPTURED = ("stdout.txt", "stderr.txt")
"""The files the command's stdout and stderr go to, in the working folder."""
ENVIRONMENT = ("HOME", "TMPDIR", "MPLCONFIGDIR", "XDG_CACHE_HOME")


def plant_the_users_file(folder: Path) -> None:
    """A user's file beside the report, before the run (tests/support/background.py
    calls it, outside the trace): the audit checks it is never touched."""
    (folder / USERS_FILE).write_text(USERS_NOTES)


@dataclass
class ExperimentsRun:
    """``demoplan experiments --out report --open`` run once, in a folder of its
    own and a process of its own, without a web browser: its exit code, stdout
    and stderr, the report folder, every figure it wrote (by its path in the
    report folder) and the arm's runs by experiment title; the job's folder
    (its strace log there if it ran under strace) and the environment's
    ``HOME``, ``TMPDIR`` and cache folders it was given."""

    report: Path
    exit_code: int
    output: str
    stderr: str
    job: JobFolder
    environment: dict[str, str] = field(default_factory=dict)
    figures: dict[str, list[AxesRecord]] = field(default_factory=dict)
    arm_runs: dict[str, ArmRun] = field(default_factory=dict)
    stages: dict[str, Recorded] = field(default_factory=dict)

    @property
    def users_file(self) -> Path:
        """The user's file planted beside the report (:func:`plant_the_users_file`)."""
        return self.report.parent / USERS_FILE

    @property
    def harness_writes(self) -> tuple[Path, ...]:
        """What the job's harness itself writes while traced, beside the
        command's report: the files stdout and stderr go to, and the result
        pickle (tests/support/background.py: written whole, then renamed)."""
        captured = tuple(self.report.parent / name for name in CAPTURED)
        return (*captured, self.job.partial_result, self.job.result)

    def replaying_the_arm(self) -> Callable[..., Any]:
        """A stand-in for ``execute_experiment`` that gives this run's result for
        the same title, after checking it was asked for the very same model,
        scene and vision (and copies the storyboard and video it wrote)."""

        def replay(title: str, model: Any, scene: Any, frames: Path, vision: bool) -> Any:
            arm = self.arm_runs[title]
            assert (model, scene, vision) == (arm.model, arm.scene, arm.vision), title
            assert frames.name == arm.frames
            if (self.report / arm.frames).exists():
                shutil.copytree(self.report / arm.frames, frames)
            video = self.report / f"{arm.frames}.mp4"
            if video.exists():
                shutil.copy(video, frames.parent / video.name)
            return arm.result

        return replay

    def replaying(self, stage: str) -> Callable[..., Any]:
        """A stand-in for the stage ``stage`` (one of :data:`RECORDED_STAGES`)
        that gives this run's result, after checking it was called with the
        very same arguments (and copies the files it wrote into the folder
        it is given)."""
        recorded = self.stages[stage]

        def replay(out: Path, *arguments: Any, **keywords: Any) -> Any:
            assert (arguments, keywords) == (recorded.arguments, recorded.keywords), stage
            for name in recorded.files():
                shutil.copy(self.report / name, Path(out) / name)
            return recorded.result

        return replay


ARM_PACKAGES = ("mujoco", "mink", "dm_control")
"""What :func:`demoplan.experiments.runs.execute_experiment` needs to run the arm."""

NO_BROWSER = ("DISPLAY", "WAYLAND_DISPLAY", "TERM", "BROWSER")
"""Without these no web browser is found: ``--open`` says to open the page by hand."""


def run_experiments_once(folder: Path) -> ExperimentsRun:
    """``demoplan experiments --out report --open`` in ``folder``, through the
    entry point of the ``demoplan`` command (:func:`demoplan.cli.launcher.main`),
    the figures observed as they are saved and the arm's runs recorded. Run
    in a process of its own (tests/support/background.py): it changes the working
    folder, the environment and the process's signal handlers."""
    import demoplan.experiments as experiments
    from demoplan.cli.launcher import main
    from demoplan.plotting.output import observing_saved_figures

    for name in NO_BROWSER:
        os.environ.pop(name, None)
    os.environ["COLUMNS"] = "100"
    folder = Path(folder).resolve()
    os.chdir(folder)
    environment = {name: os.environ[name] for name in ENVIRONMENT if name in os.environ}
    job = JobFolder(folder.parent)  # folder: the job's working folder (tests/support/background.py)
    run = ExperimentsRun(folder / "report", -1, "", "", job, environment)
    execute = experiments.execute_experiment

    def recorded(title: str, model: Any, scene: Any, frames: Path, vision: bool) -> Any:
        reports: list[tuple[str, Any]] = []
        if not all(importlib.util.find_spec(m) for m in ARM_PACKAGES):  # no arm runs
            result = execute(title, model, scene, frames, vision)
            run.arm_runs[title] = ArmRun(model, scene, frames.name, vision, result)
            return result
        import demoplan.execution.runner as runner  # as execute_experiment imports it

        run_task = runner.run_task

        def recording_run(*arguments: Any, **keywords: Any) -> Any:
            report = run_task(*arguments, **keywords)
            reports.append((keywords.get("perception", "state"), report))
            return report

        runner.run_task = recording_run  # type: ignore[assignment]
        try:
            result = execute(title, model, scene, frames, vision)
        finally:
            runner.run_task = run_task  # type: ignore[assignment]
        run.arm_runs[title] = ArmRun(model, scene, frames.name, vision, result, tuple(reports))
        return result

    def observe(figure: Any, renderer: Any, path: Path) -> None:
        # written into a folder beside the report, renamed to it at the end
        inside = Path(*(folder / path).relative_to(folder).parts[1:])  # folder: the cwd
        run.figures[inside.as_posix()] = axes_records(figure, renderer)

    def recording(stage: str) -> Callable[..., Any]:
        call = getattr(experiments, stage)

        def record(out: Path, *arguments: Any, **keywords: Any) -> Any:
            result = call(out, *arguments, **keywords)
            run.stages[stage] = Recorded(arguments, keywords, result)
            return result

        return record

    experiments.execute_experiment = recorded  # type: ignore[assignment]
    for stage in RECORDED_STAGES:
        setattr(experiments, stage, recording(stage))
    sys.argv = ["demoplan", "experiments", "--out", "report", "--open"]
    with (
        (folder / CAPTURED[0]).open("wb") as out,
        (folder / CAPTURED[1]).open("wb") as err,
        observing_saved_figures(observe),
    ):
        sys.stdout.flush()
        sys.stderr.flush()
        saved = os.dup(1), os.dup(2)
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        try:
            main()
        except SystemExit as end:
            run.exit_code = end.code if isinstance(end.code, int) else 1
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
    run.output = (folder / CAPTURED[0]).read_text(errors="replace")
    run.stderr = (folder / CAPTURED[1]).read_text(errors="replace")
    return run
