"""Plan, act, observe, replan (the paper's execution block).

The executor observes the world, plans every candidate goal and keeps the
chosen one (:func:`demoplan.scenes.plan.plan_in_scene`), then runs the plan
one action at a time. After each action it observes again and compares every
object with where it should be:

- after GRASP the object must be in the hand (else ``grasp``: the grasp failed);
- after PUT_DOWN it must stand at the target within ``position_tolerance``
  (else ``dropped`` — it fell elsewhere — or ``misplaced`` — it stands near,
  but off, its target);
- every other object must stand where it stood (else ``moved``: a person moved
  it, or an object was not where the plan needed it); an object that was not
  there before is ``new_object`` (it is planned around as clutter, moved away
  if it is in the way).

On a difference it replans the chosen goal from the observed world; subgoals
already reached stay reached (docs/execution.md: a subgoal counts once; the goal still
needs every object at its final place). Where the model has roles of identical
objects, the replan weighs every binding of roles to instances again: a plate
that was dropped may give its role to another plate when that is shorter
(subgoals then count as reached where the objects stand). It gives up after
``max_replans`` replans, when no plan exists, or after ``max_actions`` actions.
"""

from __future__ import annotations

import logging
import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from demoplan.budget import PLANNING_SECONDS, Clock
from demoplan.errors import DemoplanError, InputError
from demoplan.execution.report import (
    ExecutedAction,
    Failure,
    FailureKind,
    RunEvent,
    RunReport,
    observed_scene,
)
from demoplan.execution.turns import turn_errors, turned_beyond
from demoplan.execution.world import Observation, World
from demoplan.model import Pose, TaskModel
from demoplan.planning.problem import Action, Plan
from demoplan.planning.search import Budget
from demoplan.planning.strips import Rules
from demoplan.scenes.binding import Binding, bind_model
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.naming import StableNames
from demoplan.scenes.plan import (
    ChosenPlan,
    building_within,
    plan_in_scene,
    solve_candidate,
)
from demoplan.scenes.prepared import (
    BoundTask,
    PreparedScene,
    goal_floors,
    prepare,
    prepare_observed,
)
from demoplan.scenes.problems import SceneProblem, build_problem, pose_of
from demoplan.scenes.scene import Scene
from demoplan.scenes.table import surroundings_of
from demoplan.wording import plural

logger = logging.getLogger(__name__)

__all__ = [
    "ExecutionSettings",
    "Failure",
    "FailureKind",
    "RunEvent",
    "RunReport",
    "execute",
]


@dataclass(frozen=True, slots=True)
class ExecutionSettings:
    """When an observation differs from the expectation, and when to give up."""

    position_tolerance: float = 0.01
    """m: an object farther than this from where it should be has moved."""
    yaw_tolerance: float = 5.0
    """deg: at a target whose orientation was learned, an object turned farther than
    this (given its symmetry) is not in place."""
    max_replans: int = 25
    max_actions: int = 400
    budget: Budget = field(default_factory=lambda: Budget(timeout=PLANNING_SECONDS))
    """Per (re)planning, shared by the candidate goals (the anytime planner
    returns its best plan when it runs out; docs/cli.md)."""
    geometry: GeometrySettings = field(default_factory=GeometrySettings)


MAX_SAME_GRASP = 3
"""A grasp that failed is tried again identically (the same object, finger axis
and place) at most twice: after its third failure the replan takes another
grasp of the object, and the run stops, naming the object, when none is left.
A grasp whose motion the arm refused is not tried again at all: the arm's
check is deterministic, and the same motion would be refused again."""

MISPLACED_WITHIN = 0.06
"""m: an object off its target by less than this was misplaced; farther, dropped."""


def world_moved(observation: Observation, scene: Scene) -> bool:
    """Whether the observed world differs from ``scene`` (an object elsewhere,
    or not seen): then the first plan is made from the observation."""
    poses = observation.poses
    return set(poses) != set(scene.names) or any(
        _distance(poses[obj.name], obj.pose) > 1e-9 for obj in scene.objects
    )


def _distance(a: Pose, b: Pose) -> float:
    return math.dist(a.position, b.position)


