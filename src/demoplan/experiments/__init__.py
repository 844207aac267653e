"""``demoplan experiments``: reproduce the paper's experiments and write a report.

Both experiments (§V.A, §V.B), learning and planning: the learned states,
sequences and constraints are compared with the paper's Tables II–V
(:mod:`~demoplan.experiments.paper`, :mod:`~demoplan.experiments.compare`);
each model is then planned in a run-time scene (``examples/scenes/``) — for
Experiment 2 the paper's Fig. 4 scene, where demonstration 1's goal takes 5
moves and demonstration 2's 4 — and Experiment 2 is executed in MuJoCo; a
recorded stream is segmented; fresh draws measure how often Table II comes
out (:mod:`~demoplan.experiments.runs`). :mod:`~demoplan.experiments.report`
writes the report.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from demoplan.experiments.compare import Check, compare_with_paper
from demoplan.experiments.paper import (
    CONSTRAINTS_EXPERIMENT_2,
    PAPER_CONSTRAINTS_EXPERIMENT_1,
    PAPER_TABLE_II,
    PAPER_TABLE_III,
    PAPER_TABLE_IV,
    PAPER_TABLE_V,
    PaperState,
)
from demoplan.experiments.report import write_report
from demoplan.experiments.runs import (
    examples_dir,
    execute_experiment,
    learn_experiment,
    plan_experiment,
    precision_study,
    segment_experiment,
)
from demoplan.model import TaskModel
from demoplan.scenes.plan import ScenePlan

__all__ = [
    "PAPER_TABLE_II",
    "PAPER_TABLE_III",
    "PAPER_TABLE_IV",
    "PAPER_TABLE_V",
    "Check",
    "ExperimentsResult",
    "PaperState",
    "compare_with_paper",
    "examples_dir",
    "run_experiments",
]


@dataclass(frozen=True, slots=True)
class ExperimentsResult:
    report: Path
    checks: tuple[Check, ...]
    models: tuple[TaskModel, ...]
    plans: tuple[ScenePlan, ...] = ()
    html: Path | None = None  # the same report as one self-contained page


def run_experiments(
    out: Path, progress: Callable[[str], object] | None = None
) -> ExperimentsResult:
    """Run both experiments, the segmentation of a stream and the fresh draws,
    and write the report into ``out``; ``progress(text)`` hears each stage."""
    notify = progress or (lambda text: None)
    out = Path(out)
    examples = examples_dir()
    experiments = [
        (
            "Experiment 1 (set table)",
            "experiment1-set-table",
            examples / "set_table",
            PAPER_TABLE_II,
            PAPER_TABLE_III,
            PAPER_CONSTRAINTS_EXPERIMENT_1,
            None,
            examples / "scenes" / "set-table-cluttered.json",
        ),
        (
            "Experiment 2 (blocks)",
            "experiment2-blocks",
            examples / "blocks" / "demonstrations.json",
            PAPER_TABLE_IV,
            PAPER_TABLE_V,
            CONSTRAINTS_EXPERIMENT_2,
            "5 by the rule (text: four)",
            examples / "scenes" / "pyramid-fig4.json",
        ),
    ]
    learned, planned, executed = [], [], []
    for title, stem, source, table, sequences, n_constraints, stated, scene in experiments:
        notify(f"{title}: learning")
        learning = learn_experiment(
            title, source, table, sequences, n_constraints, out, stem, stated
        )
        learned.append(learning)
        notify(f"{title}: planning in {scene.name}")
        # The paper gives plans for Experiment 2 only (§V.B).
        second = stem.startswith("experiment2")
        planning = plan_experiment(title, learning.model, scene, out, stem, against_paper=second)
        planned.append(planning)
        notify(f"{title}: executing on the arm in MuJoCo")
        executed.append(
            execute_experiment(
                title, learning.model, planning.scene, out / f"{stem}-arm", vision=second
            )
        )
    notify("Experiment 1 (set table): segmenting a recorded stream")
    segmented = segment_experiment(out)
    notify("Experiment 1 (set table): fresh draws against placement precision")
    precision = precision_study(out)
    report, page = write_report(out, learned, planned, executed, segmented, precision)
    checks = [c for r in learned for c in r.checks] + [c for r in planned for c in r.checks]
    checks += [c for r in executed for c in r.checks] + list(segmented.checks)
    return ExperimentsResult(
        report,
        tuple(checks),
        tuple(r.model for r in learned),
        tuple(r.result for r in planned),
        page,
    )
