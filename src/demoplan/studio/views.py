"""What the command layer returns, as the JSON of the studio's API
(docs/studio-api.md): the learned model's states, sequences, constraints and
targets; a plan's lines in the CLI's words, the poses it moves the objects
to, its candidates, or why there is none; a run's events and report. Values
are only turned into JSON here, as the command line renders them
(:mod:`demoplan.cli.render`); nothing is learned, planned or run.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.errors import DemoplanError, error_line
from demoplan.model import Pose, TaskModel
from demoplan.scenes.scene import Scene

if TYPE_CHECKING:
    from demoplan.execution.report import RunEvent, RunReport
    from demoplan.execution.world import Observation
    from demoplan.scenes.plan import SceneLimitReachedError, SceneNoPlanError, ScenePlan

__all__ = [
    "LEARN_TABLE",
    "PLAN_START",
    "event_json",
    "finished_events",
    "model_json",
    "no_plan_json",
    "plan_json",
    "pose_json",
    "run_result_json",
    "targets_json",
    "world_json",
]

PLAN_START = "the Plan view's start"
"""The name an error gives the scene the Plan view plans and the Run view runs:
the page's start, which may be no file's (a scene loaded, then changed)."""
LEARN_TABLE = "the Learn view's table"
"""The name an error gives the table the Learn view draws the targets on."""


def pose_json(pose: Pose) -> dict[str, Any]:
    """``{"position": [x, y, z], "yaw": deg}``."""
    return {"position": [float(v) for v in pose.position], "yaw": round(pose.yaw, 6)}


def model_json(model: TaskModel) -> dict[str, Any]:
    """The states (as the paper's Tables II and IV: reference, value, spread,
    margin), the state sequences and the constraints as the report draws them
    (each demonstration's transitive reduction, together); where the model has
    roles of identical objects, the instance that filled each role in every
    demonstration (as the model file writes them). Each state's two references
    also in the words of ``learn``'s states table (``relative_position``,
    ``relative_orientation``: :func:`~demoplan.learning.tables.state_rows`,
    e.g. ``turns with lunchbox: never seen turned``) and its ``notes``, so the
    page and the terminal say the same."""
    from demoplan.learning.constraints import goal_order, visit_sequence
    from demoplan.learning.tables import orientation_reference_text, position_reference_text

    states = []
    for state in model.states:
        rpy = state.orientation.rpy
        margins = [m for _, m in state.margins]
        if state.position.anywhere:
            reference = "anywhere"
        else:
            reference = state.position.reference or "absolute"
        states.append(
            {
                "id": state.id,
                "object": state.object,
                "reference": reference,
                "orientation_reference": state.orientation.reference,
                "relative_position": position_reference_text(state),
                "relative_orientation": orientation_reference_text(state),
                "notes": list(state.notes),
                "position": [float(v) for v in state.position.value],
                "yaw": None if rpy is None else round(rpy[2], 6),
                "spread": math.sqrt(state.position.spread),
                "yaw_spread": (
                    None if state.orientation.value is None else math.sqrt(state.orientation.spread)
                ),
                "members": len(state.members),
                "margin": round(min(margins), 6) if margins else None,
            }
        )
    nodes: dict[str, None] = {}
    edges: dict[tuple[str, str], None] = {}
    for sequence in model.sequences:
        nodes.update(dict.fromkeys(visit_sequence(sequence)))
        order = goal_order(sequence, model.constraints)
        edges.update(dict.fromkeys(sorted(order.drawn)))
    roles = [
        {"name": role.name, "type": role.type, "instances": list(role.instances)}
        for role in model.roles
    ]
    return {
        "states": states,
        "sequences": [list(sequence) for sequence in model.sequences],
        "goals": [list(goal) for goal in model.goals],
        "constraints": {"nodes": list(nodes), "edges": [list(edge) for edge in edges]},
    } | ({"roles": roles} if roles else {})


def targets_json(model: TaskModel, scene: Scene | None) -> list[dict[str, Any]]:
    """The states of the first demonstration's goal resolved in ``scene`` (none:
    the first demonstration's final layout), where planning would put each object."""
    from demoplan.commands.scenes import targets

    return [
        {"state": target.state, "label": target.label, "object": target.object}
        | pose_json(target.pose)
        for target in targets(model, scene)
    ]


