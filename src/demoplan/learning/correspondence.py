"""Identical objects: which instance plays which role in each demonstration
(docs/learning.md, "Identical objects").

The paper assumes one object of each type ("Learning Task Models from
Multiple Human Demonstrations", Ekvall and Kragic, RO-MAN 2006, §VI: "if
there are two identical blocks present … the system gets confused"). Here
objects may declare a ``type``; instances of one type are interchangeable, so
their names mean nothing from one demonstration to the next. Before states
are generated (§IV.A), every demonstration's instances of a type are renamed
to the type's **roles** — ``plate#1``, ``plate#2`` — by the assignment under
which the roles' placements agree best across the demonstrations:

- for every candidate reference (absolute, a landmark, or an object or role
  resolved before the type — the plate before the fork laid beside it), each
  instance's final placement is expressed relative to it (in its frame where
  it has an orientation), as eq. (1) does for a state;
- roles start as one demonstration's instances (the first with the most of
  them, in the order they were placed); every demonstration's instances are
  assigned to the roles by a minimum-cost assignment on the squared distance
  to the roles' means (:func:`scipy.optimize.linear_sum_assignment`), the
  means recomputed and the assignment repeated until it stays;
- the candidate whose assignment leaves the least spread (the sum of squared
  distances to the roles' means) decides; a tie goes to absolute, then to
  landmarks, then to objects in order.

States, constraints and goals are then learned over roles exactly as over
objects, so a model of objects of their own type each is today's model. Types
are resolved in the order their instances are first placed, so that a role can
be a later type's reference ("the fork relative to the plate of its seat").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import linear_sum_assignment

from demoplan.learning.states import DemonstrationWorld
from demoplan.model import Demonstration, Pose, Role
from demoplan.rotations import matrices_from_quats

__all__ = [
    "Correspondence",
    "corresponding_roles",
    "instance_demonstrations",
    "rename_demonstration",
    "role_name",
]

MAX_ITERATIONS = 20
"""Assignment rounds per candidate reference; each round lowers the spread or
leaves the assignment as it was, so this is reached only on cycles of ties."""


@dataclass(frozen=True, slots=True)
class Correspondence:
    """Demonstrations with instances renamed to roles, the roles, and per
    type the reference the assignment was made against (``None``: absolute)."""

    demonstrations: tuple[Demonstration, ...]
    roles: tuple[Role, ...]
    references: tuple[tuple[str, str | None], ...] = ()


def role_name(kind: str, number: int, count: int) -> str:
    """``plate#2`` for the second of several roles of ``plate``; the type's own
    name where it has one role."""
    return kind if count == 1 else f"{kind}#{number}"


def corresponding_roles(demonstrations: Sequence[Demonstration]) -> Correspondence:
    """Rename every instance of a declared type to its role (module docstring).

    Demonstrations whose objects are all of their own type come back as they
    are, with no roles."""
    demos = list(demonstrations)
    instances = [_instances_by_type(demo) for demo in demos]
    kinds = sorted(
        {kind for per_demo in instances for kind, names in per_demo.items() if names != [kind]},
        key=lambda kind: _first_placement(demos, instances, kind),
    )
    if not kinds:
        return Correspondence(tuple(demos), ())
    roles: list[Role] = []
    references: list[tuple[str, str | None]] = []
    resolved = {
        name
        for per_demo in instances
        for kind, names in per_demo.items()
        if kind not in kinds
        for name in names
    }
    for kind in kinds:
        per_demo = [found.get(kind, []) for found in instances]
        count = max(len(names) for names in per_demo)
        assignment: list[list[str | None]]
        reference: str | None = None
        if count == 1:
            assignment = [[names[0] if names else None] for names in per_demo]
        else:
            assignment, reference = _assign(demos, per_demo, count, sorted(resolved))
        names = [role_name(kind, number + 1, count) for number in range(count)]
        demos = [
            rename_demonstration(
                demo,
                {inst: role for inst, role in zip(filled, names, strict=True) if inst is not None},
                kind,
            )
            for demo, filled in zip(demos, assignment, strict=True)
        ]
        roles += [
            Role(role, kind, tuple(filled[number] for filled in assignment))
            for number, role in enumerate(names)
        ]
        references.append((kind, reference))
        resolved |= set(names)
    return Correspondence(tuple(demos), tuple(roles), tuple(references))


def rename_demonstration(demo: Demonstration, renaming: dict[str, str], kind: str) -> Demonstration:
    """``demo`` with its instances of ``kind`` renamed (``renaming``: instance →
    role), their type recorded where the role's name is not the type."""
    if not renaming:
        return demo
    moved = demo.renamed(renaming)
    types = tuple((n, t) for n, t in moved.types if n != t)
    types += tuple((role, kind) for role in renaming.values() if role != kind)
    return replace(moved, types=tuple(dict(types).items()))


def instance_demonstrations(
    demonstrations: Sequence[Demonstration], roles: Sequence[Role]
) -> list[Demonstration]:
    """A model's demonstrations as they were given: every role renamed back to
    the instance that filled it (``learn --update`` learns from these again)."""
    out = []
    for index, demo in enumerate(demonstrations):
        renaming = {
            role.name: instance
            for role in roles
            if index < len(role.instances) and (instance := role.instances[index]) is not None
        }
        kinds = {role.name: role.type for role in roles}
        moved = demo.renamed(renaming)
        types = dict(moved.types) | {instance: kinds[role] for role, instance in renaming.items()}
        out.append(replace(moved, types=tuple((n, t) for n, t in types.items() if n != t)))
    return out


