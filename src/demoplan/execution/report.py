"""A run's report: what the executor did and saw (docs/formats.md "Run report").

The values :func:`demoplan.execution.executor.execute` returns and tells as it
goes — the failures it saw (:class:`FailureKind`, :class:`Failure`), the
actions it executed, the events of a live display (:class:`RunEvent`) and the
report (:class:`RunReport`) — frozen, and built by nothing but the executor.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import Any, Literal

from demoplan.execution.faults import InjectedFault
from demoplan.execution.world import Observation
from demoplan.model import Pose
from demoplan.planning.problem import Action
from demoplan.scenes.scene import Scene, SceneObject, scene_to_dict

__all__ = [
    "ExecutedAction",
    "Failure",
    "FailureKind",
    "RunEvent",
    "RunReport",
    "RunStatus",
    "observed_scene",
]


class FailureKind(StrEnum):
    """What the executor saw differ from what an action should have done."""

    GRASP = "grasp"  # after GRASP the object is not in the hand
    RELEASE = "release"  # after PUT_DOWN something is still in the hand
    DROPPED = "dropped"  # the object is nowhere, or more than 6 cm from its target
    MISPLACED = "misplaced"  # within 6 cm of its target but not within 1 cm / 5°
    MOVED = "moved"  # another object is not where it stood
    NEW_OBJECT = "new_object"  # an object that was not there appeared
    GOAL = "goal"  # no action left, but the goal does not hold


@dataclass(frozen=True, slots=True)
class Failure:
    """A difference between what an action should have done and what was observed."""

    step: int
    kind: FailureKind
    detail: str
    note: str = ""
    """What the robot itself noticed going wrong in the action (``--sim arm``:
    a motion it refused, a grasp it felt slip); also at the end of ``detail``."""


@dataclass(frozen=True, slots=True)
class ExecutedAction:
    step: int
    action: Action
    pose: Pose
    plan: int
    ok: bool


RunStatus = Literal["succeeded", "failed"]
"""How a run ended: the goal reached, or not."""


@dataclass(frozen=True, slots=True)
class RunEvent:
    """Progress for a live display: ``kind`` is plan, action, failure, replan or
    done; a plan or replan carries its ``targets`` (goal object, target pose).
    The ``done`` event carries the run's ``status`` (``succeeded`` or
    ``failed``) and its reason as ``text``; a failed run's text starts with
    ``FAILED:``, so that no display can show it as a success."""

    kind: str
    text: str
    step: int = 0
    replans: int = 0
    remaining: int = 0
    targets: tuple[tuple[str, Pose], ...] = ()
    status: RunStatus | None = None
    observation: Observation | None = None
    """The world as the executor had last observed it when it told the event:
    at a plan the start, at an action the world as the action begins, at a
    failure the world the failed action left (a dropped object where it fell),
    at a replan the world planned from, at the end the final one. Filled in by
    :func:`execute`; nothing is observed for it."""


@dataclass(frozen=True, slots=True, kw_only=True)
class RunReport:
    """What happened (docs/formats.md "Run report"); built with keywords, never changed."""

    success: bool
    replans: int
    goal: int | None
    actions: tuple[ExecutedAction, ...]
    failures: tuple[Failure, ...]
    final: Observation
    scene: Scene
    reason: str = ""
    first_plan_length: int = 0
    pose_errors: dict[str, float] = field(default_factory=dict)
    """Each goal object's distance (m) from its target at the end."""
    turn_errors: dict[str, float] = field(default_factory=dict)
    """Each goal object's turn (deg) from its target's yaw at the end, given its
    symmetry — only where the target's orientation was learned (it matters there)."""
    reached: tuple[str, ...] = ()
    seconds: float = 0.0
    world: str = ""
    frames: tuple[str, ...] = ()
    gave_up: bool = False
    """True when a limit (replans, actions) stopped the run, not a missing plan."""
    injected: tuple[InjectedFault, ...] = ()
    """The faults a simulated world injected, as they happened (a real world has none)."""
    collisions: tuple[str, ...] = ()
    """Contacts of the robot with anything but its load, as they happened (``--sim arm``)."""
    motions_refused: tuple[str, ...] = ()
    """Motions the robot did not make because a check found them impossible (``--sim arm``)."""
    simulated_seconds: float | None = None
    """Seconds the physics simulated (``--sim mujoco``, ``arm``); None: no physics."""

    @property
    def exit_code(self) -> int:
        """docs/cli.md: 0 success, 3 no plan from the observed world, 4 a limit reached."""
        return 0 if self.success else 4 if self.gave_up else 3

    @property
    def status(self) -> RunStatus:
        """``succeeded`` where the goal was reached, else ``failed``."""
        return "succeeded" if self.success else "failed"

    def to_json(self) -> dict[str, Any]:
        final_scene = observed_scene(self.final, self.scene)
        return {
            "success": self.success,
            "status": self.status,
            "exit_code": self.exit_code,
            "replans": self.replans,
            "actions": [
                [e.action.kind, e.action.object, e.action.location, e.action.grasp]
                for e in self.actions
            ],
            "failures": [
                {"step": f.step, "kind": f.kind, "detail": f.detail} for f in self.failures
            ],
            "injected": [fault.to_json() for fault in self.injected],
            "collisions": list(self.collisions),
            "motions_refused": list(self.motions_refused),
            "final_scene": scene_to_dict(final_scene),
            "goal": self.goal,
            "reason": self.reason,
            "world": self.world,
            "first_plan_actions": self.first_plan_length,
            "extra_actions": max(0, len(self.actions) - self.first_plan_length),
            "reached": list(self.reached),
            "pose_errors": {k: round(v, 6) for k, v in self.pose_errors.items()},
            "turn_errors_deg": {k: round(v, 3) for k, v in self.turn_errors.items()},
            "steps": [
                {
                    "step": e.step,
                    "action": [e.action.kind, e.action.object, e.action.location, e.action.grasp],
                    "position": [round(v, 6) for v in e.pose.position],
                    "yaw": round(e.pose.yaw, 3),
                    "plan": e.plan,
                    "ok": e.ok,
                }
                for e in self.actions
            ],
            "seconds": round(self.seconds, 3),
            "frames": list(self.frames),
        }


def observed_scene(observation: Observation, template: Scene) -> Scene:
    """The observed world as a scene (grasps, types, gripper and landmarks from
    the prepared scene; an object's geometry from it where the world gives none)."""
    known = {obj.name: obj for obj in template.objects}
    objects = tuple(
        replace(
            known[name], pose=pose, geometry=observation.geometry.get(name) or known[name].geometry
        )
        if name in known
        else SceneObject(name, pose, observation.geometry.get(name))
        for name, pose in observation.poses.items()
    )
    return replace(template, objects=objects)