def first_plan(
    model: TaskModel, prepared: PreparedScene, settings: ExecutionSettings
) -> ChosenPlan:
    """The plan a run starts with: every candidate goal planned in the
    ``prepared`` scene (objects the model never saw allowed where its caller
    prepared it so), the shortest chosen, within a clock of the settings' budget."""
    return plan_in_scene(
        model, prepared, clock=Clock(settings.budget), settings=settings.geometry
    ).chosen


def first_targets(chosen: ChosenPlan) -> tuple[tuple[str, Pose], ...]:
    """Where the put-downs of ``chosen`` put their objects (in plan order)."""
    problem = chosen.problem
    return tuple(
        (a.object, pose_of(problem.location(a.location)))
        for a in chosen.plan.actions
        if a.kind == "PUT_DOWN"
    )


class _Watched:
    """The run's world, keeping the executor's last observation (:attr:`last`)
    for its events (:attr:`RunEvent.observation`). Nothing is observed for
    them: a camera world's tracker or a physics world's check of the hand sees
    no extra look. Every other attribute is the world's own."""

    def __init__(self, world: World) -> None:
        self._world = world
        self.last: Observation | None = None

    def observe(self) -> Observation:
        self.last = self._world.observe()
        return self.last

    def __getattr__(self, name: str) -> Any:
        return getattr(self._world, name)


def execute(
    model: TaskModel,
    prepared: PreparedScene,
    world: World,
    settings: ExecutionSettings = ExecutionSettings(),
    on_event: Callable[[RunEvent], object] | None = None,
    first: ChosenPlan | None = None,
) -> RunReport:
    """Carry out the task in ``world`` (which starts as the ``prepared`` scene);
    see the module docstring. ``first``: the plan for the world as it starts, when the caller
    has made it already (it is not made again)."""
    heard = on_event or (lambda event: None)
    watched = _Watched(world)

    def emit(event: RunEvent) -> None:
        """Tell the caller, with the world last observed; and with --verbose, log
        the run's phases as they come."""
        logger.info("run: %s at step %d: %s", event.kind, event.step, event.text)
        heard(replace(event, observation=watched.last))

    run = _start_run(model, prepared, watched, settings, emit, first)
    while True:
        if not run.actions:
            report = run.check_the_end()
        elif len(run.executed) >= settings.max_actions:
            report = run.finish(
                False, f"gave up after {plural(settings.max_actions, 'action')}", gave_up=True
            )
        else:
            report = run.act(run.actions.pop(0))
        if report is not None:
            return report


def _start_run(
    model: TaskModel,
    prepared: PreparedScene,
    world: World,
    settings: ExecutionSettings,
    emit: Callable[[RunEvent], None],
    first: ChosenPlan | None,
) -> _Run:
    """A run's start: the world observed, the first plan (``first``, else made
    from the observed world where it differs from the prepared scene — then
    prepared too, objects the model never saw allowed), checked feasible and
    announced."""
    started = time.perf_counter()
    scene = prepared.scene
    observation = world.observe()
    if first is None and world_moved(observation, scene):
        observed = observed_scene(observation, scene)
        prepared = prepare(model, observed, clutter=True, settings=settings.geometry)
    chosen = first or first_plan(model, prepared, settings)
    goal = chosen.goal
    problem: SceneProblem = chosen.problem
    # Replans name the places and grasps of the first plan as it did.
    names = StableNames.of(
        ((loc.name, loc.position) for loc in problem.locations),
        ((g.name, g.object, g.axis) for g in problem.grasps),
        settings.geometry.merge_distance,
    )
    actions: list[Action] = list(chosen.plan.actions)
    _check_feasible(world, actions, problem, scene.source)
    run = _Run(
        model=bind_model(model, chosen.binding),
        roles=model,
        binding=chosen.binding,
        scene=scene,
        world=world,
        settings=settings,
        emit=emit,
        started=started,
        goal=goal,
        problem=problem,
        names=names,
        actions=actions,
        first_length=len(actions),
        reached=_reached_at_start(problem),
        expected=dict(observation.poses),
    )
    emit(
        RunEvent(
            "plan",
            f"goal of {model.demonstration_label(goal)}: {plural(len(actions), 'action')}",
            remaining=len(actions),
            targets=_targets(problem),
        )
    )
    return run


_Replan = tuple[SceneProblem, Plan, Binding, TaskModel]
"""A replan found: its problem, its plan, and the binding and model it is under."""


