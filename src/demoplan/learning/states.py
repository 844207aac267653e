"""State generation (paper §IV.A, eq. 1–2; docs/learning.md).

Every step of every demonstration is a *placement* of one object. For each
object, every candidate reference — absolute, every other object, every
landmark — is scored: the object's placements are expressed relative to the
candidate (in the reference's frame where it has an orientation, modulo its
symmetry; orientations ``R_j⁻¹·R_i`` modulo the object's own symmetry) and
clustered with K-means for c = 1..N
(:func:`demoplan.learning.clustering.select_clusterings`, eq. 2). Decisions are
measured against the placement precision, estimated from the demonstrations
(:func:`estimate_precision`) unless set: a reference, or more clusters, wins
over a choice with fewer states only where it outscores it
(:func:`~demoplan.learning.clustering.outscores`). Each placement takes the
object's own choice among the references available at all its placements, or
one available only at its step that outscores it (:class:`_Chooser`) —
"positions can only be specified towards already placed objects".

Position and orientation choose their references independently. A state is
(object, position reference and cluster, orientation reference and cluster);
states are lettered A, B, … in order of first appearance over the
demonstrations in the order given, steps in order. docs/learning.md tells
the whole method. The precision is estimated in :mod:`demoplan.learning.precision`,
the references are scored and chosen in :mod:`demoplan.learning.references`, over
the placements :class:`~demoplan.learning.world.DemonstrationWorld` reads.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from demoplan.budget import report_progress
from demoplan.learning.precision import (
    KINDS,
    MIN_ORIENTATION_PRECISION,
    MIN_POSITION_PRECISION,
    Kind,
    Precision,
    _floored,
    _own_precisions,
    _precision,
    _Spread,
    _tightest,
    estimate_precision,
)
from demoplan.learning.references import (
    FOLLOWS_NOTE,
    ReferenceScore,
    _Chooser,
    _margins,
    _orientation,
    _position,
    _relative_values,
    _score_references,
)
from demoplan.learning.regions import with_regions
from demoplan.learning.settings import LearningSettings as StateGenerationSettings
from demoplan.learning.world import DemonstrationWorld, _Placement
from demoplan.model import (
    Demonstration,
    State,
    StateOrientation,
)

__all__ = [
    "ANYWHERE_NOTE",
    "FOLLOWS_NOTE",
    "PLACED_NOTE",
    "DemonstrationWorld",
    "Precision",
    "ReferenceScore",
    "StateGeneration",
    "StateGenerationSettings",
    "estimate_precision",
    "generate_states",
    "state_letters",
]


logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class StateGeneration:
    """States, each demonstration as a state sequence, and the scores behind them."""

    states: tuple[State, ...]
    sequences: tuple[tuple[str, ...], ...]
    scores: tuple[ReferenceScore, ...]
    precision: Precision


@dataclass(frozen=True, slots=True)
class _StateKey:
    """What makes a state: object, position reference and cluster, orientation
    reference and cluster (cluster −1: orientation unknown)."""

    object: str
    position_reference: str | None
    position_cluster: int
    orientation_reference: str | None
    orientation_cluster: int


def generate_states(
    demonstrations: Sequence[Demonstration],
    settings: StateGenerationSettings | None = None,
) -> StateGeneration:
    """Quantise every step of ``demonstrations`` to a state (paper §IV.A).

    Returns the states (lettered by first appearance), each demonstration as a
    sequence of state ids, and every candidate reference's score.

    A demonstration that repeats an earlier one exactly (the same steps, poses
    and landmarks) is evidence of nothing new: the statistics are taken over
    the distinct demonstrations, and a repeat takes its original's states (its
    steps join their members), so adding it changes no decision.
    """
    original: list[int] = []
    first_of: dict[tuple[object, ...], int] = {}
    for index, demo in enumerate(demonstrations):
        key = (demo.steps, demo.landmarks, demo.initial)
        original.append(first_of.setdefault(key, index))
    distinct = sorted(set(original))
    if len(distinct) == len(demonstrations):
        return _generate_states(demonstrations, settings)
    inner = _generate_states([demonstrations[d] for d in distinct], settings)
    position = {d: k for k, d in enumerate(distinct)}
    sequences = tuple(inner.sequences[position[original[d]]] for d in range(len(demonstrations)))
    states = []
    for state in inner.states:
        members = sorted(
            (d, step)
            for d in range(len(demonstrations))
            for k, step in state.members
            if distinct[k] == original[d]
        )
        states.append(replace(state, members=tuple(members)))
    return StateGeneration(tuple(states), sequences, inner.scores, inner.precision)


def _generate_states(
    demonstrations: Sequence[Demonstration],
    settings: StateGenerationSettings | None = None,
) -> StateGeneration:
    """:func:`generate_states` over distinct demonstrations (paper §IV.A), step by step."""
    settings = settings or StateGenerationSettings()
    world = DemonstrationWorld(demonstrations)
    observed = _relative_placements(demonstrations, world)
    precision, own_precision = _placement_precision(observed, settings)
    quantised = _quantise_placements(observed, world, settings, precision, own_precision)
    letters, members, sequences = _letter_states(demonstrations, quantised.keys)
    states = [
        _describe_state(key, letter, members[letter], observed, quantised)
        for key, letter in letters.items()
    ]
    types = {name: kind for demo in demonstrations for name, kind in demo.types}
    states = _placed_anywhere(states, types, precision, settings)
    states = with_regions(states, demonstrations)
    return StateGeneration(tuple(states), sequences, tuple(quantised.scores), precision)


@dataclass(frozen=True, slots=True)
class _RelativePlacements:
    """Every object's placements (paper §IV.A: each step is one) and their values
    relative to each candidate reference defined at them (docs/learning.md,
    *Placements and candidate references*)."""

    placements: dict[str, list[_Placement]]
    candidates: dict[str, list[str | None]]
    relative: dict[tuple[str, Kind, str | None], np.ndarray]
    """(object, kind, reference) → the object's relative values, one row per placement."""
    framed: dict[tuple[str, str | None], bool]
    """(object, reference) → whether positions are in the reference's frame."""
    everywhere: set[tuple[str, Kind, str | None]]
    """The keys of ``relative`` whose reference is available at all the object's placements."""


