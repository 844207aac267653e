"""Learning a task model from demonstrations: state generation + task generalization.

:class:`TaskModelLearner` follows scikit-learn's habits: settings in
``__init__``, ``fit(demonstrations)`` returns ``self``, learned results end in
``_`` and reading them before ``fit`` raises :class:`NotFittedError`.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from typing import Any, Self

from demoplan.documents.demonstrations import check_demonstrations, warn_differing_colours
from demoplan.errors import InputError, NotFittedError
from demoplan.graphs import find_cycle
from demoplan.learning.constraints import (
    anchor_requirements,
    goal_states,
    label_key,
    learn_constraints,
    parse_requirements,
    required_pairs,
    visit_sequence,
)
from demoplan.learning.correspondence import corresponding_roles, instance_demonstrations
from demoplan.learning.settings import LearningSettings
from demoplan.learning.states import ReferenceScore, generate_states
from demoplan.model import Demonstration, State, TaskModel, demonstrated_types

__all__ = ["TaskModelLearner", "learn", "update"]

logger = logging.getLogger(__name__)


class TaskModelLearner:
    """Learns states, precedence constraints and goals from demonstrations.

    Parameters
    ----------
    settings : the :class:`LearningSettings` to learn with (default: the
        documented defaults).
    **overrides : settings to change from ``settings``, by name
        (``position_noise=0.005``, ``max_clusters=5``, ``require=["A<B"]``, …);
        a value out of range is an :class:`InputError` naming the setting.

    Examples
    --------
    >>> from demoplan import TaskModelLearner, load_demonstrations
    >>> demos = load_demonstrations(["examples/blocks/demonstrations.json"])
    >>> learner = TaskModelLearner().fit(demos)
    >>> learner.sequences_
    (('A', 'B', 'C'), ('B', 'A', 'C'))
    >>> dict(zip(learner.constraints_, learner.support_))
    {('A', 'C'): 2, ('B', 'C'): 2}
    >>> TaskModelLearner(min_support=3).fit(demos).constraints_
    ()
    """

    def __init__(self, settings: LearningSettings | None = None, **overrides: Any) -> None:
        self._settings = replace(settings or LearningSettings(), **overrides)
        self._requirements = parse_requirements(self._settings.require)
        self._demonstrations: list[Demonstration] = []
        self._model: TaskModel | None = None
        self._scores: tuple[ReferenceScore, ...] = ()
        self._support: tuple[int, ...] = ()
        self._below_support: tuple[tuple[str, str], ...] = ()

    @property
    def settings(self) -> LearningSettings:
        return self._settings

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
        _refuse_two_tasks(demos)
        warn_differing_colours(demos)
        correspondence = corresponding_roles(demos)
        learned_from = list(correspondence.demonstrations)
        generation = generate_states(learned_from, self.settings)
        required = required_pairs(
            self._requirements,
            generation.states,
            generation.sequences,
            demonstrated_types(learned_from),
        )
        constraint_set = learn_constraints(
            generation.sequences, required, self.settings.min_support
        )
        _refuse_cycles(generation.sequences, constraint_set.constraints, required, demos)
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
        self._support = constraint_set.support
        self._below_support = constraint_set.below_support
        self._model = TaskModel(
            states=generation.states,
            sequences=generation.sequences,
            constraints=constraint_set.constraints,
            goals=tuple(goal_states(s, generation.states) for s in generation.sequences),
            demonstrations=tuple(learned_from),
            teacher_constraints=required,
            violations=constraint_set.violations,
            settings=self.settings,
            precision=(generation.precision.position, generation.precision.orientation),
            precision_estimated=generation.precision.position_estimated,
            roles=correspondence.roles,
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
    def support_(self) -> tuple[int, ...]:
        """Per constraint (in the order of :attr:`constraints_`), the number of
        demonstrations that show it (docs/learning.md, "Support")."""
        self.model_  # noqa: B018 - raises when not fitted
        return self._support

    @property
    def below_support_(self) -> tuple[tuple[str, str], ...]:
        """Uncontradicted pairs left out because fewer than ``min_support``
        demonstrations show them (empty with the paper's rule, ``min_support=1``)."""
        self.model_  # noqa: B018 - raises when not fitted
        return self._below_support

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
    settings: LearningSettings | None = None,
) -> TaskModel:
    """Learn a task model in one call (default settings unless given; ``require``
    adds to ``settings.require``)."""
    settings = settings or LearningSettings()
    if require:
        settings = replace(settings, require=(*settings.require, *require))
    return TaskModelLearner(settings).fit(demonstrations).model_


