"""State generation (paper §IV.A, eq. 1–2; SPEC §5).

Every step of every demonstration is a *placement* of one object. For each
object, every candidate reference — absolute, every other object, every
landmark — is scored: the object's placements are expressed relative to the
candidate (x_i − x_j, or R_j⁻¹·R_i for orientations) and clustered with
K-means for c = 1..N (:func:`demoplan.clustering.select_clustering`, eq. 2).
Each placement then takes, among the candidates *available at that step*
(absolute, landmarks, objects already moved in that demonstration), the one
with the lowest score — "positions can only be specified towards already
placed objects". Ties (scores whose RMS differs by less than the measurement
noise) go to fewer clusters, then to absolute, then to the nearest reference.

Position and orientation choose their references independently. A state is
(object, position reference and cluster, orientation reference and cluster);
states are lettered A, B, … in order of first appearance over the
demonstrations in the order given, steps in order.
"""

from __future__ import annotations

import logging
import math
from bisect import bisect_left
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from demoplan import rotations
from demoplan.learning.clustering import (
    Clustering,
    PositionSpace,
    RotationSpace,
    Space,
    select_clusterings,
)
from demoplan.learning.settings import LearningSettings as StateGenerationSettings
from demoplan.model import Demonstration, Pose, State, StateOrientation, StatePosition

__all__ = [
    "ReferenceScore",
    "StateGeneration",
    "StateGenerationSettings",
    "generate_states",
    "state_letters",
]

Kind = Literal["position", "orientation"]

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


class _World:
    """Per-demonstration lookup of where every object and landmark was."""

    def __init__(self, demonstrations: Sequence[Demonstration]):
        # Per demonstration and object: the step indices of its moves, and its poses.
        self.moves: list[dict[str, tuple[list[int], list[Pose]]]] = []
        self.landmarks = [d.landmark_poses() for d in demonstrations]
        self.initial = [d.initial_poses() for d in demonstrations]
        for demo in demonstrations:
            moves: dict[str, tuple[list[int], list[Pose]]] = {}
            for index, step in enumerate(demo.steps):
                steps, poses = moves.setdefault(step.object, ([], []))
                steps.append(index)
                poses.append(step.pose)
            self.moves.append(moves)

    def pose(self, demo: int, name: str, step: int) -> Pose | None:
        """``name``'s placement when ``step`` happens (SPEC §5).

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
    """
    settings = settings or StateGenerationSettings()
    world = _World(demonstrations)
    placements: dict[str, list[_Placement]] = {}
    for d, demo in enumerate(demonstrations):
        for s, step in enumerate(demo.steps):
            placements.setdefault(step.object, []).append(_Placement(d, s, step.pose))
    names = sorted(
        set(placements)
        | {name for demo in demonstrations for name, _ in demo.landmarks}
        | {name for demo in demonstrations for name, _ in demo.initial}
    )

    keys: dict[tuple[int, int], _StateKey] = {}
    relative: dict[tuple[str, Kind, str | None], np.ndarray] = {}
    all_scores: list[ReferenceScore] = []
    for obj, own in placements.items():
        candidates = [None, *(n for n in names if n != obj)]
        position_scores = _score_references(
            obj, "position", own, candidates, world, settings, relative
        )
        orientation_scores = _score_references(
            obj, "orientation", own, candidates, world, settings, relative
        )
        all_scores += position_scores + orientation_scores
        for index, placement in enumerate(own):
            pos = _choose(position_scores, placement, world, settings.position_noise)
            ori_reference, ori_cluster = None, -1  # orientation unknown
            if orientation_scores:
                ori = _choose(orientation_scores, placement, world, settings.orientation_noise)
                ori_reference, ori_cluster = ori.reference, ori.clustering.labels[index]
            keys[(placement.demo, placement.step)] = _StateKey(
                obj, pos.reference, pos.clustering.labels[index], ori_reference, ori_cluster
            )

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

    states = []
    for key, letter in letters.items():
        obj = key.object
        chosen = set(members[letter])
        rows = [i for i, p in enumerate(placements[obj]) if (p.demo, p.step) in chosen]
        position = relative[(obj, "position", key.position_reference)][rows]
        orientation = relative.get((obj, "orientation", key.orientation_reference))
        states.append(
            State(
                id=letter,
                object=obj,
                position=_position(position, key.position_reference),
                orientation=_orientation(
                    None
                    if key.orientation_cluster == -1 or orientation is None
                    else orientation[rows],
                    key.orientation_reference,
                ),
                members=tuple(members[letter]),
            )
        )
    return StateGeneration(tuple(states), tuple(sequences), tuple(all_scores))


