"""The symbolic planning problem (paper §IV.C; docs/formats.md "Planning problem").

A problem names objects, locations (some marked as free space), grasps, which
grasps each object allows, collision facts ``(la, lb, g)`` — grasp g at la is
impossible while another object stands at lb — the initial placement and the
goal. Beyond the paper's example it can say:

- ``supports (upper, lower)``: a location above the table holds an object only
  while ``lower`` is occupied (while *every* lower location listed for it is,
  for a block bridging two), and the object at ``lower`` cannot be grasped
  while ``upper`` is occupied (stacking);
- ``exclusions (la, lb)``: overlapping locations that cannot both be occupied;
- ``accepts (l, o)``: a location named in any such pair holds only the objects
  paired with it (a spot sized for a fork does not take the food); locations
  named in none take any object;
- ``subgoals`` with ``precedences``: subgoal X (an object put down at a
  location) may only be reached after every Y with (Y, X); a subgoal counts as
  reached when its object is put down there after all its predecessors are
  reached, or at the start when it already holds and its predecessors do too.
  ``reached`` lists subgoals reached before planning (replanning keeps them).

Semantics of the operators (docs/formats.md): one object per location, the hand holds
at most one object;

- ``GRASP o la g``: hand empty, o at la, g allowed for o, no *other* object at
  any lb with a fact ``(la, lb, g)``, and no object on top of la;
- ``PUT_DOWN o lb g``: holding o with g, lb free, no other object at any lc
  with a fact ``(lb, lc, g)``, lb's support occupied, lb's exclusive partners free,
  lb accepts o;
- the goal holds when every goal object is at its location, every subgoal is
  reached and the hand is empty. Plans are shortest in number of actions.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from demoplan.errors import InputError

__all__ = [
    "Action",
    "Plan",
    "Problem",
    "Subgoal",
    "format_plan",
    "optimality_line",
    "plan_to_json",
]


@dataclass(frozen=True, slots=True)
class Subgoal:
    """Object ``object`` put down at ``location``; ``id`` names it in precedences."""

    id: str
    object: str
    location: str


@dataclass(frozen=True, slots=True)
class Problem:
    """A planning problem; build it with :meth:`Problem.create` to have it checked."""

    objects: tuple[str, ...]
    locations: tuple[str, ...]
    grasps: tuple[str, ...]
    allowed: frozenset[tuple[str, str]]
    collisions: frozenset[tuple[str, str, str]]
    initial: tuple[tuple[str, str], ...]
    goal: tuple[tuple[str, str], ...]
    freespace: frozenset[str] = frozenset()
    supports: frozenset[tuple[str, str]] = frozenset()
    exclusions: frozenset[tuple[str, str]] = frozenset()
    accepts: frozenset[tuple[str, str]] = frozenset()
    subgoals: tuple[Subgoal, ...] = ()
    precedences: frozenset[tuple[str, str]] = frozenset()
    reached: frozenset[str] = frozenset()
    name: str = field(default="problem", compare=False)

    @classmethod
    def create(
        cls,
        *,
        objects: Iterable[str],
        locations: Iterable[str],
        grasps: Iterable[str],
        allowed: Iterable[tuple[str, str]],
        collisions: Iterable[tuple[str, str, str]] = (),
        initial: Iterable[tuple[str, str]],
        goal: Iterable[tuple[str, str]] = (),
        freespace: Iterable[str] = (),
        supports: Iterable[tuple[str, str]] = (),
        exclusions: Iterable[tuple[str, str]] = (),
        accepts: Iterable[tuple[str, str]] = (),
        subgoals: Iterable[Subgoal] = (),
        precedences: Iterable[tuple[str, str]] = (),
        reached: Iterable[str] = (),
        name: str = "problem",
        source: str | None = None,
    ) -> Problem:
        """Build and check a problem; every name must be declared, with one kind."""
        problem = cls(
            objects=tuple(dict.fromkeys(objects)),
            locations=tuple(dict.fromkeys(locations)),
            grasps=tuple(dict.fromkeys(grasps)),
            allowed=frozenset(allowed),
            collisions=frozenset(collisions),
            initial=tuple(initial),
            goal=tuple(goal),
            freespace=frozenset(freespace),
            supports=frozenset(supports),
            exclusions=frozenset(exclusions),
            accepts=frozenset(accepts),
            subgoals=tuple(subgoals),
            precedences=frozenset(precedences),
            reached=frozenset(reached),
            name=name,
        )
        problem.check(source)
        return problem

    def check(self, source: str | None = None) -> None:
        """Raise :class:`InputError` unless every fact uses declared names consistently."""
        self._check_declared(source)
        self._check_start(source)
        self._check_goal(source)

    def _check_declared(self, source: str | None) -> None:
        """No name declared with two types; the static facts name declared ones."""
        objects, locations, grasps = set(self.objects), set(self.locations), set(self.grasps)
        clash = (objects & locations) | (objects & grasps) | (locations & grasps)
        if clash:
            raise InputError(
                f"{sorted(clash)} declared with two types", source=source, field="object"
            )
        for obj, grasp in self.allowed:
            _need(obj, objects, "Object", "state", source)
            _need(grasp, grasps, "Grasp", "state", source)
        for la, lb, grasp in self.collisions:
            _need(la, locations, "Location", "state", source)
            _need(lb, locations, "Location", "state", source)
            _need(grasp, grasps, "Grasp", "state", source)
        for name in self.freespace:
            _need(name, locations, "Location", "object", source)
        for pair in self.supports | self.exclusions:
            for loc in pair:
                _need(loc, locations, "Location", "state", source)
        for loc, obj in self.accepts:
            _need(loc, locations, "Location", "state", source)
            _need(obj, objects, "Object", "state", source)

    def _refuse(
        self, restricted: set[str], obj: str, loc: str, where: str, source: str | None
    ) -> None:
        """An error if ``loc`` has accepts facts (is ``restricted``) and none names ``obj``."""
        if loc in restricted and (loc, obj) not in self.accepts:
            raise InputError(
                f"{loc!r} does not accept {obj!r} (its accepts facts name "
                f"{sorted(o for lo, o in self.accepts if lo == loc)})",
                source=source,
                field=where,
            )

    def _check_start(self, source: str | None) -> None:
        """Every object at one declared location, one object per location."""
        objects, locations = set(self.objects), set(self.locations)
        restricted = {loc for loc, _ in self.accepts}
        seen_objects: set[str] = set()
        seen_locations: dict[str, str] = {}
        for obj, loc in self.initial:
            _need(obj, objects, "Object", "state", source)
            _need(loc, locations, "Location", "state", source)
            self._refuse(restricted, obj, loc, "state", source)
            if obj in seen_objects:
                raise InputError(f"{obj!r} is at two locations", source=source, field="state")
            if loc in seen_locations:
                raise InputError(
                    f"{loc!r} holds both {seen_locations[loc]!r} and {obj!r}; "
                    "one object per location",
                    source=source,
                    field="state",
                )
            seen_objects.add(obj)
            seen_locations[loc] = obj
        missing = objects - seen_objects
        if missing:
            raise InputError(
                f"objects {sorted(missing)} have no location in the initial state",
                source=source,
                field="state",
            )

    def _check_goal(self, source: str | None) -> None:
        """One goal location per object; subgoals, their order and those reached by id."""
        objects, locations = set(self.objects), set(self.locations)
        restricted = {loc for loc, _ in self.accepts}
        goal_objects: set[str] = set()
        for obj, loc in self.goal:
            _need(obj, objects, "Object", "goal", source)
            _need(loc, locations, "Location", "goal", source)
            self._refuse(restricted, obj, loc, "goal", source)
            if obj in goal_objects:
                raise InputError(f"{obj!r} has two goal locations", source=source, field="goal")
            goal_objects.add(obj)
        ids = [s.id for s in self.subgoals]
        if len(set(ids)) != len(ids):
            raise InputError("subgoal ids must be unique", source=source, field="goal")
        for subgoal in self.subgoals:
            _need(subgoal.object, objects, "Object", "goal", source)
            _need(subgoal.location, locations, "Location", "goal", source)
            self._refuse(restricted, subgoal.object, subgoal.location, "goal", source)
        for before, after in self.precedences:
            for sid in (before, after):
                if sid not in ids:
                    raise InputError(f"{sid!r} is not a subgoal id", source=source, field="goal")
        for sid in self.reached:
            if sid not in ids:
                raise InputError(f"{sid!r} is not a subgoal id", source=source, field="state")

    def location_of(self) -> dict[str, str]:
        """Where each object starts."""
        return dict(self.initial)


@dataclass(frozen=True, slots=True)
class Action:
    """``GRASP`` or ``PUT_DOWN`` of ``object`` at ``location`` with ``grasp``."""

    kind: str
    object: str
    location: str
    grasp: str

    def __str__(self) -> str:
        return f"{self.kind} {self.object} {self.location} {self.grasp}"


@dataclass(frozen=True, slots=True)
class Plan:
    """A plan and how the search found it."""

    actions: tuple[Action, ...]
    expanded: int = 0
    generated: int = 0
    seconds: float = 0.0
    search: str = ""
    optimal: bool = True  # proved shortest
    bound: int = 0  # proven lower bound on every plan's length (actions)

    def __len__(self) -> int:
        return len(self.actions)


def optimality_line(plan: Plan) -> str:
    """Whether ``plan`` is proved shortest, and the proven lower bound if not
    (the line ``solve`` and ``plan`` print on stderr)."""
    if plan.optimal:
        return f"{len(plan)} actions, proved shortest"
    return (
        f"{len(plan)} actions, not proved shortest within the time budget: every plan "
        f"needs at least {plan.bound} (--timeout to search longer, --optimal to insist)"
    )


def format_plan(plan: Plan) -> str:
    """The plan in the paper's format, one action per line."""
    return "".join(f"{action}\n" for action in plan.actions)


def plan_to_json(plan: Plan, read_seconds: float | None = None) -> dict[str, object]:
    """The plan as ``demoplan solve --json`` prints it (``seconds``: the search;
    ``read_seconds``: reading and checking the problem file, when measured)."""
    timing = {} if read_seconds is None else {"read_seconds": round(read_seconds, 6)}
    return {
        "actions": [[a.kind, a.object, a.location, a.grasp] for a in plan.actions],
        "length": len(plan),
        "optimal": plan.optimal,
        "bound": plan.bound,
        "search": plan.search,
        "expanded": plan.expanded,
        "generated": plan.generated,
        "seconds": round(plan.seconds, 6),
        **timing,
    }


def _need(name: str, kind: set[str], what: str, where: str, source: str | None) -> None:
    """An error unless ``name`` is a declared ``what`` (one of ``kind``)."""
    if name not in kind:
        raise InputError(f"{name!r} is not a declared {what}", source=source, field=where)