@dataclass(slots=True, kw_only=True)
class _Run:
    """A run in progress (:func:`execute`): the plan being carried out, what has
    been done and seen, and what is expected where."""

    model: TaskModel
    """The model bound to the instances the current plan moves."""
    roles: TaskModel
    """The model as learned (its roles unbound): replans weigh every binding."""
    binding: Binding
    scene: Scene
    world: World
    settings: ExecutionSettings
    emit: Callable[[RunEvent], None]
    started: float
    goal: int
    problem: SceneProblem
    names: StableNames
    actions: list[Action]
    """The current plan's actions still to do."""
    first_length: int
    reached: set[str]
    expected: dict[str, Pose]
    """Where every object not in the hand should stand."""
    executed: list[ExecutedAction] = field(default_factory=list)
    failures: list[Failure] = field(default_factory=list)
    replans: int = 0
    plan_index: int = 0
    failed_grasps: dict[GraspKey, int] = field(default_factory=dict)
    """How often each grasp failed at each place."""
    refused_grasps: set[GraspKey] = field(default_factory=set)
    """The grasps whose motion the arm refused, at their place: never tried again there."""
    grasp_misses: list[tuple[str, float, Pose]] = field(default_factory=list)
    """Every grasp that failed, in order: the object, its finger axis and where it stood."""
    step: int = 0
    picked_from: Pose = field(default_factory=lambda: Pose((0.0, 0.0, 0.0)))
    """Where the object in the hand was taken from."""

    def check_the_end(self) -> RunReport | None:
        """No action left: the report where the world is as expected and the goal
        holds, else a failure and a replan (the report where that fails)."""
        observation = self.world.observe()
        difference = _compare(self.expected, observation, self.settings, exempt=None)
        if difference is None and _goal_holds(
            self.problem, observation, self.reached, self.settings
        ):
            return self.finish(True, f"goal of {self.model.demonstration_label(self.goal)} reached")
        self.failures.append(
            difference or Failure(self.step, FailureKind.GOAL, "the goal does not hold at the end")
        )
        return self.replan_or_finish(self.step)

    def act(self, action: Action) -> RunReport | None:
        """Carry out ``action`` and check what it did (module docstring); on a
        difference, a failure and a replan (the report where that fails)."""
        self.step += 1
        step = self.step
        problem, expected, settings, world = self.problem, self.expected, self.settings, self.world
        location = problem.location(action.location)
        target = pose_of(location)
        grasp = next(g for g in problem.grasps if g.name == action.grasp)
        self.emit(RunEvent("action", str(action), step, self.replans, len(self.actions)))
        noticed = _note_counts(world)
        if action.kind == "GRASP":
            self.picked_from = expected.get(action.object, target)
            world.grasp(action.object, grasp.axis, self.picked_from)
        else:
            world.put_down(action.object, target)
        observation = world.observe()
        failure = _check_action(action, target, expected, observation, settings, step)
        if failure is None and action.kind == "PUT_DOWN":
            turn = turned_beyond(
                problem, observation, action.object, action.location, settings.yaw_tolerance
            )
            if turn is not None:
                detail = f"{action.object} is turned {turn:.1f}° from its target"
                failure = Failure(step, FailureKind.MISPLACED, detail)
        notes = _notes_since(world, noticed)
        refused = list(getattr(world, "motion_failures", ()))[
            noticed[ROBOT_NOTES.index("motion_failures")] :
        ]
        if failure is not None and failure.kind == FailureKind.GRASP and refused:
            # the arm never went: say so, not only that the object is not in the hand
            detail = f"{action.object} was not grasped: the arm refused the motion ({refused[-1]})"
            failure = replace(failure, detail=detail, note=refused[-1])
        elif failure is not None and notes:  # what the robot itself noticed going wrong
            failure = replace(failure, detail=f"{failure.detail} ({notes[-1]})", note=notes[-1])
        self.executed.append(ExecutedAction(step, action, target, self.plan_index, failure is None))
        if failure is None:
            if action.kind == "GRASP":
                expected.pop(action.object, None)
            else:
                expected[action.object] = observation.poses[action.object]
                _mark_reached(problem, action, self.reached)
            upcoming = [
                pose_of(problem.location(a.location)) for a in self.actions if a.kind == "PUT_DOWN"
            ]
            world.between_actions(upcoming)
            failure = _compare(expected, world.observe(), settings, exempt=None, step=step)
        if failure is None:
            return None
        self.failures.append(failure)
        self.emit(RunEvent("failure", f"{failure.kind}: {failure.detail}", step, self.replans))
        if action.kind == "GRASP" and failure.kind == FailureKind.GRASP:
            key = _grasp_key(action.object, grasp.axis, self.picked_from, settings)
            self.failed_grasps[key] = self.failed_grasps.get(key, 0) + 1
            if refused:  # the arm never went: it would refuse the same motion again
                self.refused_grasps.add(key)
            self.grasp_misses.append((action.object, grasp.axis, self.picked_from))
        held = world.observe().held
        if held is not None:
            # Plans start with an empty hand: put the object back where it was taken.
            world.put_down(held, self.picked_from)
        return self.replan_or_finish(step)

    def replan_or_finish(self, step: int) -> RunReport | None:
        """Replan (:meth:`replan`); the report of the failed run where it cannot."""
        why = self.replan(step)
        if why:
            return self.finish(False, why, gave_up=why.startswith("gave up"))
        return None

    def cause(self) -> str:
        """The failure that brought the run to its end, as a sentence with how
        often it happened: for a grasp, the attempts at that object and each
        grasp tried (finger axis, place, times); else the last failure. Empty
        where nothing failed."""
        if not self.failures:
            return ""
        last = self.failures[-1]
        actions = {executed.step: executed.action for executed in self.executed}
        obj = actions[last.step].object if last.step in actions else None
        if last.kind == FailureKind.GRASP and obj is not None:
            misses = [(axis, where) for name, axis, where in self.grasp_misses if name == obj]
            tried = Counter(
                f"across {axis % 180.0:g}° at ({where.position[0]:.3f}, {where.position[1]:.3f})"
                for axis, where in misses
            )
            grasps = ", ".join(f"{grasp} {plural(times, 'time')}" for grasp, times in tried.items())
            noun = "grasps" if len(tried) > 1 else "grasp"
            seen = f"; the last: {last.note}" if last.note else ""
            return (
                f"{obj} could not be grasped in {plural(len(misses), 'attempt')} "
                f"({noun} tried: {grasps}{seen})"
            )
        same = [
            f
            for f in self.failures
            if f.kind == last.kind and f.step in actions and actions[f.step].object == obj
        ]
        times = f" ({len(same)} times)" if len(same) > 1 else ""
        return f"step {last.step}: {last.kind}: {last.detail}{times}"

    def finish(self, success: bool, reason: str, gave_up: bool = False) -> RunReport:
        """The run's report, the world observed a last time. A failed run's
        ``reason`` leads with its cause (:meth:`cause`), then what stopped it."""
        world, problem = self.world, self.problem
        if not success:
            cause = self.cause()
            reason = f"{cause}; then {reason}" if cause else reason
        final = world.observe()
        errors = {
            obj: _distance(final.poses[obj], pose_of(problem.location(loc)))
            for obj, loc in problem.problem.goal
            if obj in final.poses
        }
        turns = turn_errors(problem, final)
        self.emit(
            RunEvent(
                "done",
                reason if success else f"FAILED: {reason}",
                len(self.executed),
                self.replans,
                status="succeeded" if success else "failed",
            )
        )
        return RunReport(
            success=success,
            replans=self.replans,
            goal=self.goal,
            actions=tuple(self.executed),
            failures=tuple(self.failures),
            final=final,
            scene=self.scene,
            reason=reason,
            first_plan_length=self.first_length,
            pose_errors=errors,
            turn_errors=turns,
            reached=tuple(sorted(self.reached)),
            seconds=time.perf_counter() - self.started,
            world=world.name,
            gave_up=gave_up,
            injected=tuple(getattr(world, "injected", ())),
        )

    def replan(self, step: int) -> str | None:
        """Plan again from what is observed; None on success, else why not."""
        if self.replans >= self.settings.max_replans:  # the report counts the replans made
            return f"gave up after {plural(self.settings.max_replans, 'replan')}"
        self.replans += 1
        self.plan_index += 1
        observation = self.world.observe()
        current = observed_scene(observation, self.scene)  # complete: the prepared scene's geometry
        try:
            tasks, index, floors = self._observed_tasks(current)
        except DemoplanError as exc:
            return f"cannot plan in the observed world: {exc}"
        best, why = self._shortest_replan(tasks, index, floors, current, observation)
        if best is None:
            return why
        return self._adopt_replan(best, observation, step)

    def _observed_tasks(self, current: Scene) -> tuple[tuple[BoundTask, ...], int, list[int]]:
        """The observed world's bound tasks, the index of the goal being run
        among their candidates, and each binding's lower bound on its plan."""
        tasks = prepare_observed(self.roles, current, self.settings.geometry).bindings
        index = next(i for i, c in enumerate(tasks[0].candidates) if self.goal in c.demonstrations)
        return tasks, index, goal_floors(tasks, index, current)

    def _shortest_replan(
        self,
        tasks: tuple[BoundTask, ...],
        index: int,
        floors: list[int],
        current: Scene,
        observation: Observation,
    ) -> tuple[_Replan | None, str]:
        """The shortest plan to goal ``index`` from the observed world over the
        bindings — the current binding first; others only where their bound can
        beat the plan found — and else the first reason none was found."""
        settings = self.settings
        order = sorted(
            range(len(tasks)), key=lambda b: (tasks[b].binding != self.binding, floors[b])
        )
        clock = Clock(settings.budget)
        best: _Replan | None = None
        why = ""
        for number in order:
            binding, floor = tasks[number].binding, floors[number]
            if best is not None and floor >= len(best[1]):
                continue
            left = clock.remaining()
            if best is not None and left is not None and left <= 0:
                break  # out of time: the plan found stands
            model = tasks[number].model
            reached = frozenset(self.reached) if binding == self.binding else frozenset()
            try:
                candidate = tasks[number].candidates[index]
                with building_within(clock):
                    built = build_problem(
                        current,
                        candidate,
                        settings.geometry,
                        reached,
                        self.names,
                        surroundings_of(model, current),
                    )
            except DemoplanError as exc:
                why = why or f"cannot plan in the observed world: {exc}"
                continue
            built, refused = _without_failed_grasps(
                built, self.failed_grasps, self.refused_grasps, observation, settings, self.world
            )
            if refused:
                why = why or refused
                continue
            outcome = solve_candidate(built, clock)
            if outcome.plan is None:
                why = why or f"no plan from the observed world: {outcome.reason}"
                continue
            if best is None or len(outcome.plan) < len(best[1]):
                best = (built, outcome.plan, binding, model)
        return best, why

    def _adopt_replan(self, best: _Replan, observation: Observation, step: int) -> str | None:
        """Run on with the plan ``best`` (its binding the run's from now on);
        None, else why the robot cannot carry it out."""
        built, plan, binding, model = best
        roles = ""
        if binding != self.binding:
            self.reached = set()
            roles = f" (roles given anew: {binding.describe()})"
        self.binding, self.model = binding, model
        try:
            _check_feasible(self.world, list(plan.actions), built, self.scene.source)
        except InputError as exc:  # an object moved beyond the robot's reach
            return f"the new plan {exc.message}"
        self.problem, self.actions = built, list(plan.actions)
        self.reached.update(_reached_at_start(self.problem))
        self.expected = dict(observation.poses)
        self.emit(
            RunEvent(
                "replan",
                f"replan {self.replans}: {plural(len(self.actions), 'action')}{roles}",
                step,
                self.replans,
                len(self.actions),
                _targets(self.problem),
            )
        )
        return None