def state_letters(index: int) -> str:
    """0 → ``A``, 25 → ``Z``, 26 → ``AA``, 27 → ``AB``, … (SPEC §3)."""
    letters = ""
    index += 1
    while index:
        index, rest = divmod(index - 1, 26)
        letters = chr(ord("A") + rest) + letters
    return letters


def _score_references(
    obj: str,
    kind: Kind,
    own: list[_Placement],
    candidates: list[str | None],
    world: _World,
    settings: StateGenerationSettings,
    relative: dict[tuple[str, Kind, str | None], np.ndarray],
) -> list[ReferenceScore]:
    """Eq. (2) for every candidate reference that is defined at every placement."""
    if kind == "orientation" and any(p.pose.orientation is None for p in own):
        if any(p.pose.orientation is not None for p in own):
            logger.warning(
                "%s has an orientation in some steps but not in others; its orientation "
                "is not learned (give one in every step, or in none)",
                obj,
            )
        return []
    noise = settings.position_noise if kind == "position" else settings.orientation_noise
    separation = (
        settings.position_separation if kind == "position" else settings.orientation_separation
    )
    references: list[str | None] = []
    spaces: list[Space] = []
    for reference in candidates:
        values = _relative_values(kind, own, reference, world)
        if values is None:
            continue
        relative[(obj, kind, reference)] = values
        references.append(reference)
        spaces.append(PositionSpace(values) if kind == "position" else RotationSpace(values))
    clusterings = select_clusterings(
        spaces,
        separation=separation,
        noise=noise,
        n_init=settings.n_init,
        seed=settings.seed,
        max_clusters=settings.max_clusters,
    )
    return [
        ReferenceScore(obj, kind, reference, clustering, _mean_distance(kind, space.values))
        for reference, space, clustering in zip(references, spaces, clusterings, strict=True)
    ]


def _relative_values(
    kind: Kind, own: list[_Placement], reference: str | None, world: _World
) -> np.ndarray | None:
    if kind == "position":
        positions = np.array([p.pose.position for p in own], dtype=float)
        if reference is None:
            return positions
        ref_poses = [world.pose(p.demo, reference, p.step) for p in own]
        if any(r is None for r in ref_poses):
            return None
        reference_positions = np.array([r.position for r in ref_poses if r is not None])
        return np.asarray(positions - reference_positions, dtype=float)
    quats = np.array([p.pose.orientation for p in own], dtype=float)
    if reference is None:
        return quats
    ref_quats = []
    for p in own:
        pose = world.pose(p.demo, reference, p.step)
        if pose is None or pose.orientation is None:
            return None
        ref_quats.append(pose.orientation)
    return rotations.relative_quats(np.array(ref_quats, dtype=float), quats)


def _mean_distance(kind: Kind, values: np.ndarray) -> float:
    if kind == "position":
        return float(np.linalg.norm(values, axis=1).mean())
    return float(np.degrees(2.0 * np.arccos(np.clip(np.abs(values[:, 3]), 0.0, 1.0))).mean())


def _choose(
    scores: list[ReferenceScore], placement: _Placement, world: _World, noise: float
) -> ReferenceScore:
    """The reference of one placement: the best-scoring candidate available at its step."""
    available = [
        s
        for s in scores
        if s.reference is None or world.available(placement.demo, s.reference, placement.step)
    ]
    best = min(s.rms for s in available)
    tied = [s for s in available if s.rms - best < noise]
    return min(
        tied,
        key=lambda s: (
            s.clustering.n_clusters,
            s.reference is not None,
            s.distance,
            s.reference or "",
        ),
    )


def _position(values: np.ndarray, reference: str | None) -> StatePosition:
    """A state's mean relative position and its spread (members only)."""
    mean, spread = PositionSpace(values).stats(np.arange(len(values)))
    x, y, z = (float(v) for v in mean)
    return StatePosition(reference=reference, value=(x, y, z), spread=spread)


def _orientation(values: np.ndarray | None, reference: str | None) -> StateOrientation:
    """A state's mean relative orientation and its spread; unknown when ``values`` is None."""
    if values is None:
        return StateOrientation(reference=None, value=None, spread=0.0)
    mean, spread = RotationSpace(values).stats(np.arange(len(values)))
    qx, qy, qz, qw = mean
    return StateOrientation(reference=reference, value=(qx, qy, qz, qw), spread=spread)
