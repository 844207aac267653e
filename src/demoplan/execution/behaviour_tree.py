"""A planned task as a BehaviorTree.CPP v4 tree, and that tree run in a demoplan world
(docs/execution.md "Behaviour trees"; docs/formats.md "Behaviour tree").

:func:`task_tree` turns the chosen plan of :func:`~demoplan.scenes.plan.plan_in_scene`
into a tree that a robot's runtime loads and ticks: for each subgoal, in the
plan's order (which honours the learned constraints, paper §IV.B), a
``Fallback`` whose first child checks the object is already at its target
(``IsAt``) and whose second carries it there (``MoveToFree`` for the objects the
plan parks on the way, then ``Grasp`` and ``PutDown``); each subgoal is retried
a bounded number of times, then fails the tree with the reason on the
blackboard (``failure``: the executor's failure kinds, ``failure_detail``,
``failed_subgoal``). A last ``Sequence`` checks every goal object, putting back
one that a person moved.

The four actions of the vocabulary are ``SubTree`` models with ports: each
holds one leaf (``GraspAction``, ``PutDownAction``, ``IsAtCondition``,
``MoveToFreeAction``) that reads its subtree's blackboard, where the engine puts
the port values. A leaf with ports of its own would be the more usual C++
form, but the engine's Python bindings (behaviortreepy) register leaves
without ports, and the same file must load in both.

:func:`run_behaviour_tree` loads such a file in the engine (behaviortreepy,
the ``bt`` extra) and binds the leaves to a world's ``grasp``, ``put_down`` and
``observe`` (:class:`~demoplan.execution.world.World`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any
from xml.etree.ElementTree import Element, SubElement, indent, tostring

from defusedxml.ElementTree import fromstring

from demoplan.errors import InputError, LimitReachedError, UsageError
from demoplan.execution.executor import MISPLACED_WITHIN, ExecutionSettings
from demoplan.execution.faults import InjectedFault
from demoplan.execution.report import FailureKind
from demoplan.execution.tree_checks import check_tree
from demoplan.execution.world import Observation, World
from demoplan.model import Pose, TaskModel
from demoplan.planning.problem import Action
from demoplan.planning.strips import Rules
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.geometry import bounding_radius, yaw_difference
from demoplan.scenes.plan import ChosenPlan, ScenePlan
from demoplan.scenes.problems import SceneProblem

__all__ = [
    "ATTEMPTS",
    "MAX_TICKS",
    "NODES",
    "NodeModel",
    "Port",
    "TreeRun",
    "run_behaviour_tree",
    "task_tree",
    "tree_targets",
]

MAX_TICKS = 100_000
"""A tree run stops (exit 4) after this many ticks: a ``KeepRunningUntilFailure``
around a leaf that never fails would otherwise run until killed."""

ATTEMPTS = 3
"""Each subgoal is tried at most this often (``RetryUntilSuccessful``), as the
executor tries a failed grasp (:data:`~demoplan.execution.executor.MAX_SAME_GRASP`)."""


@dataclass(frozen=True, slots=True)
class Port:
    """A port of a node of the vocabulary: its name, direction, type and meaning."""

    name: str
    kind: str  # input_port or output_port
    type: str
    description: str


@dataclass(frozen=True, slots=True)
class NodeModel:
    """A node of the vocabulary: the ``SubTree`` ID, the leaf inside it and its ports."""

    id: str
    leaf: str
    leaf_kind: str  # Action or Condition
    description: str
    ports: tuple[Port, ...]


_FAILURE_PORTS = (
    Port("failure", "output_port", "std::string", "the failure kind when the node fails"),
    Port("failure_detail", "output_port", "std::string", "a sentence saying what was seen"),
)
_POSE_PORTS = (
    Port("x", "input_port", "double", "target position, world frame (m)"),
    Port("y", "input_port", "double", "target position, world frame (m)"),
    Port("z", "input_port", "double", "target position, world frame (m): the object's bottom"),
    Port("yaw", "input_port", "double", "target yaw about the world's z axis (deg)"),
)
_REFERENCE_PORTS = (
    Port(
        "reference",
        "input_port",
        "std::string",
        "what the target is relative to: an object or landmark, 'world', or 'anywhere'",
    ),
    Port("offset_x", "input_port", "double", "target position minus the reference's (m)"),
    Port("offset_y", "input_port", "double", "target position minus the reference's (m)"),
    Port("offset_z", "input_port", "double", "target position minus the reference's (m)"),
    Port(
        "offset_frame",
        "input_port",
        "std::string",
        "'world': the offset is in world axes; 'reference': in the reference's frame",
    ),
)
_CHECK_PORTS = (
    Port("tolerance", "input_port", "double", "m: farther from the target is not at it"),
    Port("yaw_tolerance", "input_port", "double", "deg: turned farther is not at it"),
    Port("check_yaw", "input_port", "bool", "the target's orientation was learned"),
)
_OBJECT = Port("object", "input_port", "std::string", "the scene object's name")
_AXIS = Port("axis", "input_port", "double", "finger axis in the object's frame (deg)")
_SUBGOAL = Port("subgoal", "input_port", "std::string", "the subgoal's id (a state's visit)")

NODES = (
    NodeModel(
        "IsAt",
        "IsAtCondition",
        "Condition",
        "SUCCESS when the object stands at the target within the tolerances",
        (_OBJECT, _SUBGOAL, *_POSE_PORTS, *_REFERENCE_PORTS, *_CHECK_PORTS, *_FAILURE_PORTS),
    ),
    NodeModel(
        "Grasp",
        "GraspAction",
        "Action",
        "close the hand on the object and lift it; SUCCESS when it is in the hand",
        (_OBJECT, _AXIS, *_FAILURE_PORTS),
    ),
    NodeModel(
        "PutDown",
        "PutDownAction",
        "Action",
        "carry the held object to the target and release it; SUCCESS when it stands there",
        (_OBJECT, _SUBGOAL, *_POSE_PORTS, *_REFERENCE_PORTS, *_CHECK_PORTS, *_FAILURE_PORTS),
    ),
    NodeModel(
        "MoveToFree",
        "MoveToFreeAction",
        "Action",
        "grasp an object that is in the way and put it down at a free spot (a parking move)",
        (
            _OBJECT,
            _AXIS,
            *_POSE_PORTS,
            _CHECK_PORTS[0],
            *_FAILURE_PORTS,
        ),
    ),
)


# -- export ------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Move:
    """A GRASP and the PUT_DOWN after it; ``subgoal``: the subgoal it reaches (None: parking)."""

    grasp: Action
    put_down: Action
    subgoal: str | None


def task_tree(
    scene_plan: ScenePlan,
    *,
    settings: ExecutionSettings = ExecutionSettings(),
    plan_only: bool = False,
    attempts: int = ATTEMPTS,
) -> str:
    """The chosen plan of ``scene_plan`` as a BehaviorTree.CPP v4 XML document
    (module docstring); ``plan_only``: the flat ``Sequence`` of its actions."""
    chosen = scene_plan.chosen
    problem = chosen.problem
    moves = _moves(problem, chosen.plan.actions)
    references = _references(scene_plan.model, chosen)

    root = Element("root", BTCPP_format="4", main_tree_to_execute="Task")
    task = SubElement(root, "BehaviorTree", ID="Task")
    label = (
        "goal of "
        + scene_plan.model.demonstration_label(chosen.goal)
        + (f" ({chosen.binding.describe()})" if not chosen.binding.identity else "")
    )
    body = SubElement(task, "Sequence", name=label)
    if plan_only:
        for move in moves:
            SubElement(body, "SubTree", _grasp_ports(problem, move.grasp))
            SubElement(
                body, "SubTree", _put_ports(problem, move, references, settings, id="PutDown")
            )
    else:
        pending: list[_Move] = []
        for move in moves:
            pending.append(move)
            if move.subgoal is not None:
                _subgoal_node(body, problem, pending, references, settings, attempts)
                pending = []
        for move in pending:  # parking after the last subgoal (none in practice)
            SubElement(
                body, "SubTree", _put_ports(problem, move, references, settings, "MoveToFree")
            )
        _goal_check(body, problem, moves, references, settings, attempts)
    for node in NODES:
        tree = SubElement(root, "BehaviorTree", ID=node.id)
        SubElement(tree, node.leaf)
    models = SubElement(root, "TreeNodesModel")
    for node in NODES:
        SubElement(models, node.leaf_kind, ID=node.leaf)
    for node in NODES:
        declared = SubElement(models, "SubTree", ID=node.id)
        for port in node.ports:
            SubElement(declared, port.kind, name=port.name, type=port.type).text = port.description
    indent(root)
    return tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def _moves(problem: SceneProblem, actions: Sequence[Action]) -> list[_Move]:
    rules = Rules(problem.problem)
    reached = frozenset(rules.start().reached)
    moves = []
    for grasp, put_down in zip(actions[::2], actions[1::2], strict=True):
        after = rules.reached_by_put_down(put_down.object, put_down.location, reached)
        new = sorted(after - reached)
        moves.append(_Move(grasp, put_down, new[0] if new else None))
        reached = after
    return moves


def _subgoal_node(
    body: Element,
    problem: SceneProblem,
    moves: Sequence[_Move],
    references: dict[str, tuple[str, tuple[float, float, float], str]],
    settings: ExecutionSettings,
    attempts: int,
) -> None:
    last = moves[-1]
    assert last.subgoal is not None
    outer = SubElement(body, "Fallback", name=f"subgoal {last.subgoal}: {last.put_down.object}")
    retry = SubElement(outer, "RetryUntilSuccessful", num_attempts=str(attempts))
    inner = SubElement(retry, "Fallback")
    SubElement(inner, "SubTree", _put_ports(problem, last, references, settings, "IsAt"))
    steps = SubElement(inner, "Sequence")
    for move in moves[:-1]:
        # parked by an earlier attempt and still there: not again
        parking = SubElement(steps, "Fallback", name=f"{move.put_down.object} parked")
        SubElement(parking, "SubTree", _put_ports(problem, move, references, settings, "IsAt"))
        SubElement(
            parking, "SubTree", _put_ports(problem, move, references, settings, "MoveToFree")
        )
    SubElement(steps, "SubTree", _grasp_ports(problem, last.grasp))
    SubElement(steps, "SubTree", _put_ports(problem, last, references, settings, "PutDown"))
    gave_up = SubElement(outer, "Sequence", name="give up")
    SubElement(gave_up, "Script", code=f"failed_subgoal:='{last.subgoal}'")
    SubElement(gave_up, "AlwaysFailure")


def _goal_check(
    body: Element,
    problem: SceneProblem,
    moves: Sequence[_Move],
    references: dict[str, tuple[str, tuple[float, float, float], str]],
    settings: ExecutionSettings,
    attempts: int,
) -> None:
    """Every goal object at its final target, in the order the plan last moved
    them (what stands on another comes after it); one that a person moved is
    put back."""
    goal = dict(problem.problem.goal)
    last: dict[str, _Move] = {}
    for move in moves:
        if move.subgoal is not None and goal.get(move.put_down.object) == move.put_down.location:
            last.pop(move.put_down.object, None)
            last[move.put_down.object] = move
    check = SubElement(body, "Sequence", name="the goal holds")
    for obj, move in last.items():
        outer = SubElement(check, "Fallback", name=f"{obj} stays at its target")
        retry = SubElement(outer, "RetryUntilSuccessful", num_attempts=str(attempts))
        inner = SubElement(retry, "Fallback")
        SubElement(inner, "SubTree", _put_ports(problem, move, references, settings, "IsAt"))
        again = SubElement(inner, "Sequence", name=f"put {obj} back")
        SubElement(again, "SubTree", _grasp_ports(problem, move.grasp))
        SubElement(again, "SubTree", _put_ports(problem, move, references, settings, "PutDown"))
        gave_up = SubElement(outer, "Sequence", name="give up")
        SubElement(gave_up, "Script", code=f"failed_subgoal:='{move.subgoal}'")
        SubElement(gave_up, "AlwaysFailure")


def _number(value: float) -> str:
    return f"{value:.6f}".rstrip("0").rstrip(".") if value == value else "nan"


def _grasp_ports(problem: SceneProblem, action: Action) -> dict[str, str]:
    grasp = next(g for g in problem.grasps if g.name == action.grasp)
    return {
        "ID": "Grasp",
        "name": f"grasp {action.object}",
        "object": action.object,
        "axis": _number(grasp.axis),
        "failure": "{failure}",
        "failure_detail": "{failure_detail}",
    }


def _put_ports(
    problem: SceneProblem,
    move: _Move,
    references: dict[str, tuple[str, tuple[float, float, float], str]],
    settings: ExecutionSettings,
    id: str,
) -> dict[str, str]:
    action = move.put_down
    location = problem.location(action.location)
    x, y, z = location.position
    ports = {"ID": id}
    if id == "MoveToFree":
        grasp = next(g for g in problem.grasps if g.name == move.grasp.grasp)
        ports |= {
            "name": f"park {action.object}",
            "object": action.object,
            "axis": _number(grasp.axis),
        }
    else:
        verb = "is" if id == "IsAt" else "put"
        ports |= {
            "name": f"{action.object} at {move.subgoal or 'its parking spot'}"
            if id == "IsAt"
            else f"{verb} {action.object}",
            "object": action.object,
            "subgoal": move.subgoal or "",
        }
    ports |= {"x": _number(x), "y": _number(y), "z": _number(z), "yaw": _number(location.yaw)}
    if id != "MoveToFree":
        reference, offset, frame = references.get(move.subgoal or "", ("world", (x, y, z), "world"))
        oriented = _oriented(problem, move.subgoal)
        ports |= {
            "reference": reference,
            "offset_x": _number(offset[0]),
            "offset_y": _number(offset[1]),
            "offset_z": _number(offset[2]),
            "offset_frame": frame,
            "yaw_tolerance": _number(settings.yaw_tolerance),
            "check_yaw": "true" if oriented else "false",
        }
    ports["tolerance"] = _number(settings.position_tolerance)
    ports |= {"failure": "{failure}", "failure_detail": "{failure_detail}"}
    return ports


def _oriented(problem: SceneProblem, subgoal: str | None) -> bool:
    return any(s.label == subgoal and not s.turnable for s in problem.candidate.subtasks)


def _references(
    model: TaskModel, chosen: ChosenPlan
) -> dict[str, tuple[str, tuple[float, float, float], str]]:
    """Subgoal → (reference, offset, offset frame): what its target is relative
    to, named as the scene names it (roles bound to instances)."""
    renaming = chosen.binding.renaming
    found = {}
    for subtask in chosen.problem.candidate.subtasks:
        try:
            state = model.state(subtask.state)
        except KeyError:
            continue
        position = state.position
        if position.anywhere:
            reference = "anywhere"
        elif position.reference is None:
            reference = "world"
        else:
            reference = renaming.get(position.reference, position.reference)
        offset = tuple(float(v) for v in position.value)
        frame = "reference" if position.in_reference_frame else "world"
        found[subtask.label] = (reference, (offset[0], offset[1], offset[2]), frame)
    return found


# -- reading back: the tree in a world ----------------------------------------------------


@dataclass(frozen=True, slots=True)
class TreeRun:
    """What ticking a tree in a world did: the root's status, the blackboard's
    failure entries, the world's actions and injected faults, the last observation."""

    success: bool
    failure: str
    failure_detail: str
    failed_subgoal: str
    actions: int
    injected: tuple[InjectedFault, ...]
    final: Observation
    ticks: int = 1

    def to_json(self) -> dict[str, Any]:
        return {
            "success": self.success,
            "failure": self.failure,
            "failure_detail": self.failure_detail,
            "failed_subgoal": self.failed_subgoal,
            "actions": self.actions,
            "injected": [fault.to_json() for fault in self.injected],
        }