def _relative_placements(
    demonstrations: Sequence[Demonstration], world: DemonstrationWorld
) -> _RelativePlacements:
    """Paper §IV.A: every step of every demonstration as a placement of its object,
    expressed relative to every candidate reference — absolute, every other
    object, every landmark (:func:`_relative_table`)."""
    placements: dict[str, list[_Placement]] = {}
    for d, demo in enumerate(demonstrations):
        for s, step in enumerate(demo.steps):
            placements.setdefault(step.object, []).append(_Placement(d, s, step.pose))
    names = sorted(
        set(placements)
        | {name for demo in demonstrations for name, _ in demo.landmarks}
        | {name for demo in demonstrations for name, _ in demo.initial}
    )
    relative: dict[tuple[str, Kind, str | None], np.ndarray] = {}
    framed: dict[tuple[str, str | None], bool] = {}
    candidates = {obj: [None, *(n for n in names if n != obj)] for obj in placements}
    for obj, own in placements.items():
        for kind in KINDS:
            _relative_table(obj, kind, own, candidates[obj], world, relative, framed)
    everywhere = {
        key
        for key in relative
        if key[2] is None
        or all(world.available(p.demo, key[2], p.step) for p in placements[key[0]])
    }
    return _RelativePlacements(placements, candidates, relative, framed, everywhere)


def _placement_precision(
    observed: _RelativePlacements, settings: StateGenerationSettings
) -> tuple[Precision, dict[Kind, dict[str, _Spread]]]:
    """The precision eq. (2)'s decisions are measured against
    (:func:`estimate_precision`, over the references available at all of an
    object's placements), and each object's own (:func:`_own_precisions`)."""
    steady = {
        key: values for key, values in observed.relative.items() if key in observed.everywhere
    }
    tightest = {kind: _tightest(steady, kind, settings) for kind in KINDS}
    precision = _precision(tightest, settings)
    own_precision = {
        kind: _own_precisions(spreads, getattr(precision, kind), getattr(precision, f"{kind}_df"))
        if getattr(precision, f"{kind}_estimated")
        else {}
        for kind, spreads in tightest.items()
    }
    if precision.orientation >= settings.orientation_separation:
        logger.info(
            "orientations scatter by %.0f° (RMS), more than the %.0f° that tell two apart: "
            "no orientation is learned",
            precision.orientation,
            settings.orientation_separation,
        )
    return precision, own_precision


@dataclass(frozen=True, slots=True)
class _Quantised:
    """Every placement's state key, the margins of the decisions behind it, and
    every candidate reference's score."""

    keys: dict[tuple[int, int], _StateKey]
    """(demonstration, step) → its state's key."""
    decided: dict[tuple[int, int], dict[str, float]]
    """(demonstration, step) → decision → margin."""
    scores: list[ReferenceScore]
    notes: dict[tuple[int, int], list[str]]
    """(demonstration, step) → decisions taken at an edge of the rules, in words."""
    open_orientations: dict[tuple[int, int], _OpenOrientation] = field(default_factory=dict)
    """(demonstration, step) → an orientation left to its own choice, which may
    yet follow its position's reference (:func:`_follow_positions`)."""


