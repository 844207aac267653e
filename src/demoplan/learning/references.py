"""Which reference explains an object's placements best (paper §IV.A: absolute
placement or relative to another object, by position and by orientation): the
candidates' clusterings scored and compared, ties within the precision going to
the nearest reference."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from demoplan import rotations
from demoplan.learning.clustering import (
    Clustering,
    PositionSpace,
    RotationSpace,
    Space,
    outscores,
    select_clusterings,
)
from demoplan.learning.precision import Kind, _Spread
from demoplan.learning.settings import LearningSettings as StateGenerationSettings
from demoplan.learning.world import DemonstrationWorld, _Placement
from demoplan.model import (
    StateOrientation,
    StatePosition,
)

__all__ = ["FOLLOWS_NOTE", "ReferenceScore"]

FOLLOWS_NOTE = "turns with "
"""How a note on an orientation that follows its position's reference begins
(:meth:`_Chooser.follow_note`)."""
LOCAL_EVIDENCE = 0.02
"""A reference available at some of an object's placements only adds a state
there: its F test is taken at the significance level divided by the number of
such candidates at that step (Bonferroni), and at most this fraction of it
(0.05 → 0.001), so that one of many such candidates agreeing by chance does
not; and never from two placements."""


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
