"""Whether a plan as short as the feedback bound can exist: a refutation that
raises the start's lower bound by one move.

:meth:`LowerBounds.feedback <demoplan.planning.bounds.LowerBounds.feedback>`
counts the needs, the idle objects that must make way, and a minimum
feedback vertex set of the precedences between the needy objects. A plan
exactly that long (*tight*) has a rigid shape (see the method's argument):
the needy objects moved twice are a minimum feedback vertex set F — each
goes source → somewhere → goal —, every other needy object moves once,
straight home, the forced idle objects move once (no goal) or away and back
(at their goal), and no other object moves at all.

For each choice of F, the moves are *events* to be put in order. Each event
has a grasp to choose, and a grasp needs places empty at that moment: the
places that block it at the source and at the target, the target itself and
what overlaps it. A place is empty between the
moment its first occupant leaves and the moment its final occupant arrives
(an object that never moves keeps it full: that grasp is out). So each
grasp demands precedences between events, and a tight plan needs one grasp
per event with no cycle among all the precedences. Where a parked object
stands in between is not known: it is taken to be in nobody's way, which
only drops demands, so a refutation stays sound. Where places stack, a
grasp also needs the places standing on its source empty (an object on top
must have left first); that a put-down needs its support occupied is not
demanded — again fewer demands, so a refutation stays sound, and the play-out
below checks it with the real operators. The search for grasps propagates
(an event with one grasp left takes it; one with none refutes the choice)
and branches on the event with the fewest grasps left.

When an order is found it is played out with the real operators (an object
sent away goes to a free place that leaves each later move of the order a
grasp, and blocks the fewest of their grasps): a plan
as long as the bound, so shortest. Where no choice's fixed order plays out,
the orders their precedences allow are searched, choice by choice
(:mod:`~demoplan.planning.playout`: a depth-first search that sends objects
away only when no move home is possible, and drops a state where objects
that never move again rule out a move still to come). When every choice of F
is refuted, no plan has as few moves as the bound: the bound is one more.
Then plans of that length are looked for in the same way, among shapes
with one move more (:func:`_one_move_more`): one found is shortest. The solver makes
the check once, at the start, before any search (a few milliseconds on the
benchmark's hard families, where it settles all 64 problems: 63 plans, one
refutation).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass

from demoplan.graphs import acyclic, strongly_connected
from demoplan.planning.bounds import MAX_EXACT_COMPONENT, LowerBounds, Move
from demoplan.planning.budget import Clock
from demoplan.planning.compiled import Compiled
from demoplan.planning.playout import (
    MAX_EVENTS,
    NodeBudget,
    OutOfNodesError,
    PlayOutSearch,
    Ranking,
)

__all__ = ["TightResult", "searched_plan", "tight_plan"]

MAX_CHOICES = 512
"""Choices of the feedback set tried before giving up (no refutation)."""
MAX_NODES = 20_000
"""Branchings of the grasp search, over all choices, before giving up."""
PARKING_TRIED = 4
"""Places tried per object sent away when an order is played out."""
PLAY_OUTS = 256
"""Dead ends of one order's play-out before it is given up (unknown, not a
refutation: the order exists, its play-out was not found)."""
SEARCH_NODES = 20_000
"""States the search over orders (:mod:`~demoplan.planning.playout`) may
visit, over all choices, where the fixed order's play-out finds none."""
SEARCHED_ORDERS = 64
"""Orders (one per choice of the feedback set) kept for that search."""

_Precedences = tuple[tuple[int, int], ...]  # (earlier event, later event) pairs


@dataclass(frozen=True, slots=True)
class TightResult:
    """What :func:`tight_plan` found: ``moves``, a plan exactly as long as the
    feedback bound (so shortest); or ``refuted``, no such plan exists (the
    bound is one move more); or neither (unknown) — ``ordered`` then says
    whether some choice's moves had an order, whose play-out
    :func:`searched_plan` may still find."""

    moves: list[Move] | None = None
    refuted: bool = False
    ordered: bool = False


class _GiveUpError(Exception):
    """The grasp search spent :data:`MAX_NODES` or the clock ran out."""