@dataclass(frozen=True, slots=True)
class _OpenOrientation:
    """One placement's orientation as its object's own choice (``chosen``), with
    what :func:`_follow_positions` needs to take it from the position's reference."""

    placement: _Placement
    index: int
    chosen: ReferenceScore
    chooser: _Chooser
    precision: float


def _quantise_placements(
    observed: _RelativePlacements,
    world: DemonstrationWorld,
    settings: StateGenerationSettings,
    precision: Precision,
    own_precision: dict[Kind, dict[str, _Spread]],
) -> _Quantised:
    """Paper §IV.A, eq. (2): each object's candidate references scored by
    K-means clustering, and each of its placements quantised to a state key
    (:func:`_quantise_object`), object by object."""
    quantised = _Quantised({}, {}, [], {})
    reachable: dict[str, set[str]] = {obj: set() for obj in observed.placements}
    for obj, _, reference in observed.everywhere:
        if reference is not None:
            reachable[obj].add(reference)
    for done, obj in enumerate(observed.placements):
        report_progress("objects", done, len(observed.placements))
        _quantise_object(
            obj, observed, reachable[obj], world, settings, precision, own_precision, quantised
        )
    if settings.orientation_follows_position:
        _follow_positions(quantised, world)
    return quantised


def _follow_positions(quantised: _Quantised, world: DemonstrationWorld) -> None:
    """A thing in a box turns with the box (docs/learning.md): every placement
    whose orientation was its object's own choice takes it, where that choice
    is a tie within the precision (:meth:`_Chooser.following`), from its
    position's reference — or, where that reference's orientation is not part
    of the tie, from the first one up the chain of position references that is
    (an item placed against another item in the box: the box)."""
    for where, open_choice in quantised.open_orientations.items():
        follows = None
        for reference in _position_chain(where, quantised.keys, world):
            follows = open_choice.chooser.following(open_choice.chosen, reference)
            if follows is not None:
                break
        if follows is None:
            continue
        key = quantised.keys[where]
        quantised.keys[where] = replace(
            key,
            orientation_reference=follows.reference,
            orientation_cluster=int(follows.clustering.labels[open_choice.index]),
        )
        quantised.decided[where].update(
            _margins(
                "orientation",
                follows,
                open_choice.chooser.scores,
                open_choice.placement,
                world,
                open_choice.precision,
            )
        )
        quantised.notes.setdefault(where, []).append(open_choice.chooser.follow_note(follows))


def _position_chain(
    where: tuple[int, int], keys: dict[tuple[int, int], _StateKey], world: DemonstrationWorld
) -> list[str]:
    """The position references of placement ``where``, its reference's at the
    reference's own latest placement before it, and so on up to a landmark,
    an unmoved object or an absolute placement."""
    demo, step = where
    chain: list[str] = []
    reference = keys[where].position_reference
    while reference is not None and reference not in chain:
        chain.append(reference)
        history = world.moves[demo].get(reference)
        earlier = [s for s in history[0] if s < step] if history else []
        if not earlier:
            break
        step = earlier[-1]
        reference = keys[(demo, step)].position_reference
    return chain