def update(
    model: TaskModel,
    demonstrations: Iterable[Demonstration],
    *,
    require: Sequence[str] = (),
    settings: Mapping[str, Any] | None = None,
) -> TaskModel:
    """Add demonstrations to a learned model: the same model as learning from
    all of them at once (``demoplan learn --update``).

    The model's settings are kept unless overridden in ``settings`` (by name);
    its teacher requirements are kept, their state ids rewritten as the steps
    they were learned from (``@d.s``) so that they keep meaning the same
    states when the new demonstrations re-letter them; ``require`` adds more.
    """
    if not model.demonstrations:
        raise InputError(
            "model holds no demonstrations to update; relearn from the demonstration files",
            field="demonstrations",
        )
    kept = anchor_requirements(parse_requirements(model.settings.require), model.sequences)
    texts = tuple(dict.fromkeys([*(r.text for r in kept), *require]))
    merged = replace(model.settings, **(settings or {}), require=texts)
    known = instance_demonstrations(model.demonstrations, model.roles)
    return TaskModelLearner(merged).fit([*known, *demonstrations]).model_


def _refuse_two_tasks(demos: Sequence[Demonstration]) -> None:
    """Demonstrations that move no object in common, not even through others
    (one moving a and b, one b and c, one c: one task), are two tasks: an
    InputError naming both groups (exit 1). Learned together they made a model
    whose goals need both tasks' objects at once, in a scene no demonstration
    ever had, and every plan failed on a missing object (a work folder of two
    tasks, every demonstration ticked in the studio's Learn view). Objects
    are compared by type (instances of a type are one task's); a
    demonstration that moves nothing joins no group."""
    moving = [(demo, {demo.type_of(n) for n in demo.moved_objects}) for demo in demos]
    groups: list[tuple[list[Demonstration], set[str]]] = []
    for demo, moved in moving:
        if not moved:
            continue
        joined = [g for g in groups if g[1] & moved]
        merged = ([demo], set(moved))
        for group in joined:
            groups.remove(group)
            merged = (group[0] + merged[0], group[1] | merged[1])
        groups.append(merged)
    if len(groups) < 2:
        return
    first, second = sorted(groups, key=lambda g: demos.index(g[0][0]))[:2]

    def named(group: tuple[list[Demonstration], set[str]]) -> str:
        demo = min(group[0], key=demos.index)
        return f"{demo.source or demo.name} ({', '.join(sorted(group[1]))})"

    lead = min(second[0], key=demos.index)
    raise InputError(
        f"moves none of the objects of {named(first)}: "
        f"{', '.join(sorted(second[1]))}; one task's demonstrations expected, "
        "which move some objects in common — learn each task on its own",
        source=lead.source or lead.name,
        field="steps",
    )


def _refuse_cycles(
    sequences: Sequence[Sequence[str]],
    constraints: Sequence[tuple[str, str]],
    required: Sequence[tuple[str, str]],
    demos: Sequence[Demonstration],
) -> None:
    """A teacher constraint that closes a precedence cycle among one goal's states
    makes that goal impossible to reach in any order: an InputError naming the
    cycle (exit 1), not a model whose goal the planner would find unreachable.

    Why an error: the teacher said X<Y, a demonstration showed Y before X
    through other states; which of the two is meant only the teacher can say
    (drop the requirement, or the demonstration)."""
    if not required:
        return
    for index, sequence in enumerate(sequences):
        visits = set(visit_sequence(sequence))
        inside = [(a, b) for a, b in constraints if a in visits and b in visits]
        cycle = find_cycle(inside, order=label_key)
        # Each goal's own sequence orders its visits, so every learned pair
        # against it is contradicted: a cycle there runs through a requirement.
        if cycle:
            raise InputError(
                f"the teacher's constraints close a precedence cycle {' < '.join(cycle)} "
                f"within the goal of demonstration {index + 1} ({demos[index].name}); "
                "drop the requirement or that demonstration",
                field="require",
            )