def tight_plan(
    bounds: LowerBounds, positions: tuple[int, ...], reached: int, clock: Clock
) -> TightResult:
    """A plan from this state with exactly as many moves as the feedback
    bound, which must also be the state's bound, from each choice's fixed
    order; or its refutation (module docstring). Neither when one may exist
    but was not built, or the check does not apply: pending subgoals, a
    precedence cycle too large to enumerate, :data:`MAX_NODES` or the clock
    spent."""
    shape = _rigid_shape(bounds, positions, reached)
    if shape is None:
        return TightResult()
    needy, forced_objects, choices = shape
    shapes = (
        _Events(bounds, positions, needy, set(itertools.chain(*parked)), forced_objects)
        for parked in choices
    )
    return _first_play_out(shapes, positions, _Limits(MAX_NODES, clock), fixed=True, search=False)


def searched_plan(
    bounds: LowerBounds, positions: tuple[int, ...], reached: int, clock: Clock, refuted: bool
) -> list[Move] | None:
    """What :func:`tight_plan` left open, with more work: where it
    ``refuted`` the feedback bound, a plan one move longer (:func:`_one_move_more`:
    each shape's fixed order, then the orders searched); else a plan as long
    as the bound from the orders its choices allow, searched
    (:mod:`~demoplan.planning.playout`). Either is shortest; None proves
    nothing."""
    shape = _rigid_shape(bounds, positions, reached)
    if shape is None:
        return None
    needy, forced_objects, choices = shape
    if not refuted and bounds.feedback(positions, reached) > MAX_EVENTS:
        return None  # orders too long to search
    limits = _Limits(MAX_NODES, clock)
    if refuted:
        shapes = _one_move_more(bounds, positions, needy, forced_objects, choices)
        return _first_play_out(shapes, positions, limits, fixed=True, search=True).moves
    minimum = (
        _Events(bounds, positions, needy, set(itertools.chain(*parked)), forced_objects)
        for parked in choices
    )
    return _first_play_out(minimum, positions, limits, fixed=False, search=True).moves


def _rigid_shape(
    bounds: LowerBounds, positions: tuple[int, ...], reached: int
) -> tuple[list[int], int, Iterator[tuple[tuple[int, ...], ...]]] | None:
    """The needy objects, the idle ones forced to move (a mask) and the
    minimum feedback sets of a plan as long as the feedback bound; None where
    the check does not apply."""
    c = bounds.c
    if reached != c.all_subgoals:
        return None
    graph = bounds.precedence_graph(positions, reached)
    if graph is None:
        return None
    needy, after, forced_objects = graph
    if bounds.estimate(positions, reached) != bounds.feedback(positions, reached):
        return None  # another bound is larger: a plan that long has no rigid shape
    choices = _minimum_feedback_sets(after)
    return None if choices is None else (needy, forced_objects, choices)


def _one_move_more(
    bounds: LowerBounds,
    positions: tuple[int, ...],
    needy: list[int],
    forced_objects: int,
    minimum: Iterator[tuple[tuple[int, ...], ...]],
) -> Iterator[_Events]:
    """Shapes of plans one move longer than the feedback bound, for when no
    plan has its length: per minimum feedback set F, each other needy object
    parked too (it moves twice), then each idle object without a goal that
    the bound does not force moved once. Not every such plan has one of
    these shapes (an object of F may move three times; F may be a larger set
    that holds no minimum one): a plan found is shortest, none found proves
    nothing."""
    c = bounds.c
    for parked in minimum:
        feedback_set = set(itertools.chain(*parked))
        for obj in needy:
            if obj not in feedback_set:
                yield _Events(bounds, positions, needy, feedback_set | {obj}, forced_objects)
        for obj in range(len(positions)):
            if obj not in needy and c.goal[obj] < 0 and not forced_objects >> obj & 1:
                yield _Events(bounds, positions, needy, feedback_set, forced_objects | 1 << obj)