def _quantise_object(
    obj: str,
    observed: _RelativePlacements,
    reachable: set[str],
    world: DemonstrationWorld,
    settings: StateGenerationSettings,
    precision: Precision,
    own_precision: dict[Kind, dict[str, _Spread]],
    quantised: _Quantised,
) -> None:
    """Paper §IV.A, eq. (2) for one object: its position and orientation
    references scored (:func:`_score_references`) and chosen at each placement
    (:class:`_Chooser`); its placements' state keys and decision margins added
    to ``quantised``."""
    own = observed.placements[obj]
    position_precision = _floored(
        own_precision["position"].get(obj, _Spread(precision.position, precision.position_df)),
        MIN_POSITION_PRECISION,
    )
    orientation_precision = _floored(
        own_precision["orientation"].get(
            obj, _Spread(precision.orientation, precision.orientation_df)
        ),
        MIN_ORIENTATION_PRECISION,
    )
    candidates, relative = observed.candidates[obj], observed.relative
    position_scores = _score_references(
        obj, "position", candidates, settings, position_precision, relative
    )
    orientation_scores = (
        _score_references(obj, "orientation", candidates, settings, orientation_precision, relative)
        if precision.orientation < settings.orientation_separation
        else []  # the demonstrations do not fix orientations: none is learned
    )
    quantised.scores.extend(position_scores + orientation_scores)
    by_position = _Chooser.of(position_scores, reachable, position_precision, settings.significance)
    by_orientation = (
        _Chooser.of(orientation_scores, reachable, orientation_precision, settings.significance)
        if orientation_scores
        else None
    )
    for index, placement in enumerate(own):
        where = (placement.demo, placement.step)
        pos = by_position.at(placement, world)
        quantised.decided[where] = _margins(
            "position", pos, position_scores, placement, world, position_precision.rms
        )
        ori_reference, ori_cluster = None, -1  # orientation unknown
        if by_orientation is not None:
            ori = by_orientation.at(placement, world)
            if ori is by_orientation.own:
                quantised.open_orientations[where] = _OpenOrientation(
                    placement, index, ori, by_orientation, orientation_precision.rms
                )
            ori_reference, ori_cluster = ori.reference, ori.clustering.labels[index]
            quantised.decided[where].update(
                _margins(
                    "orientation",
                    ori,
                    orientation_scores,
                    placement,
                    world,
                    orientation_precision.rms,
                )
            )
        quantised.keys[where] = _StateKey(
            obj, pos.reference, pos.clustering.labels[index], ori_reference, ori_cluster
        )


def _letter_states(
    demonstrations: Sequence[Demonstration], keys: dict[tuple[int, int], _StateKey]
) -> tuple[dict[_StateKey, str], dict[str, list[tuple[int, int]]], tuple[tuple[str, ...], ...]]:
    """States lettered A, B, … in order of first appearance over the
    demonstrations in the order given, steps in order (paper §IV.A); each
    state's members; each demonstration as a sequence of state letters."""
    letters: dict[_StateKey, str] = {}
    members: dict[str, list[tuple[int, int]]] = {}
    sequences: list[tuple[str, ...]] = []
    for d, demo in enumerate(demonstrations):
        sequence = []
        for s in range(len(demo.steps)):
            key = keys[(d, s)]
            if key not in letters:
                letters[key] = state_letters(len(letters))
            sequence.append(letters[key])
            members.setdefault(letters[key], []).append((d, s))
        sequences.append(tuple(sequence))
    return letters, members, tuple(sequences)


def _describe_state(
    key: _StateKey,
    letter: str,
    members: list[tuple[int, int]],
    observed: _RelativePlacements,
    quantised: _Quantised,
) -> State:
    """State ``letter``: its members' relative position and orientation
    summarised (paper §IV.A), and the narrowest margin of each decision taken
    at its members."""
    obj = key.object
    chosen = set(members)
    rows = [i for i, p in enumerate(observed.placements[obj]) if (p.demo, p.step) in chosen]
    position = observed.relative[(obj, "position", key.position_reference)][rows]
    orientation = observed.relative.get((obj, "orientation", key.orientation_reference))
    margins: dict[str, float] = {}
    notes: dict[str, None] = {}
    for member in members:
        for decision, margin in quantised.decided.get(member, {}).items():
            margins[decision] = min(margins.get(decision, math.inf), margin)
        notes.update(dict.fromkeys(quantised.notes.get(member, [])))
    return State(
        id=letter,
        margins=tuple((d, round(m, 3)) for d, m in sorted(margins.items())),
        object=obj,
        position=_position(
            position,
            key.position_reference,
            observed.framed.get((obj, key.position_reference), False),
        ),
        orientation=_orientation(
            None if key.orientation_cluster == -1 or orientation is None else orientation[rows],
            key.orientation_reference,
        ),
        members=tuple(members),
        notes=tuple(notes),
    )


ANYWHERE_PRECISIONS = 5.0
"""An absolute state whose placements scatter (RMS) by at least this many
times the precision — and by at least ``position_separation``, the distance
that tells two places apart — is placed *anywhere* (:func:`_placed_anywhere`)."""


ANYWHERE_EDGE = 0.2
"""A decision whose spread lies within this fraction of the anywhere threshold
(:func:`_placed_anywhere`) is a near call and is told, as a precision tie is."""
ANYWHERE_NOTE = "anywhere"
PLACED_NOTE = "at its place"
"""How the notes on an anywhere decision begin: placed anywhere, or at the mean
of its placements (:func:`_placed_anywhere`)."""


