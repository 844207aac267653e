"""Plan a learned task in a scene: every candidate goal, the shortest chosen
(paper §IV.C, §V.B; docs/scenes.md "Planning").

Each demonstrated goal (deduplicated) becomes a planning problem
(:func:`~demoplan.scenes.problems.build_problem`) solved by the anytime
planner (:func:`~demoplan.planning.search.solve_within`); the shortest plan
wins, ties going to the earliest demonstration — Experiment 2 picks
demonstration 2's 4 moves over demonstration 1's 5. The scene comes
prepared (:func:`~demoplan.scenes.prepared.prepare`, by the command, inside
its clock); the command's clock is shared: each candidate gets an equal part
of what is left when its turn comes (:meth:`~demoplan.budget.Clock.part`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Any

from demoplan.budget import Clock, time_budget
from demoplan.errors import LimitReachedError, NoPlanError, UsageError
from demoplan.model import TaskModel
from demoplan.planning.problem import Plan
from demoplan.planning.search import solve_within
from demoplan.scenes.binding import Binding
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.prepared import PreparedScene
from demoplan.scenes.problems import SceneProblem, build_problem
from demoplan.scenes.scene import Scene
from demoplan.scenes.table import Surroundings, surroundings_of
from demoplan.wording import plural

__all__ = [
    "CandidatePlan",
    "ChosenPlan",
    "SceneLimitReachedError",
    "SceneNoPlanError",
    "ScenePlan",
    "building_within",
    "goal_problem",
    "plan_goal",
    "plan_in_scene",
    "scene_problems",
    "solve_candidate",
]


class SceneNoPlanError(NoPlanError):
    """No candidate goal has a plan in the scene (exit 3): each candidate's
    outcome (its problem, why it has no plan) and the prepared scene travel
    with the error, so that a figure of the failure needs no second build."""

    def __init__(
        self, message: str, outcomes: tuple[CandidatePlan, ...], scene: Scene, model: TaskModel
    ):
        super().__init__(message)
        self.outcomes = outcomes
        self.scene = scene
        self.model = model


class SceneLimitReachedError(LimitReachedError):
    """No candidate goal was planned within the budget (exit 4); as
    :class:`SceneNoPlanError`, with the outcomes and the scene."""

    def __init__(
        self, message: str, outcomes: tuple[CandidatePlan, ...], scene: Scene, model: TaskModel
    ):
        super().__init__(message)
        self.outcomes = outcomes
        self.scene = scene
        self.model = model


@dataclass(frozen=True, slots=True)
class CandidatePlan:
    """One candidate goal: its problem and its plan, or why there is none."""

    problem: SceneProblem
    plan: Plan | None
    reason: str | None = None
    limit_reached: bool = False
    binding: Binding = field(default_factory=lambda: Binding(()))
    """Which scene instance fills which role of the model (docs/planning.md,
    "Identical objects"); the problem and the plan name the instances."""
    bindings_weighed: int = 1
    """Bindings of the model's roles this goal was weighed under: planned, or
    set aside by their lower bound."""

    @property
    def bound(self) -> float:
        """A proven lower bound on this goal's plans (infinite: proved to have none)."""
        if self.plan is not None:
            return self.plan.bound
        return 0 if self.limit_reached else math.inf

    @property
    def goal(self) -> int:
        return self.problem.candidate.goal

    @property
    def length(self) -> int | None:
        return None if self.plan is None else len(self.plan)


@dataclass(frozen=True, slots=True)
class ChosenPlan:
    """The candidate goal chosen and its plan, in the scene planned in."""

    problem: SceneProblem
    plan: Plan
    scene: Scene
    """The scene planned in, prepared (complete: sizes, landmarks): what figures draw."""
    model: TaskModel
    """The task model planned, its roles bound as :attr:`binding` says (its
    demonstrations name the candidates)."""
    binding: Binding = field(default_factory=lambda: Binding(()))
    bindings_weighed: int = 1

    @classmethod
    def of(
        cls, candidate: CandidatePlan, plan: Plan, scene: Scene, model: TaskModel
    ) -> ChosenPlan:
        """``candidate``, whose plan is ``plan``, chosen in ``scene`` for ``model``."""
        return cls(
            candidate.problem, plan, scene, model, candidate.binding, candidate.bindings_weighed
        )

    @property
    def goal(self) -> int:
        return self.problem.candidate.goal

    @property
    def length(self) -> int:
        return len(self.plan)