def _first_play_out(
    shapes: Iterator[_Events],
    positions: tuple[int, ...],
    limits: _Limits,
    *,
    fixed: bool,
    search: bool,
) -> TightResult:
    """The first of ``shapes`` with an order of its events that plays out:
    with ``fixed``, each choice's fixed order (:meth:`_Events.realize`); with
    ``search``, then a search over the orders of those not played out
    (:meth:`_Events.search`). ``refuted`` when the shapes ran out and none
    had an order; else ``ordered`` says whether one had."""
    clock = limits.clock
    orderable, complete = False, True
    in_the_way: list[int] = []  # computed when first needed: a pass over every fact
    unplayed: list[tuple[_Events, list[int]]] = []  # orders the fixed play-out missed
    for count, events in enumerate(shapes):
        if clock.expired():
            return TightResult()
        if count >= MAX_CHOICES:
            complete = False
            break
        if events.impossible:
            continue
        try:
            closure = _order(events.options, events.base, limits)
        except _GiveUpError:
            complete = False
            break
        if closure is None:
            continue
        orderable = True
        in_the_way = in_the_way or _in_the_way(events.c)
        moves = events.realize(positions, closure, in_the_way) if fixed else None
        if moves is not None:
            return TightResult(moves=moves)
        if search and len(unplayed) < SEARCHED_ORDERS and len(events.moves) <= MAX_EVENTS:
            unplayed.append((events, closure))
    if complete and not orderable:
        return TightResult(refuted=True)
    budget = NodeBudget(SEARCH_NODES, clock)
    for events, closure in unplayed:
        try:
            moves = events.search(positions, closure, in_the_way, budget)
        except OutOfNodesError:
            break
        if moves is not None:
            return TightResult(moves=moves)
    return TightResult(ordered=orderable)


def _minimum_feedback_sets(
    after: dict[int, list[int]],
) -> Iterator[tuple[tuple[int, ...], ...]] | None:
    """Every minimum feedback vertex set of the digraph ``after`` (as tuples
    of one set per strongly connected component, chained), or None when a
    component is too large to enumerate."""
    nodes = {x for successors in after.values() for x in successors} | set(after)
    edges = {y: [x for x in after.get(y, ()) if x != y] for y in nodes}
    per_component: list[list[tuple[int, ...]]] = []
    for component in strongly_connected(edges):
        if len(component) < 2:
            continue
        if len(component) > MAX_EXACT_COMPONENT:
            return None
        members = set(component)
        inside = [(y, x) for y in component for x in edges[y] if x in members]
        for size in range(1, len(component)):
            sets = [
                removed
                for removed in itertools.combinations(sorted(component), size)
                if acyclic(members.difference(removed), inside)
            ]
            if sets:
                per_component.append(sets)
                break
    return itertools.product(*per_component)