@dataclass
class _Binding:
    """The leaves' callbacks on a world (module docstring)."""

    world: World
    known: set[str]
    upcoming: list[tuple[str, Pose]]
    picked_from: Pose | None = None
    actions: int = 0
    max_actions: int = ExecutionSettings().max_actions
    errors: list[BaseException] = field(default_factory=list)

    # -- helpers

    def fail(self, blackboard: Any, kind: FailureKind | str, detail: str) -> bool:
        blackboard.set_string("failure", str(kind))
        blackboard.set_string("failure_detail", detail)
        return False

    def after_action(self) -> None:
        self.actions += 1
        if self.actions >= self.max_actions:
            raise LimitReachedError(
                f"the tree gave up after {self.max_actions} actions (a run's limit; "
                "a tree that keeps moving objects is not run further)"
            )
        self.world.between_actions([pose for _, pose in self.upcoming])

    def at_target(self, blackboard: Any, obj: str, observation: Observation) -> str | None:
        """Why ``obj`` is not at the target on ``blackboard`` (None: it is), and
        the failure kind to report."""
        target = _target(blackboard)
        pose = observation.poses.get(obj)
        if pose is None:
            return "in the hand" if observation.held == obj else "nowhere to be seen"
        error = math.dist(pose.position, target.position)
        if error > float(blackboard.get_string("tolerance")):
            where = ", ".join(f"{v:.3f}" for v in pose.position)
            return f"at ({where}), {100 * error:.1f} cm from its target"
        if _flag(blackboard, "check_yaw") and obj in observation.geometry:
            turn = yaw_difference(observation.geometry[obj], pose.yaw, target.yaw)
            if turn > float(blackboard.get_string("yaw_tolerance")):
                return f"turned {turn:.1f}° from its target"
        return None

    def blocker(self, obj: str, target: Pose, observation: Observation) -> str | None:
        """An object the tree never saw standing where ``obj`` is to go."""
        shape = observation.geometry.get(obj)
        for other, pose in observation.poses.items():
            if other in self.known or other == obj or shape is None:
                continue
            reach = bounding_radius(shape) + bounding_radius(observation.geometry[other])
            if math.dist(pose.position[:2], target.position[:2]) < reach:
                return other
        return None

    # -- the leaves

    def is_at(self, node: Any) -> bool:
        blackboard = node.config().blackboard
        obj = blackboard.get_string("object")
        why = self.at_target(blackboard, obj, self.world.observe())
        if why is None:
            return True
        return self.fail(blackboard, FailureKind.MOVED, f"{obj} is {why}")

    def grasp(self, node: Any) -> bool:
        blackboard = node.config().blackboard
        obj = blackboard.get_string("object")
        before = self.world.observe()
        if before.held is not None:
            return self.fail(blackboard, FailureKind.RELEASE, f"{before.held} is in the hand")
        self.picked_from = before.poses.get(obj)
        self.world.grasp(obj, float(blackboard.get_string("axis")), self.picked_from)
        if self.world.observe().held != obj:
            self.after_action()
            return self.fail(blackboard, FailureKind.GRASP, f"{obj} is not in the hand")
        self.actions += 1  # nothing happens between a grasp and its put-down
        return True

    def put_down(self, node: Any) -> bool:
        blackboard = node.config().blackboard
        obj = blackboard.get_string("object")
        target = _target(blackboard)
        observation = self.world.observe()
        if observation.held != obj:
            return self.fail(blackboard, FailureKind.RELEASE, f"{obj} is not in the hand")
        blocker = self.blocker(obj, target, observation)
        if blocker is not None:
            self.put_back(obj)
            return self.fail(
                blackboard, FailureKind.NEW_OBJECT, f"{blocker} appeared on {obj}'s target"
            )
        self.world.put_down(obj, target)
        self.done(obj, target)
        observation = self.world.observe()
        why = self.at_target(blackboard, obj, observation)
        self.after_action()
        if why is None:
            return True
        pose = observation.poses.get(obj)
        error = math.inf if pose is None else math.dist(pose.position, target.position)
        if observation.held is not None:
            kind = FailureKind.RELEASE
        elif error < MISPLACED_WITHIN:
            kind = FailureKind.MISPLACED
        else:
            kind = FailureKind.DROPPED
        return self.fail(blackboard, kind, f"{obj} is {why}")

    def move_to_free(self, node: Any) -> bool:
        return self.grasp(node) and self.put_down(node)

    def put_back(self, obj: str) -> None:
        """Put the held object down where it was taken (plans start with an empty hand)."""
        if self.picked_from is not None:
            self.world.put_down(obj, self.picked_from)

    def done(self, obj: str, target: Pose) -> None:
        for k, (other, pose) in enumerate(self.upcoming):
            if other == obj and math.dist(pose.position, target.position) < 1e-6:
                del self.upcoming[k]
                return

    def guarded(self, leaf: Callable[[Any], bool]) -> Callable[[Any], Any]:
        """``leaf`` as an engine callback: its verdict as a NodeStatus; an exception
        kept for :func:`run_behaviour_tree` to raise (the engine would swallow it)."""
        import behaviortreepy as bt

        def callback(node: Any) -> Any:
            if self.errors:  # the rest of the tick ends at once
                return bt.NodeStatus.FAILURE
            try:
                ok = leaf(node)
            except BaseException as exc:  # Ctrl-C too: re-raised after the tick
                self.errors.append(exc)
                ok = False
            return bt.NodeStatus.SUCCESS if ok else bt.NodeStatus.FAILURE

        return callback


