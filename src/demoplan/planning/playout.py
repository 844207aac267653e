"""Playing out the events of a tight plan in any order their precedences allow
(:mod:`~demoplan.planning.tight`): a depth-first search for when the one
fixed order of :meth:`_Events.realize <demoplan.planning.tight._Events.realize>`
finds no play-out.

The events are the moves of a plan exactly as long as the feedback bound:
per object, its move home, or its move away (and back home later, for an
object of the feedback set). Their order is free but for the precedences of
the order found by the grasp search (an event waits for those before it). In
each state the search tries the events that are ready: first the moves home
that the real operators allow at once, then the moves away, the object that
stands in the way of every grasp of the most events still to come first,
each to the free places ranked as the fixed play-out ranks them.

A state is dropped when it cannot lead to a tight plan: an object whose
events are all done never moves again (a tight plan has no other move of
it), so where such objects keep every grasp of an event still to come from
happening — blocking it at its source or its target, standing on its source,
at or overlapping its target — the event can never be made. States are
remembered (object places and events done), so none is searched twice.

The places tried for a move away widen by rounds (the best one, then two,
…, up to :data:`~demoplan.planning.tight.PARKING_TRIED`): a play-out that
needs only the best-ranked places is found before the search spends its
nodes on the others. A round visits at most :data:`ROUND_NODES` states, and
every state counts against one count of nodes shared by all rounds
(:class:`NodeBudget`) and the clock.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from demoplan.planning.bounds import Move
from demoplan.planning.budget import Clock
from demoplan.planning.compiled import Compiled

__all__ = ["MAX_EVENTS", "NodeBudget", "OutOfNodesError", "PlayOutSearch"]

MAX_EVENTS = 400
"""Largest number of events searched (the search recurses once per event)."""
ROUND_NODES = 2000
"""States one round (one choice of the feedback set, one width) may visit."""
_CLOCK_EVERY = 64
"""States searched between two readings of the clock."""

Ranking = Callable[[int, int, int, list[int], int, int], list[int]]
"""``(object, source, others, grasps, events done, goals still to fill)`` ->
the free places to send the object to, best first."""


_Candidate = tuple[int, int, int, int, int]  # event, object, source, place, grasp


class OutOfNodesError(Exception):
    """The search spent its nodes or the clock ran out."""


class _RoundOverError(Exception):
    """One round spent its :data:`ROUND_NODES`."""


@dataclass(slots=True)
class NodeBudget:
    """States the search may still visit (shared by every call), and the clock."""

    nodes: int
    clock: Clock

    def spend(self) -> None:
        """Count one state; :class:`OutOfNodesError` when none is left or the time is up."""
        self.nodes -= 1
        if self.nodes < 0 or (self.nodes % _CLOCK_EVERY == 0 and self.clock.expired()):
            raise OutOfNodesError


class PlayOutSearch:
    """One search over the orders of ``moves`` (object, source or -1, target
    or -1), from ``start``.

    ``after``: per event, the mask of the events that must come after it;
    ``masks``: per event, the places each grasp it may use needs empty (the
    grasps no object that never moves rules out); ``to_fill``: the goal
    places still to be filled; ``ranking``: where an object sent away may go,
    given how many places each round may try.
    """

    def __init__(
        self,
        c: Compiled,
        moves: Sequence[tuple[int, int, int]],
        after: Sequence[int],
        masks: Sequence[Sequence[int]],
        ranking: Callable[[int], Ranking],
    ):
        self.c, self.moves, self.masks, self.ranking = c, moves, masks, ranking
        self.before = [0] * len(moves)  # event -> mask of the events it waits for
        for event, later in enumerate(after):
            while later:
                low = later & -later
                later ^= low
                self.before[low.bit_length() - 1] |= 1 << event
        self.every = [_common(event_masks) for event_masks in masks]  # in the way of each grasp
        self.events_of: dict[int, int] = {}  # object -> mask of its events
        for event, (obj, _, _) in enumerate(moves):
            self.events_of[obj] = self.events_of.get(obj, 0) | 1 << event

    def run(
        self, start: Sequence[int], to_fill: int, widths: Sequence[int], budget: NodeBudget
    ) -> list[Move] | None:
        """The moves of a play-out, or None if the rounds of ``widths`` found
        none, each within :data:`ROUND_NODES` (:class:`OutOfNodesError` when
        ``budget`` is spent)."""
        if len(self.moves) > MAX_EVENTS or len(self.moves) >= sys.getrecursionlimit() - 100:
            return None
        for width in widths:
            rank = self.ranking(width)
            at = list(start)
            occupied = 0
            for location in at:
                occupied |= 1 << location
            plan: list[Move] = []
            try:
                state = _State(at, plan, rank, set(), ROUND_NODES)
                if self._search(state, 0, occupied, to_fill, budget):
                    return plan
            except _RoundOverError:
                continue
        return None

    def _search(
        self, state: _State, done: int, occupied: int, to_fill: int, budget: NodeBudget
    ) -> bool:
        c, at = self.c, state.at
        if done == (1 << len(self.moves)) - 1:
            return c.is_goal(tuple(at), c.all_subgoals)
        key = (tuple(at), done)
        if key in state.seen or self._doomed(at, done):
            return False
        state.seen.add(key)
        state.nodes -= 1
        if state.nodes < 0:
            raise _RoundOverError
        budget.spend()
        for event, obj, source, place, grasp in self._candidates(state, done, occupied, to_fill):
            at[obj] = place
            state.plan.append((obj, source, place, grasp))
            moved = occupied & ~(1 << source) | 1 << place
            filled = to_fill & ~(1 << place) if c.goal[obj] == place else to_fill
            if self._search(state, done | 1 << event, moved, filled, budget):
                return True
            state.plan.pop()
            at[obj] = source
        return False

    def _doomed(self, at: list[int], done: int) -> bool:
        """Some event still to come has every grasp ruled out by objects whose
        events are all done (they never move again)."""
        c = self.c
        settled = 0
        for obj, location in enumerate(at):
            if not self.events_of.get(obj, 0) & ~done:
                settled |= 1 << location
        for event, (obj, _, target) in enumerate(self.moves):
            if done >> event & 1:
                continue
            source = at[obj]
            if c.above[source] & settled:
                return True
            if target >= 0 and (c.exclusive[target] | 1 << target) & settled:
                return True
            at_source = c.block[source]
            at_target = c.block[target] if target >= 0 else None
            if all(
                at_source[g] & settled or (at_target is not None and at_target[g] & settled)
                for g in c.grasps_of[obj]
            ):
                return True
        return False

    def _candidates(
        self, state: _State, done: int, occupied: int, to_fill: int
    ) -> list[_Candidate]:
        """The moves to try from this state, as (event, object, source, place,
        grasp): the ready moves home the operators allow, then the ready moves
        away, the most urgent object first, each to its ranked places."""
        c, at = self.c, state.at
        homes: list[_Candidate] = []
        aways: list[_Candidate] = []
        for event, (obj, _, target) in enumerate(self.moves):
            if done >> event & 1 or self.before[event] & ~done:
                continue
            source = at[obj]
            grasps = [g for g in c.grasps_of[obj] if c.grasp_ok(occupied, source, g)]
            others = occupied & ~(1 << source)
            places = (
                [target] if target >= 0 else state.rank(obj, source, others, grasps, done, to_fill)
            )
            for place in places:
                usable = [g for g in grasps if c.put_ok(others, place, g)]
                if usable:
                    move = (event, obj, source, place, usable[0])
                    (homes if target >= 0 else aways).append(move)
        urgency = {obj: self._blocked_by(at[obj], obj, done) for _, obj, _, _, _ in aways}
        aways.sort(key=lambda move: -urgency[move[1]])  # stable: the ranking within
        return homes + aways

    def _blocked_by(self, place: int, obj: int, done: int) -> int:
        """How many events still to come, of other objects, an object at
        ``place`` keeps from every grasp they may use."""
        count = 0
        for event, every in enumerate(self.every):
            if every >> place & 1 and not done >> event & 1 and self.moves[event][0] != obj:
                count += 1
        return count


def _common(masks: Sequence[int]) -> int:
    """The places in every one of ``masks`` (none if there are none)."""
    every = -1 if masks else 0
    for mask in masks:
        every &= mask
    return every


@dataclass(slots=True)
class _State:
    """What one round of the search changes as it goes: the objects' places,
    the moves so far, the round's ranking of places and the states seen."""

    at: list[int]
    plan: list[Move]
    rank: Ranking
    seen: set[tuple[tuple[int, ...], int]]
    nodes: int  # states this round may still visit