ROBOT_NOTES = ("motion_failures", "grasp_problems")
"""A world's lists of what its robot noticed going wrong, as it happened
(``--sim arm``: the motions it refused, the grasps it felt fail)."""


def _note_counts(world: World) -> tuple[int, ...]:
    return tuple(len(getattr(world, notes, ())) for notes in ROBOT_NOTES)


def _notes_since(world: World, counts: tuple[int, ...]) -> list[str]:
    """What the robot noticed since it had noticed ``counts`` (:func:`_note_counts`)."""
    return [
        note
        for notes, seen in zip(ROBOT_NOTES, counts, strict=True)
        for note in list(getattr(world, notes, ()))[seen:]
    ]


def _check_feasible(
    world: World, actions: list[Action], problem: SceneProblem, source: str
) -> None:
    """Before the first motion: an input error naming every object the plan
    must grasp that the world's gripper cannot take (``why_not_graspable(obj)``)
    and every grasp or put-down the robot cannot reach
    (``why_not_reachable(obj, pose)``), in a world that can tell — rather than
    one failed grasp after another."""
    graspable = getattr(world, "why_not_graspable", None)
    reachable = getattr(world, "why_not_reachable", None)
    reasons: list[str] = []
    if graspable is not None:
        moved = dict.fromkeys(a.object for a in actions if a.kind == "GRASP")
        reasons += [f"{obj} {why}" for obj in moved if (why := graspable(obj))]
    if reachable is not None and not reasons:
        reasons += _out_of_reach(world, actions, problem, reachable)
    if reasons:
        raise InputError(
            "cannot be carried out by this robot: " + "; ".join(reasons),
            source=source,
            field="objects",
        )


