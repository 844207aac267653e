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
the whole method.
"""

from __future__ import annotations

import logging
import math
from bisect import bisect_left
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Literal, NamedTuple

import numpy as np

from demoplan import rotations
from demoplan.budget import report_progress
from demoplan.learning.clustering import (
    CONSISTENCY_LEVEL,
    UNBOUNDED_DF,
    Clustering,
    PositionSpace,
    RotationSpace,
    Space,
    closest_pair,
    cluster_stats,
    f_critical,
    kmeans_batch,
    outscores,
    select_clusterings,
    spread_of,
)
from demoplan.learning.regions import with_regions
from demoplan.learning.settings import LearningSettings as StateGenerationSettings
from demoplan.model import (
    Demonstration,
    Pose,
    State,
    StateOrientation,
    StatePosition,
    demonstrated_shapes,
    yaw_period,
)

__all__ = [
    "Precision",
    "ReferenceScore",
    "StateGeneration",
    "StateGenerationSettings",
    "estimate_precision",
    "generate_states",
    "state_letters",
]

Kind = Literal["position", "orientation"]
KINDS: tuple[Kind, ...] = ("position", "orientation")

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class ReferenceScore:
    """How well one candidate reference explains one object's placements.

    ``reference`` is ``None`` for absolute; ``distance`` is the mean distance
    (m, or degrees for orientation) between object and reference, used to
    break ties towards the nearest reference.
    """

    object: str
    kind: Kind
    reference: str | None
    clustering: Clustering
    distance: float

    @property
    def rms(self) -> float:
        return math.sqrt(self.clustering.score)


@dataclass(frozen=True, slots=True)
class StateGeneration:
    """States, each demonstration as a state sequence, and the scores behind them."""

    states: tuple[State, ...]
    sequences: tuple[tuple[str, ...], ...]
    scores: tuple[ReferenceScore, ...]
    precision: Precision


@dataclass(frozen=True, slots=True)
class Precision:
    """The placement precision decisions were measured against (RMS; m and degrees)
    and whether each was estimated from the demonstrations or set by the user."""

    position: float
    orientation: float
    position_estimated: bool = True
    orientation_estimated: bool = True
    position_df: float = UNBOUNDED_DF
    """Degrees of freedom of the estimate (unbounded where the user set it)."""
    orientation_df: float = UNBOUNDED_DF


class _Spread(NamedTuple):
    """An RMS spread (m or degrees) and the degrees of freedom it was measured with."""

    rms: float
    df: float


LOCAL_EVIDENCE = 0.02
"""A reference available at some of an object's placements only adds a state
there: its F test is taken at the significance level divided by the number of
such candidates at that step (Bonferroni), and at most this fraction of it
(0.05 → 0.001), so that one of many such candidates agreeing by chance does
not; and never from two placements."""

OWN_PRECISION_DF = 6
"""Degrees of freedom from which an object's own tightest spread may be its
precision (four placements on a table): fewer agree as closely as chance
makes them (:func:`_own_precisions`)."""
SIMILAR_PRECISION = 2.0
"""An object's own precision counts where another object's lies within this
factor of it (:func:`_own_precisions`)."""
MIN_POSITION_PRECISION = 1e-4  # m: noise-free data still has a scale for ties
MIN_ORIENTATION_PRECISION = 0.05  # deg
FALLBACK_PRECISION = (0.003, 0.5)  # m, deg: when no object was placed twice


@dataclass(frozen=True, slots=True)
class _StateKey:
    """What makes a state: object, position reference and cluster, orientation
    reference and cluster (cluster −1: orientation unknown)."""

    object: str
    position_reference: str | None
    position_cluster: int
    orientation_reference: str | None
    orientation_cluster: int


@dataclass(frozen=True, slots=True)
class _Placement:
    demo: int
    step: int
    pose: Pose


class DemonstrationWorld:
    """Per-demonstration lookup of where every object and landmark was."""

    def __init__(self, demonstrations: Sequence[Demonstration]):
        # Per demonstration and object: the step indices of its moves, and its poses.
        self.moves: list[dict[str, tuple[list[int], list[Pose]]]] = []
        self.landmarks = [d.landmark_poses() for d in demonstrations]
        self.initial = [d.initial_poses() for d in demonstrations]
        self.geometry = demonstrated_shapes(demonstrations)
        for demo in demonstrations:
            moves: dict[str, tuple[list[int], list[Pose]]] = {}
            for index, step in enumerate(demo.steps):
                steps, poses = moves.setdefault(step.object, ([], []))
                steps.append(index)
                poses.append(step.pose)
            self.moves.append(moves)

    def pose(self, demo: int, name: str, step: int) -> Pose | None:
        """``name``'s placement when ``step`` happens (docs/learning.md).

        The placement current at the step; for an object placed only after the
        step, its first placement; for one never moved, its initial pose.
        """
        if name in self.landmarks[demo]:
            return self.landmarks[demo][name]
        history = self.moves[demo].get(name)
        if history:
            steps, poses = history
            moved_before = bisect_left(steps, step)
            return poses[moved_before - 1] if moved_before else poses[0]
        return self.initial[demo].get(name)

    def yaw_period(self, name: str | None) -> float:
        """``name``'s symmetry about its own z axis (deg; 0: any turn); 360° (none)
        where its geometry is unknown, and for a landmark: its yaw is given, not
        tracked, so its frame is the one given (a tray has a front, whatever
        its shape's symmetry)."""
        if name is None or any(name in landmarks for landmarks in self.landmarks):
            return 360.0
        return yaw_period(self.geometry.get(name))

    def own_symmetry(self, name: str, quats: np.ndarray) -> np.ndarray:
        """``name``'s orientations (absolute or relative to a reference) compared
        modulo its shape's symmetry: a box's half turns about its axes (and quarter
        turns where two extents agree), a cylinder's turns about its axis and
        flip, a sphere's every turn; none for other or unknown shapes."""
        shape = self.geometry.get(name)
        if shape is None or shape.shape not in {"box", "cylinder", "sphere"}:
            return quats
        if shape.shape == "sphere":
            return np.tile([0.0, 0.0, 0.0, 1.0], (len(quats), 1))
        if shape.shape == "cylinder":
            return rotations.axis_modulo_flip(quats)
        return rotations.modulo_group(quats, rotations.box_symmetries(shape.size))

    def available(self, demo: int, name: str, step: int) -> bool:
        """Whether ``name`` may serve as a reference at ``step`` of ``demo``."""
        if name in self.landmarks[demo]:
            return True
        history = self.moves[demo].get(name)
        if history:
            return history[0][0] < step
        return name in self.initial[demo]


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
FOLLOWS_NOTE = "turns with "
"""How a note on an orientation that follows its position's reference begins
(:meth:`_Chooser.follow_note`)."""


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


def estimate_precision(
    relative: dict[tuple[str, Kind, str | None], np.ndarray],
    settings: StateGenerationSettings,
) -> Precision:
    """The placement precision of the demonstrations (docs/learning.md), unless set.

    For every object placed at least twice, the RMS spread of its placements
    relative to the candidate that explains them best as one cluster (the
    lowest trace of the sample covariance over absolute, the landmarks and
    the objects placed before it in every demonstration — ``relative`` holds
    just those: the best of many candidates that were never available would
    be low by chance); the precision is the median of these over the
    objects (the lower one of an even count: with two objects, the more
    precise). An object placed where it is meant to go, relative to what it is
    meant to go with, scatters by the teacher's precision; the median keeps
    objects with several places (whose best single cluster is wide) from
    inflating it. A virtual environment gives well under a millimetre,
    people teleoperating a robot centimetres. Without any object placed
    twice, :data:`FALLBACK_PRECISION`.
    """
    return _precision({kind: _tightest(relative, kind, settings) for kind in KINDS}, settings)


def _precision(
    tightest: dict[Kind, dict[str, _Spread]], settings: StateGenerationSettings
) -> Precision:
    """:func:`estimate_precision` from each object's tightest spread, per kind; with
    the degrees of freedom of the median one (an estimate from that object's
    placements, not the truth)."""
    found: dict[Kind, _Spread] = {}
    for kind, best in tightest.items():
        fallback = FALLBACK_PRECISION[0 if kind == "position" else 1]
        ranked = sorted(best.values())
        found[kind] = ranked[(len(ranked) - 1) // 2] if ranked else _Spread(fallback, UNBOUNDED_DF)
    position = _floored(found["position"], MIN_POSITION_PRECISION)
    orientation = _floored(found["orientation"], MIN_ORIENTATION_PRECISION)
    set_position, set_orientation = settings.position_noise, settings.orientation_noise
    return Precision(
        position=position.rms if set_position is None else set_position,
        orientation=orientation.rms if set_orientation is None else set_orientation,
        position_estimated=set_position is None,
        orientation_estimated=set_orientation is None,
        position_df=position.df if set_position is None else UNBOUNDED_DF,
        orientation_df=orientation.df if set_orientation is None else UNBOUNDED_DF,
    )


def _own_precisions(
    tightest: dict[str, _Spread], median: float, median_df: float
) -> dict[str, _Spread]:
    """The precision each object's decisions are judged by.

    The median object's (:func:`estimate_precision`), or the object's own
    tightest spread where that is lower — red stands on wood to 0.6 mm while
    wood and green scatter by centimetres (the shipped blocks) — or where the
    object's own is measured (:data:`OWN_PRECISION_DF`) and another object is
    placed about as precisely (:data:`SIMILAR_PRECISION`): a task may mix
    objects put down to 2 mm relative to others with objects put on spots to
    2 cm, and one median precision would judge half of them wrongly. An
    object alone at its precision is judged by the median: a can put
    anywhere on the table that happened to land in two regions 80 cm apart
    is not two places of 8 cm while everything else is placed to 2 mm.
    """
    common = _Spread(median, median_df)
    own: dict[str, _Spread] = {}
    for obj, spread in tightest.items():
        confirmed = spread.df >= OWN_PRECISION_DF and any(
            spread.rms / SIMILAR_PRECISION <= other.rms <= spread.rms * SIMILAR_PRECISION
            for name, other in tightest.items()
            if name != obj
        )
        own[obj] = spread if confirmed else min(spread, common)
    return own


def _floored(spread: _Spread, least: float) -> _Spread:
    """``spread`` raised to at least ``least`` — noise-free data still have a scale
    for ties — and then known exactly (no degrees of freedom to doubt it by)."""
    return spread if spread.rms >= least else _Spread(least, UNBOUNDED_DF)


def _tightest(
    relative: dict[tuple[str, Kind, str | None], np.ndarray],
    kind: Kind,
    settings: StateGenerationSettings,
) -> dict[str, _Spread]:
    """Per object placed at least twice: its RMS spread relative to the candidate
    that explains it best (``relative`` holds the candidates), and its degrees
    of freedom, (placements − 1) × the axes they vary along. For positions a
    few well-separated places count too (:func:`_grouped_spreads`): an object
    put in one of two slots 15 cm apart scatters by its teacher's precision
    within each slot, not by 75 mm — which, as the median of three objects,
    was once the precision and merged the slots."""
    by_object: dict[str, list[np.ndarray]] = {}
    for (obj, what, _), values in relative.items():
        if what == kind and len(values) >= 2:
            by_object.setdefault(obj, []).append(values)
    best: dict[str, _Spread] = {}
    for obj, candidates in by_object.items():
        for values in candidates:
            space: Space = PositionSpace(values) if kind == "position" else RotationSpace(values)
            _, spread = space.stats(np.arange(len(values)))
            found = _Spread(math.sqrt(spread), (len(values) - 1) * space.dims)
            if obj not in best or found < best[obj]:
                best[obj] = found
        if kind == "position":
            grouped = _grouped_spreads(np.stack(candidates), settings)
            if grouped is not None and grouped < best[obj]:
                best[obj] = grouped
    return best


GROUP_GAP = 4.0
"""Groups of placements count as separate places in the precision estimate only
where every two centres lie at least this many pooled RMS spreads apart (and at
least ``position_separation``): two slots 11 cm apart, each scattered by 2 cm,
do; a continuum cut by K-means does not (neighbouring pieces of a uniform
stretch lie about 3.5 RMS apart)."""
GROUP_MAX_PLACES = 3
"""At most this many places per object in the precision estimate."""


def _grouped_spreads(candidates: np.ndarray, settings: StateGenerationSettings) -> _Spread | None:
    """The lowest pooled within-group RMS spread of one object's positions ``(B, n,
    3)`` (relative to B candidates) split into 2..:data:`GROUP_MAX_PLACES`
    groups of at least two placements whose centres lie :data:`GROUP_GAP`
    spreads apart and that one cluster explains far worse (an F test at
    ``CONSISTENCY_LEVEL``); ``None`` where no split qualifies. Degrees of freedom:
    (placements − groups) × varying axes. One batched K-means per group count."""
    _, n, _ = candidates.shape
    best: _Spread | None = None
    generator = np.random.default_rng(settings.seed)
    for c in range(2, min(GROUP_MAX_PLACES, n // 2) + 1):
        labels = kmeans_batch(candidates, c, settings.n_init, 100, generator)
        for values, label in zip(candidates, labels, strict=True):
            sizes = np.bincount(label, minlength=c)
            if sizes.min() < 2:
                continue
            space = PositionSpace(values)
            centres, spreads = cluster_stats(space, label, c)
            pooled = sum((k - 1) * v for k, v in zip(sizes, spreads, strict=True)) / (n - c)
            gap = max(settings.position_separation, GROUP_GAP * math.sqrt(pooled))
            if closest_pair(space.distance, centres) < gap:
                continue
            # ... and only where the groups explain the placements far better than
            # one cluster does (an F test at 0.1 %): four or six placements of one
            # spot fall into two tight-looking groups often enough by chance.
            df_one, df_groups = (n - 1) * space.dims, (n - c) * space.dims
            if spread_of(values) < f_critical(CONSISTENCY_LEVEL, df_one, df_groups) * pooled:
                continue
            found = _Spread(math.sqrt(pooled), df_groups)
            if best is None or found < best:
                best = found
    return best


def _score_references(
    obj: str,
    kind: Kind,
    candidates: list[str | None],
    settings: StateGenerationSettings,
    precision: _Spread,
    relative: dict[tuple[str, Kind, str | None], np.ndarray],
) -> list[ReferenceScore]:
    """Eq. (2) for every candidate reference that is defined at every placement."""
    separation = (
        settings.position_separation if kind == "position" else settings.orientation_separation
    )
    references: list[str | None] = []
    spaces: list[Space] = []
    for reference in candidates:
        values = relative.get((obj, kind, reference))
        if values is None:
            continue
        references.append(reference)
        spaces.append(PositionSpace(values) if kind == "position" else RotationSpace(values))
    if not spaces:
        return []
    clusterings = select_clusterings(
        spaces,
        separation=separation,
        noise=precision.rms,
        noise_df=precision.df,
        n_init=settings.n_init,
        seed=settings.seed,
        max_clusters=settings.max_clusters,
        significance=settings.significance,
    )
    return [
        ReferenceScore(obj, kind, reference, clustering, _mean_distance(kind, space.values))
        for reference, space, clustering in zip(references, spaces, clusterings, strict=True)
    ]


def _relative_values(
    kind: Kind, obj: str, own: list[_Placement], reference: str | None, world: DemonstrationWorld
) -> tuple[np.ndarray | None, bool]:
    """``obj``'s placements relative to ``reference`` (docs/learning.md): positions in the
    reference's frame where it has an orientation at every placement (turned
    back by its orientation, taken modulo its symmetry), else in world axes;
    orientations ``R_ref⁻¹·R_obj``, modulo ``obj``'s own symmetry. Returns the
    values (``None`` where the reference is not defined at every placement)
    and whether positions are in the reference's frame."""
    ref_poses = [None if reference is None else world.pose(p.demo, reference, p.step) for p in own]
    if reference is not None and any(r is None for r in ref_poses):
        return None, False
    ref_quats: np.ndarray | None = None
    oriented = all(r is not None and r.orientation is not None for r in ref_poses)
    if reference is not None and oriented:
        # The reference's frame modulo its symmetry: in every demonstration the
        # copy in which the object's placements agree (a kit tray at 10° and at
        # 170° is one frame for what lies on it), for positions and
        # orientations alike.
        positions = np.array([p.pose.position for p in own], dtype=float)
        centres = np.array([r.position for r in ref_poses if r is not None], dtype=float)
        ref_quats = rotations.frames_agreeing(
            np.array([r.orientation for r in ref_poses if r is not None], dtype=float),
            positions - centres,
            world.yaw_period(reference),
        )
    if kind == "position":
        positions = np.array([p.pose.position for p in own], dtype=float)
        if reference is None:
            return positions, False
        offsets = positions - np.array([r.position for r in ref_poses if r is not None])
        if ref_quats is None:
            return np.asarray(offsets, dtype=float), False
        return rotations.rotate_vectors(rotations.quat_inverse(ref_quats), offsets), True
    quats = np.array([p.pose.orientation for p in own], dtype=float)
    if reference is not None:
        if ref_quats is None:
            return None, False
        quats = rotations.relative_quats(ref_quats, quats)
    return world.own_symmetry(obj, quats), False


def _mean_distance(kind: Kind, values: np.ndarray) -> float:
    if kind == "position":
        return float(np.linalg.norm(values, axis=1).mean())
    return float(np.degrees(2.0 * np.arccos(np.clip(np.abs(values[:, 3]), 0.0, 1.0))).mean())


@dataclass(frozen=True, slots=True)
class _Chooser:
    """One object's reference choice for one kind (docs/learning.md).

    First the object's **own** choice among the candidates available at every
    one of its placements (absolute, landmarks, objects always placed before
    it — a choice that adds no state): the best-scoring one and those it does
    not outscore (:func:`~demoplan.learning.clustering.outscores`) are tied,
    and the tie goes to fewer clusters, then to absolute, then to the nearest
    reference (a nut to the peg it sits on, not to the other peg that moves
    with it). A placement takes another reference — one available only at its
    step — only where that reference outscores the object's own choice and
    the best of those (:meth:`at`). So the fork is placed relative to the
    glass only where the glass stands already *and* explains it better than
    the plate does everywhere (Table II, state J).
    """

    scores: list[ReferenceScore]
    own: ReferenceScore
    best: ReferenceScore
    everywhere: set[str]
    noise: _Spread
    significance: float

    @classmethod
    def of(
        cls,
        scores: list[ReferenceScore],
        everywhere: set[str],
        noise: _Spread,
        significance: float,
    ) -> _Chooser:
        steady = [s for s in scores if s.reference is None or s.reference in everywhere]
        best = min(steady, key=lambda s: s.clustering.score)
        own = min(
            (s for s in steady if not _beats(best, s, noise, significance)),
            key=lambda s: (
                s.clustering.n_clusters,
                s.reference is not None,
                s.distance,
                s.reference or "",
            ),
        )
        return cls(scores, own, best, everywhere, noise, significance)

    def at(self, placement: _Placement, world: DemonstrationWorld) -> ReferenceScore:
        """The reference of one placement: the object's own choice, or a reference
        available only at its step that outscores it (the best of those; ties:
        fewer clusters, then the nearest reference)."""
        candidates = [
            s
            for s in self.scores
            if s.reference is not None
            and s.reference not in self.everywhere
            and world.available(placement.demo, s.reference, placement.step)
        ]
        # Bonferroni over the candidates, and at most LOCAL_EVIDENCE of the level;
        # and never from two placements: their spread can be as small as chance makes it.
        level = self.significance * min(LOCAL_EVIDENCE, 1.0 / max(1, len(candidates)))
        if self.significance > 0 and len(self.own.clustering.labels) < 3:
            return self.own
        local = [
            s
            for s in candidates
            if _beats(s, self.own, self.noise, level, local=True)
            and _beats(s, self.best, self.noise, level, local=True)
        ]
        if not local:
            return self.own
        top = min(local, key=lambda s: s.clustering.score)
        return min(
            (s for s in local if not _beats(top, s, self.noise, self.significance)),
            key=lambda s: (s.clustering.n_clusters, s.distance, s.reference or ""),
        )

    def following(self, chosen: ReferenceScore, reference: str | None) -> ReferenceScore | None:
        """An orientation that follows its position's ``reference`` (docs/learning.md,
        *A thing in a box turns with the box*): where the orientation's own
        choice ``chosen`` is a tie within the precision that ``reference`` is part
        of — neither the best-scoring reference nor ``chosen`` outscores it,
        with no more clusters — the orientation is taken relative to the same
        reference as the position. ``None`` where the data decided (the
        reference turned between demonstrations and explains the orientations
        worse), where the choice was a reference available at this step only,
        or where ``reference`` has no orientation to follow."""
        if reference is None or chosen is not self.own or chosen.reference == reference:
            return None
        same = next((s for s in self.scores if s.reference == reference), None)
        if (
            same is None
            or same.clustering.n_clusters > chosen.clustering.n_clusters
            or _beats(self.best, same, self.noise, self.significance)
            or _beats(chosen, same, self.noise, self.significance)
        ):
            return None
        return same

    def follow_note(self, follows: ReferenceScore) -> str:
        """The words for an orientation that :meth:`following` took from its position's
        reference: *never seen turned* where the world explains the orientations
        as well to within the precision (the reference kept its yaw as far as the
        precision tells); *not told apart from the world* where it explains them
        worse by more than the precision but not by the F test (too few
        demonstrations: two need a 19-fold variance); else a tie with another
        reference."""
        absolute = next((s for s in self.scores if s.reference is None), None)
        if absolute is not None and _tied(absolute, follows, self.noise, self.significance):
            if abs(absolute.rms - follows.rms) < self.noise.rms:
                return f"{FOLLOWS_NOTE}{follows.reference}: never seen turned"
            return (
                f"{FOLLOWS_NOTE}{follows.reference}: not told apart from the world by "
                "these demonstrations"
            )
        return f"{FOLLOWS_NOTE}{follows.reference}: a tie within the precision"


def _tied(a: ReferenceScore, b: ReferenceScore, noise: _Spread, significance: float) -> bool:
    """Neither of two references outscores the other (:func:`_beats`)."""
    return not _beats(a, b, noise, significance) and not _beats(b, a, noise, significance)


def _beats(
    better: ReferenceScore,
    worse: ReferenceScore,
    noise: _Spread,
    significance: float,
    *,
    local: bool = False,
) -> bool:
    """:func:`~demoplan.learning.clustering.outscores` for two references; a
    ``local`` one (available at some placements only, adding states there)
    must win by the F test against the other reference alone — it never wins
    because the other one scatters beyond the precision: one of many such
    candidates explains an outlier better by chance."""
    return outscores(
        (worse.clustering.score, worse.clustering.df),
        (better.clustering.score, better.clustering.df),
        noise=noise.rms,
        significance=significance,
        noise_df=noise.df,
        against_precision=not local,
    )


def _margins(
    kind: Kind,
    chosen: ReferenceScore,
    scores: list[ReferenceScore],
    placement: _Placement,
    world: DemonstrationWorld,
    precision: float,
) -> dict[str, float]:
    """How far each decision of one placement was from going the other way, in units
    of the precision: the runner-up reference's RMS spread minus the chosen one's
    (negative: a lower-spread reference was set aside as a tie, for fewer
    states), and the nearest other cluster count's minus the chosen count's."""
    out: dict[str, float] = {}
    others = [
        s.rms
        for s in scores
        if s is not chosen
        and (s.reference is None or world.available(placement.demo, s.reference, placement.step))
    ]
    if others:
        out[f"{kind} reference"] = (min(others) - chosen.rms) / precision
    counts = [
        math.sqrt(score)
        for c, score in chosen.clustering.tried
        if score is not None and c != chosen.clustering.n_clusters
    ]
    if counts:
        out[f"{kind} clusters"] = (min(counts) - chosen.rms) / precision
    return out


def _position(values: np.ndarray, reference: str | None, in_frame: bool) -> StatePosition:
    """A state's mean relative position and its spread (members only)."""
    mean, spread = PositionSpace(values).stats(np.arange(len(values)))
    x, y, z = (float(v) for v in mean)
    return StatePosition(
        reference=reference, value=(x, y, z), spread=spread, in_reference_frame=in_frame
    )


def _orientation(values: np.ndarray | None, reference: str | None) -> StateOrientation:
    """A state's mean relative orientation and its spread; unknown when ``values`` is None."""
    if values is None:
        return StateOrientation(reference=None, value=None, spread=0.0)
    mean, spread = RotationSpace(values).stats(np.arange(len(values)))
    qx, qy, qz, qw = mean
    return StateOrientation(reference=reference, value=(qx, qy, qz, qw), spread=spread)