def _flag(blackboard: Any, key: str) -> bool:
    """A bool port's value; False where the node has no such port (MoveToFree)."""
    if key not in blackboard.get_keys():
        return False
    return str(blackboard.get_string(key)).strip().lower() in ("true", "1")


def _target(blackboard: Any) -> Pose:
    x, y, z, yaw = (float(blackboard.get_string(k)) for k in ("x", "y", "z", "yaw"))
    return Pose((x, y, z), quat_from_yaw(yaw))


def tree_targets(xml: str, source: str = "tree") -> list[tuple[str, Pose]]:
    """The targets of the tree's PutDown and MoveToFree nodes, in document order
    (an InputError naming ``source`` where ``xml`` is not a tree the engine may
    be given: :func:`~demoplan.execution.tree_checks.check_tree`)."""
    check_tree(xml, source)
    root = fromstring(xml)
    found = []
    for node in _subtrees(root):
        kind, obj = node.get("ID"), node.get("object")
        if obj is None or kind not in NUMBER_PORTS:
            continue  # a TreeNodesModel entry, or a node of no port we read
        numbers = {port: _port_number(node, port, source) for port in NUMBER_PORTS[kind]}
        if kind in ("PutDown", "MoveToFree"):
            position = (numbers["x"], numbers["y"], numbers["z"])
            found.append((obj, Pose(position, quat_from_yaw(numbers["yaw"]))))
    return found


