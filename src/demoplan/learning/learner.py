"""Learning a task model from demonstrations: state generation + task generalization.

:class:`TaskModelLearner` follows scikit-learn's habits: settings in
``__init__``, ``fit(demonstrations)`` returns ``self``, learned results end in
``_`` and reading them before ``fit`` raises :class:`NotFittedError`.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence
from dataclasses import asdict
from typing import Self

from demoplan.errors import InputError, NotFittedError
from demoplan.learning.constraints import (
    anchor_requirements,
    goal_states,
    learn_constraints,
    parse_requirements,
)
from demoplan.learning.demonstrations import check_demonstrations
from demoplan.learning.states import ReferenceScore, StateGenerationSettings, generate_states
from demoplan.model import Demonstration, State, TaskModel

__all__ = ["TaskModelLearner", "learn", "update"]

logger = logging.getLogger(__name__)


class TaskModelLearner:
    """Learns states, precedence constraints and goals from demonstrations.

    Parameters
    ----------
    position_noise : RMS placement noise (m); spreads closer than this are ties.
    orientation_noise : RMS orientation noise (degrees).
    position_separation : minimum distance (m) between two clusters of one object.
    orientation_separation : minimum angle (degrees) between two orientation clusters.
    n_init : K-means restarts per clustering.
    random_state : seed of the K-means restarts.
    max_clusters : cap on the clusters per object and reference; 0 (default)
        scans c = 1..N as the paper does. With placements that follow no
        structure, eq. (2) scans far and learning slows (docs/learning.md).
    require : teacher constraints such as ``"A<B"`` or ``"plate<napkin"``; never
        removed by demonstrations (the journal version of the paper).

    Examples
    --------
    >>> from demoplan import TaskModelLearner, load_demonstrations
    >>> demos = load_demonstrations(["examples/blocks/demonstrations.json"])
    >>> learner = TaskModelLearner().fit(demos)
    >>> learner.sequences_
    (('A', 'B', 'C'), ('D', 'A', 'C'))
    """

    def __init__(
        self,
        *,
        position_noise: float = 0.003,
        orientation_noise: float = 0.5,
        position_separation: float = 0.05,
        orientation_separation: float = 15.0,
        n_init: int = 8,
        random_state: int = 0,
        max_clusters: int = 0,
        require: Sequence[str] = (),
    ):
        self.position_noise = _positive(position_noise, "position_noise")
        self.orientation_noise = _positive(orientation_noise, "orientation_noise")
        self.position_separation = _positive(position_separation, "position_separation")
        self.orientation_separation = _positive(orientation_separation, "orientation_separation")
        if not isinstance(n_init, int) or n_init < 1:
            raise InputError(f"expected a whole number ≥ 1, got {n_init!r}", field="n_init")
        self.n_init = n_init
        if not isinstance(max_clusters, int) or max_clusters < 0:
            raise InputError(
                f"expected a whole number ≥ 0 (0: no cap), got {max_clusters!r}",
                field="max_clusters",
            )
        self.max_clusters = max_clusters
        self.random_state = int(random_state)
        self.require = tuple(require)
        self._demonstrations: list[Demonstration] = []
        self._model: TaskModel | None = None
        self._scores: tuple[ReferenceScore, ...] = ()

    @property
    def settings(self) -> StateGenerationSettings:
        return StateGenerationSettings(
            position_noise=self.position_noise,
            orientation_noise=self.orientation_noise,
            position_separation=self.position_separation,
            orientation_separation=self.orientation_separation,
            n_init=self.n_init,
            seed=self.random_state,
            max_clusters=self.max_clusters,
        )

    def fit(self, demonstrations: Iterable[Demonstration]) -> Self:
        """Learn from ``demonstrations`` (in this order, which fixes the state letters)."""
        return self._refit(list(demonstrations))

    def partial_fit(self, demonstrations: Demonstration | Iterable[Demonstration]) -> Self:
        """Add demonstrations to those already seen and update the model.

        The result equals ``fit`` on all demonstrations at once: state
        generation is redone over every demonstration (a new one can move a
        cluster or change a reference), and contradicted constraints stay
        removed because they are recomputed from every sequence.
        """
        if isinstance(demonstrations, Demonstration):
            demonstrations = [demonstrations]
        return self._refit([*self._demonstrations, *demonstrations])

    def _refit(self, demos: list[Demonstration]) -> Self:
        """Learn from ``demos``; on an error the learner keeps its previous state."""
        check_demonstrations(demos)
        generation = generate_states(demos, self.settings)
        required = parse_requirements(self.require, generation.states, generation.sequences)
        constraint_set = learn_constraints(generation.sequences, required)
        for index, x, y in constraint_set.violations:
            logger.warning(
                "demonstration %d (%s) puts %s before %s, against the teacher's %s<%s",
                index + 1,
                demos[index].name,
                y,
                x,
                x,
                y,
            )
        self._demonstrations = demos
        self._scores = generation.scores
        self._model = TaskModel(
            states=generation.states,
            sequences=generation.sequences,
            constraints=constraint_set.constraints,
            goals=tuple(goal_states(s, generation.states) for s in generation.sequences),
            demonstrations=tuple(demos),
            teacher_constraints=required,
            violations=constraint_set.violations,
            settings=(*asdict(self.settings).items(), ("require", ";".join(self.require))),
        )
        return self

    @property
    def model_(self) -> TaskModel:
        if self._model is None:
            raise NotFittedError("TaskModelLearner is not fitted yet; call fit(demonstrations)")
        return self._model

    @property
    def states_(self) -> tuple[State, ...]:
        return self.model_.states

    @property
    def sequences_(self) -> tuple[tuple[str, ...], ...]:
        return self.model_.sequences

    @property
    def constraints_(self) -> tuple[tuple[str, str], ...]:
        return self.model_.constraints

    @property
    def goals_(self) -> tuple[tuple[str, ...], ...]:
        return self.model_.goals

    @property
    def violations_(self) -> tuple[tuple[int, str, str], ...]:
        return self.model_.violations

    @property
    def reference_scores_(self) -> tuple[ReferenceScore, ...]:
        """Every candidate reference's eq. (2) score, for diagnostics."""
        self.model_  # noqa: B018 - raises when not fitted
        return self._scores