class _Events:
    """The moves of a tight plan for one feedback set ``parked``, as events,
    with each event's grasp options (each a tuple of precedences)."""

    def __init__(
        self,
        bounds: LowerBounds,
        positions: tuple[int, ...],
        needy: list[int],
        parked: set[int],
        forced_objects: int,
    ):
        c = bounds.c
        self.c = c
        self.impossible = False
        self.leave: dict[int, int] = {}  # object -> the event that takes it from its place
        self.arrive: dict[int, int] = {}  # object -> the event that puts it at its goal
        moves: list[tuple[int, int, int]] = []  # (object, source or -1, target or -1)
        moving = set(needy)
        for obj in range(len(positions)):
            if forced_objects >> obj & 1:
                moving.add(obj)
        for obj in sorted(moving):
            source, goal = positions[obj], c.goal[obj]
            if obj in parked or (obj not in needy and goal >= 0):
                self.leave[obj] = len(moves)
                moves.append((obj, source, -1))  # away to a place in nobody's way
                if goal >= 0:
                    self.arrive[obj] = len(moves)
                    moves.append((obj, -1, goal))  # and home from there
            elif goal >= 0:
                self.leave[obj] = self.arrive[obj] = len(moves)
                moves.append((obj, source, goal))
            else:
                self.leave[obj] = len(moves)
                moves.append((obj, source, -1))
        self.moves = moves
        self.first_occupant = {positions[obj]: obj for obj in range(len(positions))}
        self.final_occupant = {c.goal[obj]: obj for obj in moving if c.goal[obj] >= 0}
        self.fixed = {positions[obj] for obj in range(len(positions)) if obj not in moving}
        # Two events of one object come in order.
        self.base: _Precedences = tuple(
            (self.leave[obj], self.arrive[obj])
            for obj in moving
            if obj in self.arrive and self.arrive[obj] != self.leave[obj]
        )
        self.options: list[list[_Precedences]] = []
        for event, (obj, source, target) in enumerate(moves):
            options = []
            for grasp in c.grasps_of[obj]:
                demands = self._empty_at(event, obj, _kept_empty(c, source, target, grasp))
                if demands is not None:
                    options.append(demands)
            if not options:
                self.impossible = True
            self.options.append(options)

    def realize(
        self, positions: tuple[int, ...], closure: list[int], in_the_way: list[int]
    ) -> list[Move] | None:
        """The events in an order of ``closure`` as real moves, checked by the
        operators' own tests; None if no play-out tried works. An object sent
        away goes to a free place that leaves every later move a grasp, no goal
        still to be filled, those in the way of the fewest grasps first
        (:meth:`_PlayOut._spots`); where a later move is then not
        possible, the play-out backs up to the last object sent away and tries
        its next place (:data:`PARKING_TRIED` places each, :data:`PLAY_OUTS`
        dead ends in all)."""
        at = list(positions)
        occupied = 0
        for location in at:
            occupied |= 1 << location
        to_fill = 0
        for place in self.final_occupant:
            to_fill |= 1 << place
        playing = _PlayOut(self, _linear(closure), in_the_way)
        return playing.run(at, occupied, to_fill)

    def search(
        self,
        positions: tuple[int, ...],
        closure: list[int],
        in_the_way: list[int],
        budget: NodeBudget,
    ) -> list[Move] | None:
        """The events in any order ``closure`` allows, by depth-first search
        (:class:`~demoplan.planning.playout.PlayOutSearch`): where the fixed
        order of :meth:`realize` has no play-out, another order may."""
        c = self.c
        masks = []  # per event: what each grasp no unmoved object rules out keeps empty
        for event, (obj, source, target) in enumerate(self.moves):
            kept = [_kept_empty(c, source, target, g) for g in c.grasps_of[obj]]
            masks.append([mask for mask in kept if self._empty_at(event, obj, mask) is not None])
        per_event = [_waiting([event_masks]) for event_masks in masks]
        to_fill = 0
        for place in self.final_occupant:
            to_fill |= 1 << place

        def ranking(width: int) -> Ranking:
            def rank(
                obj: int, source: int, others: int, grasps: list[int], done: int, to_fill: int
            ) -> list[int]:
                killing = hitting = 0
                for event, (every, union) in enumerate(per_event):
                    if not done >> event & 1 and self.moves[event][0] != obj:
                        killing |= every
                        hitting |= union
                waiting = killing, hitting
                return _ranked_places(
                    c, obj, source, others, grasps, to_fill, waiting, in_the_way, width
                )

            return rank

        search = PlayOutSearch(c, self.moves, closure, masks, ranking)
        return search.run(positions, to_fill, range(1, PARKING_TRIED + 1), budget)

    def _empty_at(self, event: int, obj: int, places: int) -> _Precedences | None:
        """The precedences that keep ``places`` empty at ``event`` (a move of
        ``obj``), or None if an object that never moves stands at one."""
        demands = []
        while places:
            low = places & -places
            places ^= low
            place = low.bit_length() - 1
            if place in self.fixed:
                return None
            first = self.first_occupant.get(place)
            if first is not None and first != obj:
                demands.append((self.leave[first], event))
            final = self.final_occupant.get(place)
            if final is not None and final != obj:
                demands.append((event, self.arrive[final]))
        return tuple(demands)


