"""The experiments themselves, each returning a frozen result: learning an
experiment and comparing it with the paper's tables, planning it in a
run-time scene, executing Experiment 2 in MuJoCo (and on vision), segmenting
a recorded stream, and how often fresh draws learn Table II as the placement
precision varies. Figures are written into the report folder as they are
made; :mod:`demoplan.experiments.report` turns the results into text.
"""

from __future__ import annotations

import importlib.resources
import importlib.util
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.experiments.compare import Check, compare_with_paper, plan_checks
from demoplan.experiments.paper import (
    PAPER_TABLE_II,
    PAPER_TABLE_III,
    PaperState,
    distinct_places,
    paper_experiment_1,
    table_places,
)
from demoplan.learning import TaskModelLearner
from demoplan.learning.settings import PAPER_SETTINGS, LearningSettings
from demoplan.model import TaskModel
from demoplan.scenes.landmarks import complete_scene
from demoplan.scenes.plan import ScenePlan, plan_in_scene
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene, load_scene
from demoplan.wording import plural

__all__ = [
    "ExecutionRun",
    "LearningRun",
    "PlanningRun",
    "PrecisionStudy",
    "SegmentationRun",
    "examples_dir",
    "execute_experiment",
    "learn_experiment",
    "plan_experiment",
    "precision_study",
    "segment_experiment",
]

logger = logging.getLogger(__name__)


def examples_dir() -> Path:
    """The shipped ``examples/`` folder (inside the wheel, or the source checkout)."""
    packaged = Path(str(importlib.resources.files("demoplan"))) / "examples"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[3] / "examples"


@dataclass(frozen=True, slots=True)
class LearningRun:
    """An experiment learned with the paper's reading and compared with its tables."""

    title: str
    source: Path
    model: TaskModel
    checks: tuple[Check, ...]
    figure: str | None  # the demonstrations and constraints, a file in the report folder
    seconds: float


@dataclass(frozen=True, slots=True)
class PlanningRun:
    """Every demonstrated goal planned in a run-time scene, the shortest chosen."""

    title: str
    scene_path: Path
    scene: Scene
    result: ScenePlan
    checks: tuple[Check, ...]  # against §V.B (Experiment 2 only)
    figure: str | None
    seconds: float


@dataclass(frozen=True, slots=True)
class ExecutionRun:
    """The chosen plan run by the arm in MuJoCo with a storyboard and a video,
    and (Experiment 2) again on vision."""

    title: str
    skipped: str | None  # why it was not run (MuJoCo, mink or dm_control missing)
    success: bool = False
    actions: int = 0
    replans: int = 0
    pose_errors: tuple[tuple[str, float], ...] = ()
    storyboard: str | None = None
    video: str | None = None  # an MP4 of the run, when imageio-ffmpeg is installed
    vision: bool = False  # also run on vision
    vision_success: bool = False
    vision_actions: int = 0
    vision_replans: int = 0
    checks: tuple[Check, ...] = ()
    seconds: float = 0.0
    collisions: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class SegmentationRun:
    """A demonstration played back as a tracker would record it, and segmented."""

    title: str
    stream_file: str
    samples: int
    moves: int
    nudges: int  # small moves segmentation saw and left out (not steps)
    checks: tuple[Check, ...]
    figure: str | None
    seconds: float


@dataclass(frozen=True, slots=True)
class PrecisionStudy:
    """How often fresh draws with Experiment 1's structure learn Table II, per
    placement precision σ: with the paper's reading (its ten states) and at
    the defaults (its seven places)."""

    sigmas_mm: tuple[float, ...]
    draws: int
    paper_states: tuple[int, ...]  # draws that gave Table II's ten states, per σ
    default_places: tuple[int, ...]  # draws that gave its seven places, per σ
    figure: str | None
    seconds: float


def learn_experiment(
    title: str,
    source: Path,
    table: tuple[PaperState, ...],
    sequences: tuple[str, ...],
    n_constraints: int,
    out: Path,
    stem: str,
    paper_constraints: str | None = None,
) -> LearningRun:
    """Learn ``source`` with the paper's reading (the examples were drawn for
    it, examples/README.md), save the model, compare with the paper, and draw
    the demonstrations with their constraints."""
    from demoplan.learning.modelfile import save_model

    started = time.perf_counter()
    model = TaskModelLearner(PAPER_SETTINGS).fit(load_demonstrations([source])).model_
    save_model(model, out / f"{stem}.model.json")
    checks = compare_with_paper(model, title, table, sequences, n_constraints, paper_constraints)
    figure = _plot_demonstrations(model, out / f"{stem}-demonstrations.png", title)
    return LearningRun(title, source, model, tuple(checks), figure, time.perf_counter() - started)


