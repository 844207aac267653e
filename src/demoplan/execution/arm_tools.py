"""How the arm's tool is chosen (:mod:`demoplan.execution.arm`): the suction
cup where it carries an object, else the fingers, else neither, with why —
each tool tried in a trial carry in the simulation itself, on the object
:data:`TRIAL_MARGIN` times as heavy.

The trial needs an arm world to carry in; the world is given as a parameter
(anything making a :class:`TrialArm` from a scene), so this module does not
import the world that uses it (:class:`~demoplan.execution.arm.ArmWorld`,
whose :func:`~demoplan.execution.arm.choose_tool` passes itself)."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Literal, Protocol

from demoplan.execution.arm_model import GRIP_FORCE, JAW_STROKE, PAD_HALF, SUCTION_FORCE
from demoplan.execution.world import Observation
from demoplan.model import ObjectGeometry, Pose
from demoplan.scenes.geometry import half_extent
from demoplan.scenes.scene import Scene, SceneObject

__all__ = [
    "TRIAL_MARGIN",
    "TRIAL_PICK",
    "TRIAL_PLACE",
    "Tool",
    "ToolChoice",
    "TrialArm",
    "TrialCarry",
    "carry_in_trial",
    "tool_by_trial",
]

Tool = Literal["suction", "fingers"]

TRIAL_PICK = Pose((0.42, -0.14, 0.0))
TRIAL_PLACE = Pose((0.42, 0.14, 0.0), (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)))
"""Where the trial carry (:func:`tool_by_trial`) takes an object from and puts it,
the arm's base at the origin facing +x: 28 cm across its front, turned by 90°."""
TRIAL_MARGIN = 1.25
"""The trial carries the object this many times as heavy: an object the check
accepts must be carried by every motion of a run, and near the cup's limit
the trial's are not the hardest. Measured (5 N cup, 4 cm block and 15 × 10 ×
3 cm box alike): the trial carry holds up to 0.44 kg, carries between other
places 30–50 cm out as much, but the half turn behind the base before a top
camera's picture (:meth:`~demoplan.execution.arm.ArmWorld.park`) only 0.35 kg (a 20 cm tall box
0.32 kg): the margin covers that."""
TRIAL_LIGHT: dict[Tool, float] = {"suction": 0.01, "fingers": 0.05}
"""kg: the weight of a second trial carry when the first fails, per tool.
Carried this light, the object's weight is why the tool loses it; not even
this light, something else is, and the refusal says what the tool felt
instead. The fingers' is the lightest they are measured to lift (an 8 × 9.5 cm
cylinder of 5 g is not lifted, of 50 g it is: docs/execution.md): at 10 g a
7 kg cup was said to have slipped from them "even at 10 g", not to be too
heavy."""
MIN_JAW_CLEARANCE = 0.002  # m: the least room the open jaws leave on either side
FINGERTIP_GAP = 0.003  # m: the fingertips stop this far above what the object stands on
TOOL_NAMES = {"suction": "suction cup", "fingers": "fingers"}
GRAVITY = 9.81  # m/s²: MuJoCo's default, the scenes' (a weight in newtons)


class TrialArm(Protocol):
    """What a trial carry needs of an arm world."""

    tools: dict[str, Tool]  # each object's tool
    motion_failures: list[str]  # motions not made, and why
    grasp_problems: list[str]  # grasps the tool felt fail, and how

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None: ...

    def put_down(self, obj: str, pose: Pose) -> None: ...

    def observe(self) -> Observation: ...

    def close(self) -> None: ...


@dataclass(frozen=True, slots=True)
class ToolChoice:
    """The tool that takes an object (None: neither), the finger axis (deg, in
    the object's frame) its trial used, and why it is refused."""

    tool: Tool | None
    axis: float
    why: str | None


@functools.cache
def tool_by_trial(
    shape: ObjectGeometry, axes: tuple[float, ...], arm: Callable[[Scene], TrialArm]
) -> ToolChoice:
    """The tool that carries an object of ``shape`` (its size and mass) whose
    scene allows finger ``axes``: the suction cup where it carries it, else the
    fingers, else neither, with why. Each is tried in the world ``arm`` makes —
    the arm, the tool, the servos and the motions of a run — on the object
    :data:`TRIAL_MARGIN` times as heavy, taken at :data:`TRIAL_PICK`, carried
    across the arm's front and turned by 90° to :data:`TRIAL_PLACE`; it is
    carried when it ends there within 1 cm. Before a trial, what rules a tool
    out by geometry alone: a sphere has no flat top for the cup, a top
    narrower than the pad none to seal on; the fingers need the object
    narrower than their stroke across one of ``axes`` (the trial takes the
    narrowest) and taller than the gap they leave over the table.
    The check is the physics itself, not a model of it (docs/execution.md)."""
    suction = _why_not_by_suction(shape, arm)
    fits = sorted(axes, key=lambda a: half_extent(shape, a))
    axis = fits[0] if fits else 0.0
    if suction is None:
        return ToolChoice("suction", axis, None)
    fingers = _why_not_by_fingers(shape, axis, suction.startswith("weighs"), arm)
    if fingers is None:
        return ToolChoice("fingers", axis, None)
    return ToolChoice(None, axis, f"{suction}; {fingers}")


