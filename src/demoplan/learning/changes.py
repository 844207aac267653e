"""What a model update changed (``demoplan learn --update``, issue 12 item 4).

States are matched through the steps they were learned from: a state of the
old model is *kept* when one new state holds exactly its (demonstration,
step) members among the old demonstrations, *split* when its members went to
several new states, and several old states are *merged* when one new state
holds members of each; a new state holding only steps of the added
demonstrations is *added*. References are compared for kept states;
constraints after renaming the old ids to the new ones.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from demoplan.model import TaskModel

__all__ = ["ModelChanges", "model_changes"]


@dataclass(frozen=True, slots=True)
class ModelChanges:
    """The differences between a model and its update, in the update's state ids
    (old ids in ``renamed``, ``split`` and ``merged`` keys where they differ)."""

    added: tuple[str, ...]
    split: tuple[tuple[str, tuple[str, ...]], ...]  # old id → new ids
    merged: tuple[tuple[tuple[str, ...], str], ...]  # old ids → new id
    renamed: tuple[tuple[str, str], ...]  # old id → new id, kept states only
    references: tuple[tuple[str, str, str | None, str | None], ...]  # id, kind, old, new
    constraints_added: tuple[tuple[str, str], ...]
    constraints_removed: tuple[tuple[str, str], ...]

    @property
    def unchanged(self) -> bool:
        """No state, reference or constraint changed (member counts may have)."""
        return not (
            self.added
            or self.split
            or self.merged
            or self.references
            or self.constraints_added
            or self.constraints_removed
        )

    def lines(self) -> list[str]:
        """One line per kind of change, for people."""
        if self.unchanged:
            return ["no state, reference or constraint changed"]
        out = []
        if self.added:
            out.append(f"states added: {', '.join(self.added)}")
        for old, parts in self.split:
            out.append(f"state {old} split into {', '.join(parts)}")
        for olds, whole in self.merged:
            out.append(f"states {', '.join(olds)} merged into {whole}")
        for state, kind, before, after in self.references:
            out.append(
                f"state {state}: {kind} reference {before or 'absolute'} → {after or 'absolute'}"
            )
        if self.constraints_added:
            out.append(f"constraints added: {_pairs(self.constraints_added)}")
        if self.constraints_removed:
            out.append(f"constraints removed: {_pairs(self.constraints_removed)}")
        return out


def _pairs(pairs: Iterable[tuple[str, str]]) -> str:
    return ", ".join(f"{a}<{b}" for a, b in pairs)


def model_changes(old: TaskModel, new: TaskModel) -> ModelChanges:
    """Compare ``old`` with ``new``, learned from old's demonstrations and more
    (the first ``len(old.demonstrations)`` demonstrations of ``new`` are old's)."""
    n_old = len(old.demonstrations) or len(old.sequences)
    owner = {m: s.id for s in new.states for m in s.members}  # member → new state id
    new_members = {s.id: {m for m in s.members if m[0] < n_old} for s in new.states}
    rename: dict[str, str] = {}
    split: list[tuple[str, tuple[str, ...]]] = []
    taken: dict[str, list[str]] = {}
    for state in old.states:
        targets = sorted({owner[m] for m in state.members if m in owner})
        if len(targets) > 1:
            split.append((state.id, tuple(targets)))
            continue
        if targets:
            taken.setdefault(targets[0], []).append(state.id)
    merged = [(tuple(olds), new_id) for new_id, olds in taken.items() if len(olds) > 1]
    for new_id, olds in taken.items():
        if len(olds) == 1:
            rename[olds[0]] = new_id
    added = tuple(s.id for s in new.states if not new_members[s.id])
    references = []
    old_by_id = {s.id: s for s in old.states}
    new_by_id = {s.id: s for s in new.states}
    for old_id, new_id in rename.items():
        before, after = old_by_id[old_id], new_by_id[new_id]
        if before.position.reference != after.position.reference:
            references.append(
                (new_id, "position", before.position.reference, after.position.reference)
            )
        if before.orientation.reference != after.orientation.reference:
            references.append(
                (new_id, "orientation", before.orientation.reference, after.orientation.reference)
            )

    def relabel(label: str) -> str | None:
        state, mark, visit = label.partition("#")  # a visit label: "C#2"
        return rename[state] + mark + visit if state in rename else None

    mapped: set[tuple[str, str]] = set()
    unmapped: list[tuple[str, str]] = []
    for a, b in old.constraints:
        ra, rb = relabel(a), relabel(b)
        if ra is None or rb is None:
            unmapped.append((a, b))
        else:
            mapped.add((ra, rb))
    current = set(new.constraints)
    return ModelChanges(
        added=added,
        split=tuple(split),
        merged=tuple(merged),
        renamed=tuple((a, b) for a, b in sorted(rename.items()) if a != b),
        references=tuple(references),
        constraints_added=tuple(sorted(current - mapped)),
        constraints_removed=tuple(sorted((mapped - current) | set(unmapped))),
    )