def _placed_anywhere(
    states: list[State],
    types: dict[str, str],
    precision: Precision,
    settings: StateGenerationSettings,
) -> list[State]:
    """``states``, those placed anywhere on their support marked so: absolute
    states whose placements scatter (RMS) by at least ``position_separation``,
    the distance that tells two places apart, and at least
    :data:`ANYWHERE_PRECISIONS` times the precision, with no reference
    explaining them (one was chosen otherwise) — a tray put down at a
    different place in every demonstration is not meant to go to the mean of
    them. The same reading as the paper's eq. (2) stopping at one cluster: the
    placements are not one place, and no more states are supported.

    The roles of one type (``plate#1``, ``plate#2``: identical objects, laid
    the same way) are decided together, on their pooled spread: one plate
    learned *anywhere* at 54 mm and the other at its place at 44 mm was two
    rules for one way of laying a table. A decision whose spread lies within
    :data:`ANYWHERE_EDGE` of the threshold, or that the pooling turned for one
    of the roles, is told in the notes of every state it decided, as a
    precision tie is."""
    threshold = max(settings.position_separation, ANYWHERE_PRECISIONS * precision.position)
    groups: dict[tuple[str, str], list[int]] = {}
    for index, state in enumerate(states):
        if state.position.reference is None and len(state.members) >= 2:
            kind = types.get(state.object)
            key = (kind, "") if kind is not None else (state.object, state.id)
            groups.setdefault(key, []).append(index)
    for key, indices in list(groups.items()):  # one role alone: each state by itself
        if len(indices) > 1 and len({states[i].object for i in indices}) == 1:
            del groups[key]
            groups.update({(key[0], states[i].id): [i] for i in indices})
    out = list(states)
    for (kind, _), indices in groups.items():
        dof = sum(len(states[i].members) - 1 for i in indices)
        pooled = math.sqrt(
            sum((len(states[i].members) - 1) * states[i].position.spread for i in indices) / dof
        )
        anywhere = pooled >= threshold
        near = abs(pooled - threshold) <= ANYWHERE_EDGE * threshold
        turned = any((states[i].position.spread >= threshold**2) != anywhere for i in indices)
        for i in indices:
            state = states[i]
            own = math.sqrt(state.position.spread)
            if anywhere:
                state = _anywhere(state, settings)
            if near or turned:
                text = ANYWHERE_NOTE if anywhere else PLACED_NOTE
                if len(indices) > 1:
                    text += f", as every {kind}: their pooled spread {1000 * pooled:.1f} mm"
                    text += f" (its own {1000 * own:.1f} mm)"
                else:
                    text += f": spread {1000 * own:.1f} mm"
                text += (
                    f", within {100 * ANYWHERE_EDGE:.0f} % of the {1000 * threshold:.1f} mm "
                    "from which placements are anywhere"
                    if near
                    else f"; anywhere from {1000 * threshold:.1f} mm"
                )
                state = replace(state, notes=(*state.notes, text))
            out[i] = state
    return out


def _anywhere(state: State, settings: StateGenerationSettings) -> State:
    """``state`` placed anywhere on its support (:func:`_placed_anywhere`). Its
    orientation, if absolute and as scattered (RMS at least
    ``orientation_separation``, as the whole model's orientations are dropped
    beyond it), is dropped too."""
    orientation = state.orientation
    if (
        orientation.reference is None
        and orientation.value is not None
        and math.sqrt(orientation.spread) >= settings.orientation_separation
    ):
        orientation = StateOrientation(reference=None, value=None, spread=orientation.spread)
    return replace(state, position=replace(state.position, anywhere=True), orientation=orientation)


def state_letters(index: int) -> str:
    """0 → ``A``, 25 → ``Z``, 26 → ``AA``, 27 → ``AB``, … (docs/formats.md)."""
    letters = ""
    index += 1
    while index:
        index, rest = divmod(index - 1, 26)
        letters = chr(ord("A") + rest) + letters
    return letters


def _relative_table(
    obj: str,
    kind: Kind,
    own: list[_Placement],
    candidates: list[str | None],
    world: DemonstrationWorld,
    relative: dict[tuple[str, Kind, str | None], np.ndarray],
    framed: dict[tuple[str, str | None], bool],
) -> None:
    """``obj``'s placements relative to every candidate defined at all of them."""
    if kind == "orientation" and any(p.pose.orientation is None for p in own):
        if any(p.pose.orientation is not None for p in own):
            logger.warning(
                "%s has an orientation in some steps but not in others; its orientation "
                "is not learned (give one in every step, or in none)",
                obj,
            )
        return
    for reference in candidates:
        values, in_frame = _relative_values(kind, obj, own, reference, world)
        if values is not None:
            relative[(obj, kind, reference)] = values
            if kind == "position":
                framed[(obj, reference)] = in_frame
