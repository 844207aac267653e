"""One evaluated run: a scene, a seed, the faults and the world in → one row out.

A run is carried out exactly as ``demoplan run MODEL SCENE --sim SIM --faults
FAULTS --seed SEED --timeout inf [--clutter]`` carries it out (the command
layer's ``run`` is passed in: :data:`RunFunction`; ``--sim robosuite:ENV``
takes no SCENE): each (re)planning without a time
limit (:data:`RUN_SETTINGS`), so that a row does not depend on how busy the
machine or the worker was — with ``run``'s default 2 s, a replan on a loaded
worker could end with another plan than the same replan in a serial run. Its
row keeps what an evaluation
compares (docs/execution.md "Evaluation"). A run that raises is a row too:
``status`` ``error`` with the exception, never a lost run.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, fields
from typing import Any

from demoplan.budget import Budget
from demoplan.errors import InputError
from demoplan.execution.executor import ExecutionSettings, RunEvent, RunReport
from demoplan.execution.faults import parse_faults
from demoplan.execution.robosuite_run import JudgedRunReport
from demoplan.model import TaskModel
from demoplan.scenes.scene import scene_from_document

__all__ = ["TIMING_FIELDS", "RunFunction", "RunRow", "RunSpec", "error_row", "execute_run"]

RunFunction = Callable[..., RunReport]
"""What carries a run out: :func:`demoplan.commands.execution.run`'s signature
(model, scene or None; ``sim``, ``faults``, ``seed``, ``clutter``, ``on_event``,
``settings`` by keyword)."""

TIMING_FIELDS = ("planning_s", "execution_s", "attempts")
"""Fields of a row that differ between two runs of one spec (the clock, the engine)."""


@dataclass(frozen=True, slots=True)
class RunSpec:
    """One run to make: ``scene`` names the scene document ``layout`` (a file's
    stem or ``random-N``; with ``--sim robosuite:ENV`` the environment's name and
    no layout: robosuite's ``reset(seed)`` makes the scene), ``faults`` is
    ``--faults``' text."""

    scene: str
    layout: dict[str, Any] | None
    seed: int
    faults: str = ""
    sim: str = "kinematic"
    clutter: bool = False

    @property
    def run_id(self) -> str:
        return f"{self.scene}/seed-{self.seed}"


@dataclass(frozen=True, slots=True)
class RunRow:
    """What one run did (one line of ``runs.jsonl``). ``status``: ``success``,
    ``failed`` (the executor gave up or found no plan: ``reason``) or ``error``
    (the run raised, or its worker died more often than allowed)."""

    run_id: str
    scene: str
    seed: int
    sim: str
    faults: str
    status: str
    success: bool
    replans: int = 0
    actions: int = 0
    injected: dict[str, int] = field(default_factory=dict)
    detected: dict[str, int] = field(default_factory=dict)
    final_error_mm: float | None = None
    """The largest final position error of a goal object (mm); None: none measured."""
    reason: str = ""
    planning_s: float = 0.0
    """Seconds from the start to the first plan, and from each failure to its replan."""
    execution_s: float = 0.0
    """The run's other seconds: acting, observing, comparing."""
    attempts: int = 1
    first_plan_length: int = 0
    gave_up: bool = False
    """A limit (replans, actions) stopped the run, not a missing plan."""
    first_failure: str = ""
    """The first failure the executor detected: ``kind: detail``."""
    pose_errors_mm: dict[str, float] = field(default_factory=dict)
    """Each goal object's final position error (mm)."""
    collisions: int = 0
    """The robot's contacts with anything but its load (``--sim arm``)."""
    refused_motions: int = 0
    """Motions a check found impossible (``--sim arm``)."""
    simulated_s: float | None = None
    """Seconds the physics simulated (``mujoco``, ``arm``, ``robosuite:ENV``)."""
    env_success: bool | None = None
    """robosuite's ``_check_success()`` after the run (``robosuite:ENV``; else None)."""
    demoplan_success: bool | None = None
    """Whether demoplan's executor reached a goal (``robosuite:ENV``: ``success``
    is this and ``env_success`` together; else None)."""

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RunRow:
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in data.items() if k in names})

    def outcome(self) -> dict[str, Any]:
        """The row without its timing: equal for two runs of one spec."""
        return {k: v for k, v in self.to_json().items() if k not in TIMING_FIELDS}


def error_row(spec: RunSpec, reason: str, attempts: int = 1) -> RunRow:
    """The row of a run that did not finish."""
    return RunRow(
        spec.run_id,
        spec.scene,
        spec.seed,
        spec.sim,
        spec.faults,
        "error",
        False,
        reason=reason,
        attempts=attempts,
    )


class _Clock:
    """Planning time from the run's events: start → plan, failure → replan."""

    def __init__(self) -> None:
        self.mark: float | None = time.perf_counter()
        self.planning = 0.0

    def __call__(self, event: RunEvent) -> None:
        now = time.perf_counter()
        if event.kind in ("plan", "replan") and self.mark is not None:
            self.planning += now - self.mark
            self.mark = None
        elif event.kind == "failure":
            self.mark = now


RUN_SETTINGS = ExecutionSettings(budget=Budget(timeout=None))
"""An evaluated run's settings: ``run``'s defaults, planning without a time limit
(``run --timeout inf``; the search's limit of states kept still holds)."""


def execute_run(run: RunFunction, model: TaskModel, spec: RunSpec) -> RunRow:
    """Carry ``spec`` out with ``run`` as ``demoplan run`` would; any exception
    becomes an ``error`` row."""
    started = time.perf_counter()
    clock = _Clock()
    try:
        scene = None if spec.layout is None else scene_from_document(spec.layout, spec.scene)
        report = run(
            model,
            scene,
            sim=spec.sim,
            faults=parse_faults(spec.faults),
            seed=spec.seed,
            clutter=spec.clutter,
            on_event=clock,
            settings=RUN_SETTINGS,
        )
    except InputError as exc:  # refused before the first motion
        return error_row(spec, f"refused: {exc}")
    except Exception as exc:  # a crash is a finding: kept as the run's row
        return error_row(spec, f"exception: {type(exc).__name__}: {exc}")
    total = time.perf_counter() - started
    judged = report if isinstance(report, JudgedRunReport) else None
    errors = [1e3 * e for e in report.pose_errors.values()]
    return RunRow(
        spec.run_id,
        spec.scene,
        spec.seed,
        spec.sim,
        spec.faults,
        "success" if report.success else "failed",
        report.success,
        replans=report.replans,
        actions=len(report.actions),
        injected=dict(sorted(Counter(f.kind for f in report.injected).items())),
        detected=dict(sorted(Counter(f.kind for f in report.failures).items())),
        final_error_mm=round(max(errors), 6) if errors else None,
        reason=report.reason if not report.success else "",
        planning_s=round(clock.planning, 6),
        execution_s=round(max(0.0, total - clock.planning), 6),
        first_plan_length=report.first_plan_length,
        gave_up=report.gave_up,
        first_failure=(
            f"{report.failures[0].kind}: {report.failures[0].detail}" if report.failures else ""
        ),
        pose_errors_mm={k: round(e, 6) for k, e in zip(report.pose_errors, errors, strict=True)},
        collisions=len(report.collisions),
        refused_motions=len(report.motions_refused),
        simulated_s=None
        if report.simulated_seconds is None
        else round(report.simulated_seconds, 6),
        env_success=judged.env_success if judged else None,
        demoplan_success=judged.demoplan_success if judged else None,
    )