def _out_of_reach(
    world: World,
    actions: list[Action],
    problem: SceneProblem,
    reachable: Callable[[str, Pose], str | None],
) -> list[str]:
    """The plan's places (an object standing where it is grasped, put down where
    it goes) the robot cannot reach, in one sentence: the one place's reason;
    for several, why no base reaches them all where the world can tell
    (``why_not_reachable_together``: two of them too far apart), else the
    first one's reason and how many more, of which objects — not a reason per
    place, each saying the same."""
    places: list[tuple[str, Pose]] = []
    out: list[tuple[str, str]] = []
    seen = set()
    for action in actions:
        if (action.object, action.location) in seen:
            continue
        seen.add((action.object, action.location))
        pose = pose_of(problem.location(action.location))
        where = "standing" if action.kind == "GRASP" else "put down"
        places.append((f"{action.object} {where} at {_xy(pose)}", pose))
        why = reachable(action.object, pose)
        if why:
            out.append((f"{action.object} {where}", why))
    if len(out) <= 1:
        return [f"{label} {why}" for label, why in out]
    together = getattr(world, "why_not_reachable_together", None)
    apart = None if together is None else together(places)
    if apart:
        count = f"{len(out)} of the plan's {len(places)} places are out of its reach"
        return [f"{apart} ({count}): bring them closer together"]
    (label, why), *more = out
    of = ", ".join(sorted({other.split()[0] for other, _ in more}))
    verb = "is" if len(more) == 1 else "are"
    return [f"{label} {why}; so {verb} {len(more)} more of the plan's {len(places)} places ({of})"]