def plan_experiment(
    title: str, model: TaskModel, scene_path: Path, out: Path, stem: str, against_paper: bool
) -> PlanningRun:
    """Plan every candidate goal of ``model`` in the scene, draw the chosen plan;
    ``against_paper``: compare with §V.B's plans (Experiment 2)."""
    started = time.perf_counter()
    scene = load_scene(scene_path)
    result = plan_in_scene(model, prepare(model, scene))
    checks = plan_checks(title, result) if against_paper else []
    figure = _plot_plan(model, scene, result, out / f"{stem}-plan.png")
    return PlanningRun(
        title, scene_path, scene, result, tuple(checks), figure, time.perf_counter() - started
    )


def execute_experiment(
    title: str, model: TaskModel, scene: Scene, frames: Path, vision: bool
) -> ExecutionRun:
    """The chosen plan executed by the arm in MuJoCo (Fig. 4, right: the paper's
    robot carrying out the plan), with a storyboard and a video; with
    ``vision``, the same again on what the top camera sees (the Hough
    transform, stacking from occlusion)."""
    missing = [m for m in ("mujoco", "mink", "dm_control") if importlib.util.find_spec(m) is None]
    if missing:
        return ExecutionRun(
            title, f"{', '.join(missing)} not installed (`pip install 'demoplan[sim]'`)"
        )
    from demoplan.execution.runner import run_task

    started = time.perf_counter()
    filmed = importlib.util.find_spec("imageio_ffmpeg") is not None
    video = frames.parent / f"{frames.name}.mp4" if filmed else None
    prepared = prepare(model, scene)
    report = run_task(model, prepared, sim="arm", frames=frames, video=video)
    worst = max(report.pose_errors.values(), default=float("inf"))
    done = Check(
        title,
        "Executed by the arm (MuJoCo)",
        "goal reached, every object within 10 mm, the arm touching nothing but its load",
        f"{'reached' if report.success else 'NOT reached'}, max error {1000 * worst:.1f} mm, "
        f"{plural(len(report.collisions), 'collision')}",
        report.success and worst < 0.01 and not report.collisions,
    )
    checks = [done]
    seen = None
    if vision:
        seen = run_task(model, prepared, sim="arm", perception="camera")
        checks.append(
            Check(
                title,
                "Executed on vision (top camera)",
                "goal reached from the camera's view",
                "reached" if seen.success else f"NOT reached: {seen.reason}",
                seen.success,
            )
        )
    storyboard = frames / "storyboard.png"
    return ExecutionRun(
        title,
        None,
        report.success,
        len(report.actions),
        report.replans,
        tuple(report.pose_errors.items()),
        f"{frames.name}/storyboard.png" if storyboard.exists() else None,
        video.name if video is not None and video.exists() else None,
        vision,
        seen is not None and seen.success,
        len(seen.actions) if seen is not None else 0,
        seen.replans if seen is not None else 0,
        tuple(checks),
        time.perf_counter() - started,
        report.collisions,
    )


def segment_experiment(out: Path) -> SegmentationRun:
    """Demonstration 1 of Experiment 1 as a tracker would record it — a 60 Hz pose
    stream with 2 mm noise, lift–carry–place moves, a few dropped samples, one
    nudge — and the steps segmentation finds in it, against the demonstration's."""
    from demoplan.segmentation import segment, write_csv
    from demoplan.segmentation.synthetic import compare_steps, stream_from_demonstration

    started = time.perf_counter()
    title = "Experiment 1 (set table)"
    demo = load_demonstrations([examples_dir() / "set_table" / "demonstration-1.json"])[0]
    stream = stream_from_demonstration(
        demo, rate_hz=60, noise_m=0.002, rng=1, drop_fraction=0.03, nudges=1
    )
    stream_file = "experiment1-stream.csv"
    write_csv(stream, out / stream_file)
    found = segment(stream)
    steps = found.to_demonstration(demo.name)
    comparison = compare_steps(demo.steps, steps.steps)
    order = [s.object for s in steps.steps] == [s.object for s in demo.steps]
    worst = max(comparison.errors, default=float("inf"))
    check = Check(
        title,
        "Stream segmented into the demonstration's steps",
        f"{len(demo.steps)} steps in order",
        f"{len(steps.steps)} steps{' in order' if order else ', order differs'}, "
        f"max error {1000 * worst:.1f} mm",
        len(steps.steps) == len(demo.steps) and order and worst < 0.005,
    )
    figure = None
    if _can_plot():
        from demoplan.plotting.segmentation import plot_segmentation

        plot_segmentation(found, out / "experiment1-segmentation.png")
        figure = "experiment1-segmentation.png"
    return SegmentationRun(
        title,
        stream_file,
        stream.n_samples,
        len(found.moves),
        len(found.nudges),
        (check,),
        figure,
        time.perf_counter() - started,
    )


PRECISION_SIGMAS_MM = (0.3, 0.5, 1.0, 2.0, 3.0, 5.0, 8.0)
"""Placement precisions (RMS, per axis) of the precision study."""
PRECISION_DRAWS = 20
"""Fresh draws per precision in ``demoplan experiments``."""