def _instances_by_type(demo: Demonstration) -> dict[str, list[str]]:
    """The demonstration's movable objects by type, in the order they are first
    placed (objects never moved after them, in the order they are listed)."""
    landmarks = {name for name, _ in demo.landmarks}
    names = [*demo.moved_objects, *(n for n, _ in demo.objects), *(n for n, _ in demo.initial)]
    by_type: dict[str, list[str]] = {}
    for name in dict.fromkeys(names):
        if name not in landmarks:
            by_type.setdefault(demo.type_of(name), []).append(name)
    return by_type


def _first_placement(
    demos: Sequence[Demonstration], instances: Sequence[dict[str, list[str]]], kind: str
) -> tuple[int, int, str]:
    """Sort key of a type: the demonstration and step that first move one of its instances."""
    for index, (demo, found) in enumerate(zip(demos, instances, strict=True)):
        for step, move in enumerate(demo.steps):
            if move.object in found.get(kind, []):
                return (index, step, kind)
    return (len(demos), 0, kind)


def _final(demo: Demonstration, name: str) -> tuple[int, Pose] | None:
    """The step after which ``name`` stays where it ends, and that pose."""
    for step in range(len(demo.steps) - 1, -1, -1):
        if demo.steps[step].object == name:
            return step, demo.steps[step].pose
    initial = demo.initial_poses().get(name)
    return None if initial is None else (len(demo.steps), initial)


def _assign(
    demos: Sequence[Demonstration],
    per_demo: Sequence[list[str]],
    count: int,
    resolved: Sequence[str],
) -> tuple[list[list[str | None]], str | None]:
    """The assignment of every demonstration's instances to ``count`` roles of the
    candidate reference leaving the least spread (module docstring)."""
    world = DemonstrationWorld(demos)
    present = [d for d, names in enumerate(per_demo) if names]
    landmarks = sorted(set.intersection(*(set(demos[d].landmark_poses()) for d in present)))
    best: tuple[float, list[list[str | None]], str | None] | None = None
    for reference in [None, *landmarks, *resolved]:
        features = _features(demos, per_demo, reference, world)
        if features is None:
            continue
        spread, assignment = _assignment(features, count)
        if best is None or spread < best[0] - 1e-12:
            best = (spread, assignment, reference)
    assert best is not None  # absolute always has features
    _, indices, reference = best
    return indices, reference


_Features = list[list[tuple[str, np.ndarray | None]]]


def _features(
    demos: Sequence[Demonstration],
    per_demo: Sequence[list[str]],
    reference: str | None,
    world: DemonstrationWorld,
) -> _Features | None:
    """Each instance's final position relative to ``reference`` (eq. 1, in its
    frame where it has an orientation); ``None`` where the reference is missing
    at some instance's placement."""
    out: _Features = []
    for index, (demo, names) in enumerate(zip(demos, per_demo, strict=True)):
        rows: list[tuple[str, np.ndarray | None]] = []
        for name in names:
            final = _final(demo, name)
            if final is None:
                rows.append((name, None))
                continue
            step, pose = final
            position = np.asarray(pose.position, dtype=float)
            if reference is not None:
                base = world.pose(index, reference, step)
                if base is None:
                    return None
                position = position - np.asarray(base.position)
                if base.orientation is not None:
                    turn = matrices_from_quats(np.asarray([base.orientation]))[0].reshape(3, 3)
                    position = turn.T @ position
            rows.append((name, position))
        out.append(rows)
    return out


def _assignment(features: _Features, count: int) -> tuple[float, list[list[str | None]]]:
    """Roles from the first demonstration with ``count`` instances, every
    demonstration assigned to them by minimum cost, the roles' means
    recomputed, until the assignment stays: the spread left and, per
    demonstration, the instance filling each role (``None``: none)."""
    seed = next(rows for rows in features if len(rows) == count)
    means = np.array([_or_nan(row[1]) for row in seed])
    means = np.where(np.isnan(means), 0.0, means)
    previous: list[list[str | None]] | None = None
    assignment: list[list[str | None]] = []
    spread = 0.0
    for _ in range(MAX_ITERATIONS):
        assignment, spread, sums, counts = [], 0.0, np.zeros_like(means), np.zeros(count)
        for rows in features:
            filled: list[str | None] = [None] * count
            if rows:
                cost = np.array(
                    [
                        np.zeros(count) if value is None else np.sum((means - value) ** 2, axis=1)
                        for _, value in rows
                    ]
                )
                chosen_rows, chosen_roles = linear_sum_assignment(cost)
                for row, role in zip(chosen_rows, chosen_roles, strict=True):
                    name, value = rows[row]
                    filled[role] = name
                    spread += float(cost[row, role])
                    if value is not None:
                        sums[role] += value
                        counts[role] += 1
            assignment.append(filled)
        if assignment == previous:
            break
        previous = assignment
        seen = counts > 0
        means[seen] = sums[seen] / counts[seen, None]
    return spread, assignment


def _or_nan(value: np.ndarray | None) -> np.ndarray:
    return np.full(3, np.nan) if value is None else value