def _xy(pose: Pose) -> str:
    return f"({pose.position[0]:.3f}, {pose.position[1]:.3f})"


GraspKey = tuple[str, float, int, int]
"""A grasp as tried: the object, its finger axis (deg, mod 180) and the place it
stood (x, y in cells of the position tolerance)."""


def _grasp_key(obj: str, axis: float, where: Pose, settings: ExecutionSettings) -> GraspKey:
    cell = settings.position_tolerance
    return (
        obj,
        round(axis % 180.0, 1),
        round(where.position[0] / cell),
        round(where.position[1] / cell),
    )


def _without_failed_grasps(
    built: SceneProblem,
    failed: dict[GraspKey, int],
    refused: set[GraspKey],
    observation: Observation,
    settings: ExecutionSettings,
    world: World,
) -> tuple[SceneProblem, str]:
    """``built`` without the grasps that failed :data:`MAX_SAME_GRASP` times, or
    whose motion the arm ``refused`` once, on an object standing where it stood
    then (another grasp is planned instead); with the reason to stop when such
    an object has no grasp left."""
    banned: dict[tuple[str, float], GraspKey] = {}
    for key, count in failed.items():
        obj = key[0]
        pose = observation.poses.get(obj)
        here = pose is not None and _grasp_key(obj, key[1], pose, settings) == key
        if (count >= MAX_SAME_GRASP or key in refused) and here:
            banned[(obj, key[1])] = key
    if not banned:
        return built, ""
    axis = {g.name: round(g.axis % 180.0, 1) for g in built.grasps}
    allowed = frozenset(
        (obj, grasp) for obj, grasp in built.problem.allowed if (obj, axis[grasp]) not in banned
    )
    for obj, _ in banned:
        if not any(o == obj for o, _ in allowed):
            pose = observation.poses[obj]
            motions = list(getattr(world, "motion_failures", ()))
            cause = f"; the last motion refused: {motions[-1]}" if motions else ""
            ways = {key in refused for (name, _), key in banned.items() if name == obj}
            how = {
                frozenset({False}): f"each of its grasps failed {MAX_SAME_GRASP} times",
                frozenset({True}): "the arm refused each of its grasps",
            }.get(
                frozenset(ways), f"each of its grasps failed {MAX_SAME_GRASP} times or was refused"
            )
            return built, (
                f"gave up on {obj}: {how} at "
                f"({pose.position[0]:.3f}, {pose.position[1]:.3f}){cause}"
            )
    return replace(built, problem=replace(built.problem, allowed=allowed)), ""


