"""Learned results against the paper's: one :class:`Check` per row of its
tables, per sequence, for the number of constraints, and for the plans of
§V.B."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from demoplan.experiments.paper import (
    PAPER_PLAN_EXPERIMENT_2,
    PAPER_PLAN_MOVES_EXPERIMENT_2,
    PaperState,
)
from demoplan.learning.tables import format_orientation, format_position
from demoplan.model import TaskModel
from demoplan.scenes.plan import ScenePlan

__all__ = ["Check", "compare_with_paper", "plan_checks"]


@dataclass(frozen=True, slots=True)
class Check:
    """One comparison of a learned result with the paper."""

    experiment: str
    name: str
    paper: str
    ours: str
    ok: bool


def _describe(object_: str, reference: str | None, orientation_reference: str | None) -> str:
    text = object_.capitalize()
    if reference:
        text += f" rel. {reference.capitalize()}"
    if orientation_reference:
        text += f" (orient. rel. {orientation_reference.capitalize()})"
    return text


def _paper_values(row: PaperState) -> str:
    values = ", ".join(f"{v:.2f}" for v in row.position)
    theta = "" if row.theta is None else f", θ={row.theta:g}"
    return f"({values}{theta})"


def compare_with_paper(
    model: TaskModel,
    experiment: str,
    table: Sequence[PaperState],
    sequences: Sequence[str],
    n_constraints: int,
    paper_constraints: str | None = None,
) -> list[Check]:
    """Compare states (object, references, values to the paper's precision),
    sequences and the number of constraints with the paper's tables."""
    checks = []
    ours = {s.id: s for s in model.states}
    for row in table:
        described = _describe(row.object, row.position_reference, row.orientation_reference)
        paper = f"{described} {_paper_values(row)}"
        state = ours.get(row.id)
        if state is None:
            checks.append(Check(experiment, f"State {row.id}", paper, "missing", False))
            continue
        position = tuple(round(v, 2) for v in state.position.value[: len(row.position)])
        ok = (
            state.object == row.object
            and state.position.reference == row.position_reference
            and all(abs(a - b) < 1e-9 for a, b in zip(position, row.position, strict=True))
        )
        theta = ""
        if row.theta is not None:
            rpy = state.orientation.rpy
            ok = ok and rpy is not None and round(rpy[2]) == row.theta
            ok = ok and state.orientation.reference == row.orientation_reference
            theta = f", θ={format_orientation(state)}"
        ours_text = (
            f"{_describe(state.object, state.position.reference, state.orientation.reference)} "
            f"{format_position(state)[:-1]}{theta})"
        )
        checks.append(Check(experiment, f"State {row.id}", paper, ours_text, ok))
    extra = [s.id for s in model.states if s.id not in {r.id for r in table}]
    checks.append(
        Check(experiment, "Number of states", str(len(table)), str(len(model.states)), not extra)
    )
    for index, expected in enumerate(sequences):
        got = "-".join(model.sequences[index]) if index < len(model.sequences) else "missing"
        checks.append(Check(experiment, f"Sequence {index + 1}", expected, got, got == expected))
    checks.append(
        Check(
            experiment,
            "Constraints",
            paper_constraints or str(n_constraints),
            str(len(model.constraints)),
            len(model.constraints) == n_constraints,
        )
    )
    return checks


def _moved_objects(result: ScenePlan) -> tuple[str, ...]:
    plan = result.chosen.plan
    return tuple(a.object for a in plan.actions if a.kind == "GRASP") if plan else ()


def plan_checks(experiment: str, result: ScenePlan) -> list[Check]:
    """Experiment 2's plans against §V.B: 5 and 4 moves, demonstration 2's chosen."""
    moves = tuple(None if c.length is None else c.length // 2 for c in result.candidates)
    chosen = f"demonstration {result.chosen.goal + 1}: " + ", ".join(_moved_objects(result))
    paper = "demonstration 2: " + ", ".join(PAPER_PLAN_EXPERIMENT_2)
    return [
        Check(
            experiment,
            "Plan moves per goal (Fig. 4 scene)",
            " and ".join(map(str, PAPER_PLAN_MOVES_EXPERIMENT_2)),
            " and ".join("—" if m is None else str(m) for m in moves),
            moves == PAPER_PLAN_MOVES_EXPERIMENT_2,
        ),
        Check(experiment, "Plan chosen (objects moved)", paper, chosen, chosen == paper),
    ]