def learn(
    demonstrations: Iterable[Demonstration],
    *,
    require: Sequence[str] = (),
    settings: StateGenerationSettings | None = None,
) -> TaskModel:
    """Learn a task model in one call (default settings unless given)."""
    return _learner(settings or StateGenerationSettings(), require).fit(demonstrations).model_


def update(
    model: TaskModel,
    demonstrations: Iterable[Demonstration],
    *,
    require: Sequence[str] = (),
    settings: dict[str, float | int] | None = None,
) -> TaskModel:
    """Add demonstrations to a learned model: the same model as learning from
    all of them at once (``demoplan learn --update``).

    The model's settings are kept unless overridden in ``settings``; its
    teacher requirements are kept, their state ids rewritten as the steps
    they were learned from (``@d.s``) so that they keep meaning the same
    states when the new demonstrations re-letter them; ``require`` adds more.
    """
    if not model.demonstrations:
        raise InputError(
            "model holds no demonstrations to update; relearn from the demonstration files",
            field="demonstrations",
        )
    stored = dict(model.settings)
    merged = StateGenerationSettings(
        **{
            name: kind(
                settings[name] if settings and name in settings else stored.get(name, default)
            )
            for name, (kind, default) in _SETTING_TYPES.items()
        }
    )
    previous = [r for r in str(stored.get("require", "")).split(";") if r]
    requirements = list(dict.fromkeys([*anchor_requirements(previous, model.sequences), *require]))
    learner = _learner(merged, requirements)
    return learner.fit([*model.demonstrations, *demonstrations]).model_


_SETTING_TYPES: dict[str, tuple[type, float | int]] = {
    name: (type(value), value) for name, value in asdict(StateGenerationSettings()).items()
}


def _learner(settings: StateGenerationSettings, require: Sequence[str]) -> TaskModelLearner:
    return TaskModelLearner(
        position_noise=settings.position_noise,
        orientation_noise=settings.orientation_noise,
        position_separation=settings.position_separation,
        orientation_separation=settings.orientation_separation,
        n_init=settings.n_init,
        random_state=settings.seed,
        max_clusters=settings.max_clusters,
        require=require,
    )


def _positive(value: float, name: str) -> float:
    if not isinstance(value, int | float) or not value > 0 or value == float("inf"):
        raise InputError(f"expected a positive number, got {value!r}", field=name)
    return float(value)