def _targets(problem: SceneProblem) -> tuple[tuple[str, Pose], ...]:
    """Each goal object's target pose in ``problem``."""
    return tuple((obj, pose_of(problem.location(loc))) for obj, loc in problem.problem.goal)


def _reached_at_start(problem: SceneProblem) -> set[str]:
    """The subgoals that count as reached where the objects stand (docs/execution.md)."""
    return set(Rules(problem.problem).start().reached)


def _mark_reached(problem: SceneProblem, action: Action, reached: set[str]) -> None:
    """The subgoal this put-down reaches (at most one; docs/execution.md)."""
    rules = Rules(problem.problem)
    reached |= rules.reached_by_put_down(action.object, action.location, frozenset(reached))


def _goal_holds(
    problem: SceneProblem, observation: Observation, reached: set[str], settings: ExecutionSettings
) -> bool:
    if observation.held is not None:
        return False
    if {s.id for s in problem.problem.subgoals} - reached:
        return False
    for obj, loc in problem.problem.goal:
        pose = observation.poses.get(obj)
        if (
            pose is None
            or _distance(pose, pose_of(problem.location(loc))) > settings.position_tolerance
        ):
            return False
        if turned_beyond(problem, observation, obj, loc, settings.yaw_tolerance) is not None:
            return False
    return True


def _check_action(
    action: Action,
    target: Pose,
    expected: dict[str, Pose],
    observation: Observation,
    settings: ExecutionSettings,
    step: int,
) -> Failure | None:
    obj = action.object
    if action.kind == "GRASP":
        if observation.held != obj:
            return Failure(step, FailureKind.GRASP, f"{obj} is not in the hand after the grasp")
        return _compare(expected, observation, settings, exempt=obj, step=step)
    if observation.held is not None:
        return Failure(step, FailureKind.RELEASE, f"{observation.held} is still in the hand")
    pose = observation.poses.get(obj)
    if pose is None:
        return Failure(step, FailureKind.DROPPED, f"{obj} is nowhere to be seen")
    error = _distance(pose, target)
    if error > settings.position_tolerance:
        kind = FailureKind.MISPLACED if error < MISPLACED_WITHIN else FailureKind.DROPPED
        where = ", ".join(f"{v:.3f}" for v in pose.position)
        return Failure(
            step, kind, f"{obj} stands at ({where}), {100 * error:.1f} cm from its target"
        )
    return _compare(expected, observation, settings, exempt=obj, step=step)


def _compare(
    expected: dict[str, Pose],
    observation: Observation,
    settings: ExecutionSettings,
    exempt: str | None,
    step: int = 0,
) -> Failure | None:
    """The first object that is not where it should be, or a new one."""
    for obj, pose in expected.items():
        if obj == exempt:
            continue
        seen = observation.poses.get(obj)
        if seen is None:
            if observation.held == obj:
                continue
            return Failure(step, FailureKind.MOVED, f"{obj} is gone from where it stood")
        error = _distance(seen, pose)
        if error > settings.position_tolerance:
            where = ", ".join(f"{v:.3f}" for v in seen.position)
            return Failure(
                step, FailureKind.MOVED, f"{obj} moved {100 * error:.1f} cm, to ({where})"
            )
    for obj in observation.poses:
        if obj not in expected and obj != exempt:
            return Failure(step, FailureKind.NEW_OBJECT, f"{obj} appeared")
    return None
