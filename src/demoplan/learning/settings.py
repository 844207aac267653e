"""The learning settings: one typed value from the command line to the model file.

:class:`LearningSettings` is what ``demoplan learn`` options override, what
:class:`~demoplan.learning.TaskModelLearner` learns with, what a
:class:`~demoplan.model.TaskModel` records (``TaskModel.settings``) and what
the model file stores; ``learn --update`` relearns with
``replace(model.settings, **overrides)``. Values are checked here, once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from demoplan.errors import InputError

__all__ = ["LearningSettings"]


@dataclass(frozen=True, slots=True)
class LearningSettings:
    """Settings of learning (documented defaults, docs/learning.md).

    position_noise : RMS placement noise in metres; spreads whose RMS differs
        by less than this are ties.
    orientation_noise : the same for orientations, in degrees.
    position_separation : cluster means closer than this (m) reject a clustering.
    orientation_separation : the same for orientations (degrees, geodesic).
    n_init : K-means restarts per call.
    seed : seed of the K-means restarts.
    max_clusters : cap on the clusters per object and reference (0: the
        paper's N, the number of placements). With placements that follow no
        structure, eq. (2) scans far and learning slows (docs/learning.md).
    require : teacher constraints as given, such as ``"A<B"`` or
        ``"plate<napkin"``; never removed by demonstrations (the journal
        version of the paper).

    A value out of range is an :class:`~demoplan.errors.InputError` naming
    the setting.
    """

    position_noise: float = 0.003
    orientation_noise: float = 0.5
    position_separation: float = 0.05
    orientation_separation: float = 15.0
    n_init: int = 8
    seed: int = 0
    max_clusters: int = 0
    require: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for setting in fields(self):
            if type(setting.default) is float:
                value = getattr(self, setting.name)
                if (
                    isinstance(value, bool)
                    or not isinstance(value, int | float)
                    or not 0 < value < math.inf
                ):
                    raise InputError(
                        f"expected a positive number, got {value!r}", field=setting.name
                    )
                object.__setattr__(self, setting.name, float(value))
        _check_whole(self.n_init, "n_init", 1)
        _check_whole(self.seed, "seed", 0)
        _check_whole(self.max_clusters, "max_clusters", 0, " (0: no cap)")
        if isinstance(self.require, str) or not all(isinstance(r, str) for r in self.require):
            raise InputError(
                f"expected requirement texts such as ['A<B'], got {self.require!r}", field="require"
            )
        object.__setattr__(self, "require", tuple(self.require))


def _check_whole(value: object, name: str, least: int, note: str = "") -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < least:
        raise InputError(f"expected a whole number ≥ {least}{note}, got {value!r}", field=name)