NUMBER_PORTS = {
    "IsAt": ("x", "y", "z", "yaw", "tolerance"),
    "PutDown": ("x", "y", "z", "yaw", "tolerance"),
    "MoveToFree": ("x", "y", "z", "yaw", "tolerance", "axis"),
    "Grasp": ("axis",),
}
"""The ports the leaves read as numbers, checked before the first tick."""


def _port_number(node: Any, port: str, source: str) -> float:
    text = node.get(port)
    try:
        value = float(text) if text is not None else math.nan
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise InputError(
            f"{node.get('ID')} {node.get('object')}: {port}={text!r}: a finite number expected",
            source=source,
        )
    return value


def _subtrees(root: Any) -> Iterator[Any]:
    yield from root.iter("SubTree")


def _check_graspable(xml: str, world: World, source: str) -> None:
    """Before the first motion, as the executor checks a plan: an InputError
    naming the objects the tree grasps that the world does not have, or that
    its gripper cannot take (a world that can tell: ``why_not_graspable``)."""
    grasped = dict.fromkeys(
        node.get("object")
        for node in _subtrees(fromstring(xml))
        if node.get("ID") in ("Grasp", "MoveToFree") and node.get("object") is not None
    )
    standing = world.observe().poses
    unknown = [repr(obj) for obj in grasped if obj not in standing]
    if unknown:
        raise InputError(
            f"grasps {', '.join(unknown)}, which the scene does not have", source=source
        )
    graspable = getattr(world, "why_not_graspable", None)
    if graspable is None:
        return
    reasons = [f"{obj} {why}" for obj in grasped if (why := graspable(obj))]
    if reasons:
        raise InputError(
            "cannot be carried out by this robot: " + "; ".join(reasons),
            source=source,
            field="objects",
        )


