"""Which instance in the scene fills which role of the model (docs/planning.md,
"Identical objects").

A model learned from identical objects names roles (``plate#1``, ``plate#2``;
:mod:`demoplan.learning.correspondence`); a scene names instances
(``plate-a``, ``plate-b``) and says their type. A **binding** gives every role
an instance of its type; bound, the model names the scene's instances and is
planned as any model is. Which binding is best is part of the search:
:func:`demoplan.scenes.plan.plan_in_scene` plans the bindings in order of a
lower bound on their plans' length — two actions for every object its goal
needs elsewhere — and stops where no binding left can beat the best plan, so
the plan it returns is shortest over every binding where it says so.

Instances beyond a type's roles stand in the scene as objects with no goal
(moved only if in the way). An object of its own type binds to itself, so a
model without roles is planned exactly as before.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TypeVar

from demoplan.errors import InputError, LimitReachedError
from demoplan.model import State, StateOrientation, StatePosition, TaskModel
from demoplan.scenes.scene import Scene
from demoplan.scenes.targets import Candidate
from demoplan.wording import plural

__all__ = [
    "MAX_BINDINGS",
    "Binding",
    "bind_model",
    "lower_bound",
    "role_bindings",
]

MAX_BINDINGS = 5_040
"""At most this many bindings (7! — seven identical objects in seven roles)
are weighed; a scene with more is refused with the numbers (exit 4)."""


@dataclass(frozen=True, slots=True)
class Binding:
    """Role → instance, for every object of the model (role names sorted)."""

    pairs: tuple[tuple[str, str], ...]

    @property
    def renaming(self) -> dict[str, str]:
        return dict(self.pairs)

    @property
    def roles(self) -> dict[str, str]:
        """Role → instance, for the roles an instance of another name fills (what
        figures and ``plan --json`` show)."""
        return {role: instance for role, instance in self.pairs if role != instance}

    @property
    def identity(self) -> bool:
        """Every role is filled by the scene object of its own name."""
        return all(role == instance for role, instance in self.pairs)

    def describe(self) -> str:
        """``plate#1=plate-b, plate#2=plate-a``: the roles filled by other names."""
        return ", ".join(f"{role}={instance}" for role, instance in self.pairs if role != instance)


def role_bindings(model: TaskModel, scene: Scene) -> list[Binding]:
    """Every binding of the model's objects (roles) to the scene's instances of
    their types, in a fixed order (instances in scene order).

    An :class:`InputError` where the scene has fewer instances of a type than
    the model has roles (naming the type, the roles and the instances), a
    :class:`LimitReachedError` beyond :data:`MAX_BINDINGS`."""
    types = model.object_types()
    needed = _needed(model)
    by_type: dict[str, list[str]] = {}
    for role in sorted(needed):
        by_type.setdefault(types.get(role, role), []).append(role)
    instances: dict[str, list[str]] = {}
    for obj in scene.objects:
        # An object named like one of the model's (a role, plate#1) is of its type.
        kind = obj.type or types.get(obj.name, obj.name)
        instances.setdefault(kind, []).append(obj.name)
    choices: list[list[tuple[tuple[str, str], ...]]] = []
    count = 1
    for kind, roles in sorted(by_type.items()):
        found = instances.get(kind, [])
        if len(roles) == 1 and found == roles:
            # An object of its own type, alone: itself (the scene's "red" is the model's "red").
            choices.append([((roles[0], roles[0]),)])
            continue
        if len(found) < len(roles):
            have = f"{len(found)} ({', '.join(found)})" if found else "none"
            raise InputError(
                f"the task model needs {plural(len(roles), 'object')} of type {kind!r} "
                f"({', '.join(roles)}); the scene has {have} "
                f'(an object is of type {kind!r} by its name or by "type": "{kind}")',
                source=scene.source,
                field="objects",
            )
        count *= math.perm(len(found), len(roles))
        if count > MAX_BINDINGS:
            raise LimitReachedError(
                f"{count:,}+ ways to give the scene's instances the model's roles; at most "
                f"{MAX_BINDINGS:,} are weighed (fewer identical objects, or distinct types)"
            )
        choices.append(
            [
                tuple(zip(roles, chosen, strict=True))
                for chosen in itertools.permutations(found, len(roles))
            ]
        )
    return [
        Binding(tuple(sorted(pair for part in product for pair in part)))
        for product in itertools.product(*choices)
    ]


def _needed(model: TaskModel) -> set[str]:
    """The objects (roles) the model's states and references name, landmarks aside."""
    landmarks = {name for demo in model.demonstrations for name, _ in demo.landmarks}
    needed = {state.object for state in model.states}
    for state in model.states:
        for reference in (state.position.reference, state.orientation.reference):
            if reference is not None and reference not in landmarks:
                needed.add(reference)
    return needed


def bind_model(model: TaskModel, binding: Binding) -> TaskModel:
    """``model`` naming the instances of ``binding`` instead of its roles (the
    model itself for an identity binding)."""
    if binding.identity:
        return model
    renaming = binding.renaming
    # Roles no instance fills (a reference only some demonstration had) keep their names.
    return replace(
        model,
        states=tuple(_bind_state(state, renaming) for state in model.states),
        demonstrations=tuple(demo.renamed(renaming) for demo in model.demonstrations),
    )


def _bind_state(state: State, renaming: Mapping[str, str]) -> State:
    position, orientation = state.position, state.orientation
    return replace(
        state,
        object=renaming.get(state.object, state.object),
        position=_bind_reference(position, renaming),
        orientation=_bind_reference(orientation, renaming),
    )


_Part = TypeVar("_Part", StatePosition, StateOrientation)


def _bind_reference(part: _Part, renaming: Mapping[str, str]) -> _Part:
    if part.reference is None:
        return part
    return replace(part, reference=renaming.get(part.reference, part.reference))


def lower_bound(candidate: Candidate, scene: Scene, tolerance: float) -> int:
    """Actions any plan of ``candidate`` needs: a grasp and a put-down for every
    object whose final target lies farther than ``tolerance`` from where it
    stands (orientations aside, so that the bound stays a bound)."""
    current = {obj.name: obj.pose.position for obj in scene.objects}
    away = [
        name
        for name, pose in candidate.final_poses().items()
        if name not in current or math.dist(current[name], pose.position) > tolerance
    ]
    return 2 * len(away)