def _why_not_by_suction(shape: ObjectGeometry, arm: Callable[[Scene], TrialArm]) -> str | None:
    if shape.shape == "sphere":
        return "is a sphere: it has no flat top for the suction cup to seal on"
    width = min(shape.size[0], shape.size[1])
    if width < 2 * PAD_HALF:
        return (
            f"has a top {1000 * width:.0f} mm across; the suction pad needs "
            f"{2000 * PAD_HALF:.0f} mm"
        )
    return _why_not_in_trial(
        shape, "suction", 0.0, f"the suction cup ({SUCTION_FORCE:g} N)", True, arm
    )


def _why_not_by_fingers(
    shape: ObjectGeometry, axis: float, weighed: bool, arm: Callable[[Scene], TrialArm]
) -> str | None:
    """Why the fingers do not carry ``shape`` taken across ``axis`` (``weighed``:
    the cup's reason already gave its weight)."""
    half = half_extent(shape, axis)
    if half + MIN_JAW_CLEARANCE > JAW_STROKE / 2:
        return (
            f"it is {200 * half:.1f} cm across its narrowest grasp; the fingers open to "
            f"{100 * JAW_STROKE:.1f} cm"
        )
    if shape.size[2] < FINGERTIP_GAP + 0.002:
        return (
            f"it is {1000 * shape.size[2]:.0f} mm tall; the fingertips stop "
            f"{1000 * FINGERTIP_GAP:.0f} mm above the table"
        )
    return _why_not_in_trial(
        shape, "fingers", axis, f"the fingers ({GRIP_FORCE:g} N)", not weighed, arm
    )


def _why_not_in_trial(
    shape: ObjectGeometry,
    tool: Tool,
    axis: float,
    named: str,
    weigh: bool,
    arm: Callable[[Scene], TrialArm],
) -> str | None:
    """Why ``tool`` loses ``shape`` :data:`TRIAL_MARGIN` times as heavy in the
    trial carry, or None. Its weight only when the same shape
    :data:`TRIAL_LIGHT` light is carried (``weigh``: the reason starts with
    the weight; else the cup's reason gave it), else what went wrong."""
    heavier = replace(shape, mass=TRIAL_MARGIN * shape.kg)
    trial = carry_in_trial(heavier, TRIAL_PICK, TRIAL_PLACE, tool, axis, arm)
    if trial.carried:
        return None
    if trial.refused:  # not the load: the arm could not make the motions
        return f"the {TOOL_NAMES[tool]} cannot carry it in a trial carry: {trial.refused[0]}"
    light = carry_in_trial(
        replace(shape, mass=TRIAL_LIGHT[tool]), TRIAL_PICK, TRIAL_PLACE, tool, axis, arm
    )
    if not light.carried:  # not its weight
        return (
            f"the {TOOL_NAMES[tool]} cannot carry it in a trial carry, even at "
            f"{1000 * TRIAL_LIGHT[tool]:g} g: {light.what_went_wrong()}"
        )
    what = (
        ("does not lift" if tool == "suction" else "do not lift")
        if not trial.lifted
        else ("lifts but loses" if tool == "suction" else "lift but lose")
    )
    if weigh:
        return (
            f"weighs {shape.kg:.3g} kg; {named} {what} {TRIAL_MARGIN:g} times that "
            f"({TRIAL_MARGIN * shape.kg * GRAVITY:.1f} N) in a trial carry in the simulation"
        )
    return f"{named} {what} it either"


@dataclass(frozen=True, slots=True)
class TrialCarry:
    """One carry (:func:`carry_in_trial`): whether the object was lifted, where it
    ended (m from its place; None: nowhere to be seen, or still held), the
    motions the arm refused and what the tool felt go wrong (the object named
    ``it``)."""

    lifted: bool
    miss: float | None
    refused: tuple[str, ...]
    felt: tuple[str, ...]

    @property
    def carried(self) -> bool:
        """Put down within 1 cm of its place."""
        return self.lifted and self.miss is not None and self.miss < 0.01

    def what_went_wrong(self) -> str:
        if self.felt:
            return self.felt[0]
        if not self.lifted:
            return "it was not lifted"
        if self.miss is None:
            return "it was not put down"
        return f"it ended {100 * self.miss:.1f} cm from its place"


def carry_in_trial(
    shape: ObjectGeometry,
    pick: Pose,
    place: Pose,
    tool: Tool | None,
    axis: float,
    arm: Callable[[Scene], TrialArm],
) -> TrialCarry:
    """The world ``arm`` makes, alone on a table with an object of ``shape``
    standing at ``pick`` (the base at the origin facing +x), takes it and puts it
    down at ``place``: whether it lifted it, how near its place it ended, and
    what went wrong on the way. ``tool``: the one it uses (None: its own
    choice); ``axis``: the fingers'."""
    name = "load"
    scene = Scene(objects=(SceneObject(name, pick, shape, (axis,)),), robot=(0.0, 0.0, 0.0))
    world = arm(scene)
    if tool is not None:
        world.tools[name] = tool
    try:
        world.grasp(name, axis, pick)
        lifted = world.observe().held == name
        if lifted:
            world.put_down(name, place)
        final = world.observe()
        pose = final.poses.get(name)
        miss = (
            math.dist(pose.position, place.position)
            if lifted and final.held is None and pose is not None
            else None
        )
        felt = tuple(problem.replace(name, "it") for problem in world.grasp_problems)
        return TrialCarry(lifted, miss, tuple(world.motion_failures), felt)
    finally:
        world.close()