class _PlayOut:
    """A depth-first play-out of ordered events (:meth:`_Events.realize`):
    the only choices are where the objects sent away go."""

    def __init__(self, events: _Events, order: list[int], in_the_way: list[int]):
        self.events, self.order, self.in_the_way = events, order, in_the_way
        self.plan: list[Move] = []
        self.dead_ends = 0
        c = events.c
        # Per event of the order: per grasp the order leaves it (its demands
        # kept by the order), the places an object must not stand at for it
        # (blocking at the source or the target, on the source, the target or
        # overlapping it).
        at_position = {event: position for position, event in enumerate(order)}
        self.forbidden: list[list[int]] = []
        for event in order:
            obj, source, target = events.moves[event]
            masks = []
            for grasp in c.grasps_of[obj]:
                mask = _kept_empty(c, source, target, grasp)
                demands = events._empty_at(event, obj, mask)
                if demands is not None and all(
                    at_position[before] < at_position[later] for before, later in demands
                ):
                    masks.append(mask)
            self.forbidden.append(masks)

    def run(self, at: list[int], occupied: int, to_fill: int) -> list[Move] | None:
        """The moves of the order, the objects starting at ``at``; None where
        no place tried works out. Iterative (an order has thousands of events
        on a thousand objects): a choice point is kept for each object sent
        away with places left to try."""
        c = self.events.c
        choices: list[tuple[int, list[int], int, int, int, list[int]]] = []
        index, places = 0, None
        while True:
            if index == len(self.order) and c.is_goal(tuple(at), c.all_subgoals):
                return self.plan
            move = None
            if index < len(self.order):
                obj, _, target = self.events.moves[self.order[index]]
                source = at[obj]
                others = occupied & ~(1 << source)
                grasps = [g for g in c.grasps_of[obj] if c.grasp_ok(occupied, source, g)]
                if places is None:
                    places = (
                        [target]
                        if target >= 0
                        else self._spots(index, source, others, grasps, to_fill)
                    )
                while places and move is None:
                    place = places.pop(0)
                    usable = [g for g in grasps if place != source and c.put_ok(others, place, g)]
                    if usable:
                        move = (obj, source, place, usable[0])
                if move is not None and places:
                    choices.append((index, list(at), occupied, to_fill, len(self.plan), places))
            if move is not None:
                self.plan.append(move)
                obj, _, place, _ = move
                at[obj] = place
                occupied = occupied & ~(1 << move[1]) | 1 << place
                if c.goal[obj] == place:
                    to_fill &= ~(1 << place)
                index, places = index + 1, None
                continue
            self.dead_ends += 1  # back up to the last object sent away with places left
            if not choices or self.dead_ends >= PLAY_OUTS:
                return None
            index, at, occupied, to_fill, length, places = choices.pop()
            del self.plan[length:]

    def _spots(
        self, index: int, source: int, others: int, grasps: list[int], to_fill: int
    ) -> list[int]:
        """Where the object of event ``index`` may be sent away: first free
        places that leave every later event one of the grasps the order
        leaves it (until the object's own next event, which takes it from
        there), then those that are no goal
        still to be filled, stand on no other place (an object put on top
        keeps the one below from being grasped), block no grasp of those
        later events, and are in the way of the fewest grasps at all."""
        obj = self.events.moves[self.order[index]][0]
        waiting = []  # the grasps' masks of each later event, until the object's next
        for position in range(index + 1, len(self.order)):
            if self.events.moves[self.order[position]][0] == obj:
                break
            waiting.append(self.forbidden[position])
        return _ranked_places(
            self.events.c,
            obj,
            source,
            others,
            grasps,
            to_fill,
            _waiting(waiting),
            self.in_the_way,
            PARKING_TRIED,
        )


@dataclass(slots=True)
class _Limits:
    """What the grasp search may spend: branchings left (shared by every
    choice of the feedback set) and the clock."""

    nodes: int
    clock: Clock


def _order(
    options: list[list[_Precedences]], base: _Precedences, limits: _Limits
) -> list[int] | None:
    """One option per event with no cycle among the chosen precedences and
    ``base``: the transitive closure of the order (event -> mask of the
    events after it), or None when there is none; :class:`_GiveUpError`
    when ``limits`` are spent."""
    reach = [0] * len(options)
    if not _add(reach, base):
        return None
    return _search(reach, [list(o) for o in options], [False] * len(options), limits)


def _add(reach: list[int], precedences: _Precedences) -> bool:
    """Add precedences to the transitive closure ``reach`` in place; False on a cycle."""
    for before, later in precedences:
        if before == later or reach[later] >> before & 1:
            return False
        if reach[before] >> later & 1:
            continue
        gained = 1 << later | reach[later]
        for event in range(len(reach)):
            if event == before or reach[event] >> before & 1:
                reach[event] |= gained
    return True