def run_behaviour_tree(
    xml: str, world: World, source: str = "tree", *, max_ticks: int = MAX_TICKS
) -> TreeRun:
    """Load ``xml`` in BehaviorTree.CPP (behaviortreepy), bind its leaves to
    ``world`` and tick it until it stops (module docstring), at most
    ``max_ticks`` times (then LimitReachedError, exit 4). A tree the engine
    does not load is an InputError naming ``source`` and the engine's reason."""
    try:
        import behaviortreepy as bt
    except ImportError as exc:  # pragma: no cover - the bt extra is in dev
        raise UsageError(
            "running a behaviour tree needs behaviortreepy: pip install 'demoplan[bt]'"
        ) from exc
    targets = tree_targets(xml, source)
    _check_graspable(xml, world, source)
    binding = _Binding(world, set(world.observe().poses), targets)
    factory = bt.BehaviorTreeFactory()
    factory.register_simple_condition("IsAtCondition", binding.guarded(binding.is_at))
    factory.register_simple_action("GraspAction", binding.guarded(binding.grasp))
    factory.register_simple_action("PutDownAction", binding.guarded(binding.put_down))
    factory.register_simple_action("MoveToFreeAction", binding.guarded(binding.move_to_free))
    try:
        tree = factory.create_tree_from_text(xml)
    except RuntimeError as exc:
        raise InputError(f"the engine does not load the tree: {exc}", source=source) from None
    ticks = 1
    status = tree.tick_once()
    while status == bt.NodeStatus.RUNNING and not binding.errors:
        if ticks >= max_ticks:
            raise LimitReachedError(
                f"{source}: the tree still runs after {max_ticks:,} ticks "
                f"({binding.actions} actions); a tree that never ends is not run further"
            )
        ticks += 1
        status = tree.tick_once()
    if binding.errors:
        raise binding.errors[0]
    blackboard = tree.root_blackboard()
    keys = set(blackboard.get_keys())

    def entry(key: str) -> str:
        return str(blackboard.get_string(key)) if key in keys else ""

    success = status == bt.NodeStatus.SUCCESS
    return TreeRun(
        success=success,
        failure="" if success else entry("failure"),
        failure_detail="" if success else entry("failure_detail"),
        failed_subgoal="" if success else entry("failed_subgoal"),
        actions=binding.actions,
        injected=tuple(getattr(world, "injected", ())),
        final=world.observe(),
        ticks=ticks,
    )