def plan_json(result: ScenePlan) -> dict[str, Any]:
    """The chosen plan in the CLI's words, each action's pose of its object
    after it, and every candidate goal with its length or why it has none."""
    model, chosen, scene = result.model, result.chosen, result.scene
    current = {obj.name: pose_json(obj.pose) for obj in scene.objects}
    moves = []
    for action in chosen.plan.actions:
        if action.kind == "PUT_DOWN":
            location = chosen.problem.location(action.location)
            current[action.object] = {
                "position": [float(v) for v in location.position],
                "yaw": round(location.yaw, 6),
            }
        moves.append(
            {
                "action": str(action),
                "kind": action.kind,
                "object": action.object,
                "location": action.location,
                "pose": current.get(action.object),
            }
        )
    return {
        "plan": [str(action) for action in chosen.plan.actions],
        "moves": moves,
        "candidates": [_candidate(model, c, result.is_chosen(c)) for c in result.candidates],
        "chosen": chosen.goal,
        "optimal": result.optimal,
        "no_plan": None,
    }


def _candidate(model: TaskModel, candidate: Any, chosen: bool) -> dict[str, Any]:
    return {
        "goal": candidate.goal,
        "demonstrations": [
            model.demonstration_number(k) for k in candidate.problem.candidate.demonstrations
        ],
        "length": candidate.length,
        "outcome": "chosen" if chosen else (candidate.reason or ""),
    }


def no_plan_json(failure: SceneNoPlanError | SceneLimitReachedError) -> dict[str, Any]:
    """No plan: the CLI's line, every candidate's outcome, and the figure
    ``plan --plot`` draws then (SVG text; None without matplotlib)."""
    return {
        "plan": [],
        "moves": [],
        "candidates": [
            {
                "goal": outcome.goal,
                "demonstrations": [
                    failure.model.demonstration_number(k)
                    for k in outcome.problem.candidate.demonstrations
                ],
                "length": outcome.length,
                "outcome": outcome.reason or "",
            }
            for outcome in failure.outcomes
        ],
        "chosen": None,
        "optimal": False,
        "no_plan": {"reason": error_line(failure), "figure": _no_plan_figure(failure)},
    }


def _no_plan_figure(failure: SceneNoPlanError | SceneLimitReachedError) -> str | None:
    """The figure of ``plan --plot`` without a plan, as SVG text."""
    from demoplan.plotting.figures import save_no_plan

    with tempfile.TemporaryDirectory(prefix="demoplan-studio-") as folder:
        path = Path(folder) / "no-plan.svg"
        try:
            save_no_plan(failure, path)
        except (ImportError, DemoplanError):
            return None
        return path.read_text(encoding="utf-8")


def world_json(observation: Observation | None) -> dict[str, Any] | None:
    """The world as observed: every object standing in it with its pose
    (:func:`pose_json`), and the object in the hand (it stands nowhere)."""
    if observation is None:
        return None
    return {
        "objects": {name: pose_json(pose) for name, pose in observation.poses.items()},
        "held": observation.held,
    }


def event_json(event: RunEvent) -> dict[str, Any]:
    """A run's event as the CLI's live display words it (``step N: text``),
    with the world the executor had last observed when it told the event
    (:attr:`RunEvent.observation`, :func:`world_json`) and, at the end, the
    run's status (``succeeded`` or ``failed``)."""
    return {
        "kind": event.kind,
        "text": event.text,
        "step": event.step,
        "replans": event.replans,
        "remaining": event.remaining,
        "world": world_json(event.observation),
        "status": None if event.status is None else str(event.status),
        "targets": {name: pose_json(pose) for name, pose in event.targets} or None,
    }


def run_result_json(report: RunReport, video: str | None) -> dict[str, Any]:
    """The run's report: success, why it ended, replans, the failures as the
    CLI prints them, the final world (:func:`world_json`)."""
    return {
        "success": report.success,
        "status": str(report.status),
        "exit_code": report.exit_code,
        "replans": report.replans,
        "reason": report.reason,
        "actions": len(report.actions),
        "failures": [f"step {f.step}: {f.kind}: {f.detail}" for f in report.failures],
        "injected": [
            f"injected at action {fault.action}: {fault.kind}: {fault.detail}"
            for fault in report.injected
        ],
        "final": {name: pose_json(pose) for name, pose in report.final.poses.items()},
        "world": world_json(report.final),
        "video": video,
    }


def finished_events(events: list[dict[str, Any]], report: RunReport) -> list[dict[str, Any]]:
    """``events`` once the run is over: the end (``done``) marked with the
    run's outcome (``success``: whether the goal was reached) and the final
    world, which the report observed last."""
    final = world_json(report.final)
    return [
        event | {"success": report.success, "world": final} if event["kind"] == "done" else event
        for event in events
    ]