def _search(
    reach: list[int], options: list[list[_Precedences]], done: list[bool], limits: _Limits
) -> list[int] | None:
    """Propagate, then branch on the event with the fewest live options."""
    changed = True
    while changed:
        changed = False
        for event, live in enumerate(options):
            if done[event]:
                continue
            kept = [o for o in live if _add(list(reach), o)]
            if not kept:
                return None
            options[event] = kept
            if len(kept) == 1:
                _add(reach, kept[0])
                done[event] = True
                changed = True
    open_events = [e for e in range(len(options)) if not done[e]]
    if not open_events:
        return reach
    limits.nodes -= 1
    if limits.nodes <= 0 or limits.clock.expired():
        raise _GiveUpError
    branch = min(open_events, key=lambda e: len(options[e]))
    for option in options[branch]:
        trial = list(reach)
        _add(trial, option)
        choice = [list(o) for o in options]
        choice[branch] = [option]
        marks = list(done)
        marks[branch] = True
        found = _search(trial, choice, marks, limits)
        if found is not None:
            return found
    return None


def _linear(closure: list[int]) -> list[int]:
    """The events in an order that keeps every precedence of ``closure``
    (event -> mask of the events after it), the lowest index first among
    the ready ones."""
    waiting = [0] * len(closure)
    for event, later in enumerate(closure):
        while later:
            low = later & -later
            later ^= low
            waiting[low.bit_length() - 1] |= 1 << event
    order: list[int] = []
    left = (1 << len(closure)) - 1
    while left:
        event = next(e for e in range(len(closure)) if left >> e & 1 and not waiting[e] & left)
        order.append(event)
        left &= ~(1 << event)
    return order


def _ranked_places(
    c: Compiled,
    obj: int,
    source: int,
    others: int,
    grasps: list[int],
    to_fill: int,
    waiting: tuple[int, int],
    in_the_way: list[int],
    limit: int,
) -> list[int]:
    """The ``limit`` best free places ``obj`` (at ``source``, one of ``grasps``
    usable) may be sent to. ``waiting``: the places that would take the last
    grasp of an event still to come (killing), and those in the way of any of
    its grasps (hitting). First the places that kill none, then those that are
    no goal still to be filled, stand on no other place (an object put on top
    keeps the one below from being grasped), hit none, and are in the way of
    the fewest grasps at all. Its own goal is not one: it comes with its own
    move."""
    killing, hitting = waiting
    ranked = sorted(
        (
            (
                killing >> place & 1,
                to_fill >> place & 1,
                c.below[place] != 0,
                hitting >> place & 1,
                in_the_way[place],
            ),
            place,
        )
        for place in range(len(c.locations))
        if place not in (source, c.goal[obj]) and not others >> place & 1
    )
    chosen: list[int] = []
    for _, place in ranked:
        if len(chosen) == limit:
            break
        if any(c.put_ok(others, place, g) for g in grasps):
            chosen.append(place)
    return chosen


def _waiting(masks_per_event: Iterable[Sequence[int]]) -> tuple[int, int]:
    """For :func:`_ranked_places`: the places in the way of every grasp of one
    of the events (each given by the places its grasps need empty), and
    those in the way of any grasp."""
    killing = hitting = 0
    for masks in masks_per_event:
        every = -1
        for mask in masks:
            every &= mask
            hitting |= mask
        killing |= every if masks else 0
    return killing, hitting


def _kept_empty(c: Compiled, source: int, target: int, grasp: int) -> int:
    """The places (a bit mask) that must be empty for a move from ``source`` to
    ``target`` (-1: none) with ``grasp``: those the grasp's hand sweeps at both
    ends, the places above the source, the target's exclusive ones and the
    target itself."""
    empty = 0
    if source >= 0:
        empty |= c.block[source][grasp] | c.above[source]
    if target >= 0:
        empty |= c.block[target][grasp] | c.exclusive[target] | 1 << target
    return empty


def _in_the_way(c: Compiled) -> list[int]:
    """Per place, how many (place, grasp) pairs an object standing there blocks."""
    counts = [0] * len(c.locations)
    for row in c.block:
        for mask in row:
            while mask:
                low = mask & -mask
                mask ^= low
                counts[low.bit_length() - 1] += 1
    return counts