@dataclass(frozen=True, slots=True)
class ScenePlan:
    """Every candidate's outcome and the chosen one."""

    candidates: tuple[CandidatePlan, ...]
    chosen: ChosenPlan

    @property
    def scene(self) -> Scene:
        """The scene planned in, prepared: what figures draw."""
        return self.chosen.scene

    @property
    def model(self) -> TaskModel:
        """The task model planned (bound as the chosen plan's roles are)."""
        return self.chosen.model

    def is_chosen(self, candidate: CandidatePlan) -> bool:
        """Whether ``candidate`` is the one chosen."""
        return candidate.problem is self.chosen.problem

    @property
    def bound(self) -> int:
        """A proven lower bound on the length of a plan for any candidate goal."""
        return int(min(c.bound for c in self.candidates))

    @property
    def optimal(self) -> bool:
        """The chosen plan is proved shortest over every candidate goal."""
        return self.bound >= len(self.chosen.plan)

    def as_plan(self) -> Plan:
        """The chosen plan, with the optimality and bound of the whole choice."""
        return replace(self.chosen.plan, optimal=self.optimal, bound=self.bound)

    def to_json(self) -> dict[str, Any]:
        """``plan --json`` (docs/formats.md "Plan output")."""
        chosen = self.chosen
        return {
            "actions": [[a.kind, a.object, a.location, a.grasp] for a in chosen.plan.actions],
            "length": len(chosen.plan),
            "optimal": self.optimal,
            "bound": self.bound,
            "goal": chosen.goal,
            **({"binding": chosen.binding.roles} if not chosen.binding.identity else {}),
            "candidates": [
                {
                    "goal": c.goal,
                    "demonstrations": list(c.problem.candidate.demonstrations),
                    "length": c.length,
                    "optimal": None if c.plan is None else c.plan.optimal,
                    "bound": None if math.isinf(c.bound) else int(c.bound),
                    **({"reason": c.reason} if c.reason else {}),
                    **({"bindings": c.bindings_weighed} if c.bindings_weighed > 1 else {}),
                    "expanded": None if c.plan is None else c.plan.expanded,
                    "seconds": None if c.plan is None else round(c.plan.seconds, 6),
                }
                for c in self.candidates
            ],
            **(
                {"collisions": chosen.problem.collision_check.to_json()}
                if chosen.problem.collision_check is not None
                else {}
            ),
            "subgoals": [
                {
                    "id": s.label,
                    "state": s.state,
                    "object": s.object,
                    "location": _target(chosen.problem, s.label),
                }
                for s in chosen.problem.candidate.subtasks
            ],
            "precedences": [list(p) for p in chosen.problem.candidate.precedences],
            "locations": chosen.problem.locations_json(),
            "grasps": {g.name: {"object": g.object, "axis": g.axis} for g in chosen.problem.grasps},
        }


def _target(problem: SceneProblem, label: str) -> str:
    return next(s.location for s in problem.problem.subgoals if s.id == label)


BUILDING_SECONDS = 0.5
"""Preparing a scene and building its planning problems get at least this
long, even where the budget is spent before they start (a slow start-up on a
loaded machine): a small scene is always planned, and a goal with no plan is
reported as such (exit 3), not as out of time."""


@contextmanager
def building_within(clock: Clock) -> Iterator[None]:
    """Scene preparation and problem building inside the block stop at
    ``clock``'s deadline (given at least :data:`BUILDING_SECONDS`) with
    LimitReachedError (exit 4), naming the option that raises the budget and
    the work the time ran out in: a flood of objects or free-space spots
    makes the geometry (collision facts: grasps × locations²) take minutes."""
    if clock.deadline is None or math.isinf(clock.deadline):
        yield
        return
    timeout = clock.budget.timeout
    limit = "the time budget" if timeout is None else f"--timeout {timeout:g} s"
    message = (
        f"no plan within {limit}: the time ran out building the planning problems, "
        "{where}, before any search; give it more time (--timeout), or the scene fewer objects "
        "or free-space spots"
    )
    with time_budget(clock.at_least(BUILDING_SECONDS), message):
        yield


def scene_problems(
    model: TaskModel, prepared: PreparedScene, settings: GeometrySettings = GeometrySettings()
) -> list[SceneProblem]:
    """The planning problem of every candidate goal (deduplicated) in the
    ``prepared`` scene."""
    around = surroundings_of(model, prepared.scene)
    return [
        build_problem(prepared.scene, c, settings, surroundings=around) for c in prepared.candidates
    ]


def goal_problem(
    model: TaskModel,
    prepared: PreparedScene,
    number: int,
    settings: GeometrySettings = GeometrySettings(),
) -> SceneProblem:
    """The planning problem of the goal of demonstration ``number`` (numbered
    from 1, as people read them) in the ``prepared`` scene; a usage error for a number the
    model does not have."""
    if not 1 <= number <= len(model.sequences):
        raise UsageError(
            f"--goal {number}: the model has {plural(len(model.sequences), 'demonstration')} "
            f"(1..{len(model.sequences)})"
        )
    problems = scene_problems(model, prepared, settings)
    return next(p for p in problems if number - 1 in p.candidate.demonstrations)


def solve_candidate(
    problem: SceneProblem, clock: Clock | None = None, search: str = "astar"
) -> CandidatePlan:
    """Plan one candidate within ``clock`` (None: no limit but the states kept);
    its failure (no plan, a limit reached) becomes the reason."""
    if problem.obstacles:
        return CandidatePlan(problem, None, "; ".join(problem.obstacles))
    shortage = None if problem.room is None else problem.room.shortage()
    try:
        return CandidatePlan(problem, solve_within(problem.problem, search, clock or Clock()))
    except NoPlanError as exc:
        reason = str(exc) if shortage is None else f"{shortage} ({exc})"
        return CandidatePlan(problem, None, reason)
    except LimitReachedError as exc:
        reason = str(exc) if shortage is None else f"{shortage} ({exc})"
        return CandidatePlan(problem, None, reason, limit_reached=True)