def precision_study(
    out: Path,
    sigmas_mm: tuple[float, ...] = PRECISION_SIGMAS_MM,
    draws: int = PRECISION_DRAWS,
    seed: int = 0,
) -> PrecisionStudy:
    """Draw ``draws`` new sets of three demonstrations with Experiment 1's
    structure per σ (:func:`~demoplan.experiments.paper.paper_experiment_1`)
    and learn each twice: with the paper's reading, counting the draws that give
    Table II's ten states (objects and references), and at the defaults,
    counting those that give its seven places (one state per place, each
    within 1 cm)."""
    started = time.perf_counter()
    rng = np.random.default_rng(seed)
    sequences = [tuple(s.replace("-", "")) for s in PAPER_TABLE_III]
    places = table_places(PAPER_TABLE_II, sequences)
    merged = distinct_places(places)
    seven = {places[p] for p in set(merged.values())}
    expected = [(r.id, r.object, r.position_reference) for r in PAPER_TABLE_II]
    paper_counts, default_counts = [], []
    for sigma in sigmas_mm:
        paper_ok = default_ok = 0
        for _ in range(draws):
            draw = paper_experiment_1(rng, sigma=sigma / 1000)
            model = TaskModelLearner(PAPER_SETTINGS).fit(draw.demos).model_
            got = [(s.id, s.object, s.position.reference) for s in model.states]
            paper_ok += got == expected
            model = TaskModelLearner(LearningSettings()).fit(draw.demos).model_
            default_ok += _learns_places(model, draw.demos, seven)
        paper_counts.append(paper_ok)
        default_counts.append(default_ok)
    figure = _plot_precision(sigmas_mm, draws, paper_counts, default_counts, out)
    return PrecisionStudy(
        tuple(sigmas_mm),
        draws,
        tuple(paper_counts),
        tuple(default_counts),
        figure,
        time.perf_counter() - started,
    )


def _learns_places(
    model: TaskModel, demos: list[Any], places: set[tuple[str, tuple[float, ...]]]
) -> bool:
    """One state per place of ``places`` (object, x y), each state's mean
    placement within 1 cm of its place."""
    if len(model.states) != len(places):
        return False
    matched = set()
    for state in model.states:
        mean = np.mean([demos[d].steps[k].pose.position[:2] for d, k in state.members], axis=0)
        near = [p for p in places if p[0] == state.object and math.dist(p[1], mean) <= 0.01]
        if len(near) != 1:
            return False
        matched.add(near[0])
    return matched == places


def _plot_precision(
    sigmas_mm: tuple[float, ...],
    draws: int,
    paper_counts: list[int],
    default_counts: list[int],
    out: Path,
) -> str | None:
    if not _can_plot():
        return None
    from demoplan.plotting.backend import tight_layout, use_agg

    use_agg()
    import matplotlib.pyplot as plt

    from demoplan.plotting.output import save_figure

    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    ax.plot(
        sigmas_mm,
        [100 * c / draws for c in paper_counts],
        "o-",
        label=("the paper's reading (3 mm / 0.5° ties): Table II's 10 states"),
    )
    ax.plot(
        sigmas_mm,
        [100 * c / draws for c in default_counts],
        "s-",
        label=("demoplan's defaults (precision estimated, F test): its 7 places"),
    )
    ax.set_xscale("log")
    ax.minorticks_off()
    ax.set_xticks(sigmas_mm, [f"{s:g}" for s in sigmas_mm])
    ax.set_xlabel("placement precision σ (mm, per axis)")
    ax.set_ylabel(f"draws learning Table II (%, of {draws})")
    ax.set_ylim(-5, 105)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")
    ax.set_title(
        "Fresh demonstrations with Experiment 1's structure (a new scene per draw)", fontsize=9
    )
    tight_layout(fig)
    path = out / "experiment1-precision.png"
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)
    return path.name


def _plot_plan(model: TaskModel, scene: Any, result: ScenePlan, path: Path) -> str | None:
    from demoplan.plotting.figures import save_scene_plan

    chosen = result.chosen
    title = (
        f"Plan for the goal of {model.demonstration_label(chosen.goal)}: "
        f"{len(chosen.plan) // 2} moves"
    )
    if not _can_plot():
        return None
    save_scene_plan(
        complete_scene(scene, model),
        chosen.problem,
        chosen.plan,
        path,
        title,
        chosen.binding.roles,
    )
    return path.name


def _plot_demonstrations(model: TaskModel, path: Path, title: str) -> str | None:
    if not _can_plot():
        logger.warning(
            "matplotlib is not installed; the report has no figures (pip install demoplan[plot])"
        )
        return None
    from demoplan.plotting.figures import save_demonstrations

    save_demonstrations(model, path, title)
    return path.name


def _can_plot() -> bool:
    """matplotlib is installed (asked of the installation, not by catching an
    ``ImportError``: an import that Ctrl-C interrupts fails with one too)."""
    return importlib.util.find_spec("matplotlib") is not None
