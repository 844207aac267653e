"""The learning settings: one typed value from the command line to the model file.

:class:`LearningSettings` is what ``demoplan learn`` options override, what
:class:`~demoplan.learning.TaskModelLearner` learns with, what a
:class:`~demoplan.model.TaskModel` records (``TaskModel.settings``) and what
the model file stores; ``learn --update`` relearns with
``replace(model.settings, **overrides)``. Values are checked here, once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from demoplan.errors import InputError

__all__ = ["PAPER_SETTINGS", "LearningSettings", "paper_overrides"]


@dataclass(frozen=True, slots=True)
class LearningSettings:
    """Settings of learning (documented defaults, docs/learning.md).

    position_noise : the placement precision (RMS, metres) decisions are
        measured against (docs/learning.md): spreads whose RMS differs by less than
        this are ties, and a cluster of one placement has this spread.
        ``None`` (default): estimated from the demonstrations
        (:func:`demoplan.learning.states.estimate_precision`), so that one
        default serves a virtual environment and teleoperated recordings.
    orientation_noise : the same for orientations, in degrees.
    position_separation : cluster means closer than this (m) reject a clustering.
    orientation_separation : the same for orientations (degrees, geodesic).
    n_init : K-means restarts per call.
    seed : seed of the K-means restarts.
    max_clusters : cap on the clusters per object and reference (0: the
        paper's N, the number of placements). With placements that follow no
        structure, eq. (2) scans far and learning slows (docs/learning.md).
    significance : a reference, or more clusters, is preferred to a choice
        with fewer states only when its spread is also lower by an F test at
        this level (:func:`demoplan.learning.clustering.outscores`): two
        placements that happen to agree are no evidence. 0: the paper's plain
        comparison.
    require : teacher constraints as given, such as ``"A<B"`` or
        ``"plate<napkin"``; never removed by demonstrations (the journal
        version of the paper).
    min_support : a learned constraint is kept only when at least this many
        demonstrations show it (its support,
        :func:`demoplan.learning.constraints.constraint_support`); 1 (default):
        the paper's rule (§IV.B), every pair no demonstration contradicts.
        Teacher constraints are kept whatever their support.
    orientation_follows_position : where an object's orientation reference is
        a tie within the precision and its position is relative to an object
        or landmark, the orientation is taken relative to the same reference
        (a thing in a box turns with the box, docs/learning.md). ``False``:
        the tie goes to absolute, as the paper's reading does.

    A value out of range is an :class:`~demoplan.errors.InputError` naming
    the setting. :data:`PAPER_SETTINGS` is the paper's reading: fixed
    thresholds of 3 mm and 0.5° and the plain comparison.
    """

    position_noise: float | None = None
    orientation_noise: float | None = None
    position_separation: float = 0.05
    orientation_separation: float = 15.0
    n_init: int = 8
    seed: int = 0
    max_clusters: int = 0
    significance: float = 0.05
    require: tuple[str, ...] = ()
    min_support: int = 1
    orientation_follows_position: bool = True

    def __post_init__(self) -> None:
        for name in _POSITIVE:
            value = getattr(self, name)
            if value is None and name in _ESTIMATED:
                continue
            if (
                isinstance(value, bool)
                or not isinstance(value, int | float)
                or not 0 < value < math.inf
            ):
                note = " (or null: estimated from the demonstrations)" if name in _ESTIMATED else ""
                raise InputError(f"expected a positive number{note}, got {value!r}", field=name)
            if value > _UPPER[name]:
                raise InputError(
                    f"{value:g} is beyond any tabletop; at most {_UPPER[name]:g} "
                    f"{'m' if name.startswith('position') else 'degrees'} expected "
                    "(docs/limits.md)",
                    field=name,
                )
            object.__setattr__(self, name, float(value))
        level = self.significance
        if isinstance(level, bool) or not isinstance(level, int | float) or not 0 <= level < 1:
            raise InputError(
                f"expected a level in [0, 1) (0: the paper's plain comparison), got {level!r}",
                field="significance",
            )
        object.__setattr__(self, "significance", float(level))
        _check_whole(self.n_init, "n_init", 1, most=(MAX_RESTARTS, "restarts run side by side"))
        _check_whole(self.seed, "seed", 0)
        _check_whole(self.max_clusters, "max_clusters", 0, " (0: no cap)")
        _check_whole(self.min_support, "min_support", 1, " (1: the paper's rule)")
        if isinstance(self.require, str) or not all(isinstance(r, str) for r in self.require):
            raise InputError(
                f"expected requirement texts such as ['A<B'], got {self.require!r}", field="require"
            )
        object.__setattr__(self, "require", tuple(self.require))
        if not isinstance(self.orientation_follows_position, bool):
            raise InputError(
                f"expected true or false, got {self.orientation_follows_position!r}",
                field="orientation_follows_position",
            )


_ESTIMATED = frozenset({"position_noise", "orientation_noise"})
_UPPER = {  # physically meaningful bounds (docs/limits.md): 10 m, a full turn
    "position_noise": 10.0,
    "position_separation": 10.0,
    "orientation_noise": 360.0,
    "orientation_separation": 360.0,
}
_POSITIVE = (
    "position_noise",
    "orientation_noise",
    "position_separation",
    "orientation_separation",
)


def _check_whole(
    value: object, name: str, least: int, note: str = "", most: tuple[int, str] | None = None
) -> None:
    """A whole number ≥ ``least`` (``note``: what the least means) and, with
    ``most`` (the largest, why), at most that."""
    if isinstance(value, bool) or not isinstance(value, int) or value < least:
        raise InputError(f"expected a whole number ≥ {least}{note}, got {value!r}", field=name)
    if most is not None and value > most[0]:
        raise InputError(
            f"expected a whole number from {least} to {most[0]} ({most[1]}), got {value!r}",
            field=name,
        )


MAX_RESTARTS = 1000
"""Most K-means restarts (``n_init``): they run side by side, each on its own
copy of the placements (``n_init`` × placements × 3 floats: 10⁹ restarts of
the Fig. 4 example asked for 45 GB)."""


PAPER_SETTINGS = LearningSettings(
    position_noise=0.003,
    orientation_noise=0.5,
    significance=0.0,
    orientation_follows_position=False,
)
# (the same values as paper_overrides(), below)
"""The paper's reading: fixed ties at 3 mm and 0.5°, the plain comparison of
spreads, orientation ties to absolute. The shipped examples were drawn for it
(examples/README.md)."""


def paper_overrides() -> dict[str, float | bool]:
    """The settings :data:`PAPER_SETTINGS` changes from the defaults, by name."""
    return {
        "position_noise": 0.003,
        "orientation_noise": 0.5,
        "significance": 0.0,
        "orientation_follows_position": False,
    }