def plan_in_scene(
    model: TaskModel,
    prepared: PreparedScene,
    *,
    clock: Clock | None = None,
    settings: GeometrySettings = GeometrySettings(),
    search: str = "astar",
) -> ScenePlan:
    """Plan every candidate goal in the ``prepared`` scene and choose the
    shortest; ``clock``'s time (None: no limit but the states kept) is shared,
    each candidate getting an equal part of what is left.

    Where the model has roles of identical objects, each goal is planned under
    the bindings of roles to instances in order of their lower bound, until
    none left can beat the best plan (:func:`plan_goal`).

    Raises :class:`NoPlanError` (exit 3) when no candidate has a plan, with each
    candidate's reason, and :class:`LimitReachedError` (exit 4) when none was
    found but some candidate's search was cut short.
    """
    clock = clock or Clock()
    with building_within(clock):
        around = surroundings_of(model, prepared.scene)
    goals = len(prepared.candidates)
    outcomes = []
    for index in range(goals):  # an equal part of what is left (every limit as named)
        share = clock.part(1 / (goals - index))
        outcomes.append(plan_goal(prepared, index, share, settings, search, around))
    solved = [(c, c.plan) for c in outcomes if c.plan is not None]
    if not solved:
        reasons = "; ".join(
            f"goal of {model.demonstration_label(c.goal)}: {c.reason}" for c in outcomes
        )
        if any(c.limit_reached for c in outcomes):
            raise SceneLimitReachedError(
                f"no candidate goal planned within the budget ({reasons})",
                tuple(outcomes),
                prepared.scene,
                prepared.model,
            )
        raise SceneNoPlanError(
            f"no candidate goal can be reached in this scene ({reasons})",
            tuple(outcomes),
            prepared.scene,
            prepared.model,
        )
    candidate, plan = min(solved, key=lambda pair: (len(pair[1]), pair[0].goal))
    bound = next(task.model for task in prepared.bindings if task.binding == candidate.binding)
    return ScenePlan(tuple(outcomes), ChosenPlan.of(candidate, plan, prepared.scene, bound))


def plan_goal(
    prepared: PreparedScene,
    index: int,
    clock: Clock,
    settings: GeometrySettings,
    search: str = "astar",
    surroundings: Surroundings | None = None,
) -> CandidatePlan:
    """Candidate goal ``index`` planned under every binding of the model's roles
    (:mod:`demoplan.scenes.binding`), lowest lower bound first; a binding whose
    bound reaches the best plan's length is set aside unplanned, so that the
    plan returned is the shortest over all bindings where every binding planned
    proved its own, and its bound is the least over all of them. The first
    binding's search gets half the time, each later one an equal part of what
    is left; building a binding's problem may take the goal's whole time. When
    the time is spent, the bindings not planned yet keep their bounds: the plan
    found is returned, proved shortest only where those bounds say so."""
    around = surroundings or surroundings_of(prepared.model, prepared.scene)
    floors = prepared.floors(index)
    order = sorted(range(len(prepared.bindings)), key=floors.__getitem__)
    best: CandidatePlan | None = None
    failed: CandidatePlan | None = None
    bounds: list[float] = []
    for position, number in enumerate(order):
        task, floor = prepared.bindings[number], floors[number]
        if best is not None and best.plan is not None and floor >= len(best.plan):
            bounds.append(floor)
            continue
        left = clock.remaining()
        if position > 0 and left is not None and left <= 0:
            # Out of time: the bindings not planned keep their bounds.
            bounds += [floors[b] for b in order[position:]]
            if best is None and failed is not None:
                failed = replace(
                    failed,
                    reason=f"{failed.reason}; the time ran out after "
                    f"{plural(position, 'binding')} of {len(order)} ways to fill the roles",
                    limit_reached=True,
                )
            break
        # the most promising binding half, the others equal parts
        parts = 2 if position == 0 and len(order) > 1 else len(order) - position
        share = clock.part(1 / parts)
        with building_within(clock):
            problem = build_problem(
                prepared.scene, task.candidates[index], settings, surroundings=around
            )
        outcome = replace(solve_candidate(problem, share, search), binding=task.binding)
        bounds.append(max(outcome.bound, floor))
        if outcome.plan is None:
            failed = failed or outcome
        elif best is None or best.plan is None or len(outcome.plan) < len(best.plan):
            best = outcome
    chosen = best or failed
    assert chosen is not None
    weighed = len(order)
    if chosen.plan is None or weighed == 1:
        return replace(chosen, bindings_weighed=weighed)
    bound = int(min(bounds))
    plan = replace(chosen.plan, bound=bound, optimal=bound >= len(chosen.plan))
    return replace(chosen, plan=plan, bindings_weighed=weighed)
