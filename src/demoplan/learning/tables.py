"""The model as the paper's tables (Tables II–V), as plain rows.

Functions here return rows of strings; the command line renders them with
rich and the experiment report as Markdown, so both show the same numbers.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence

from demoplan.learning.constraints import constraint_support, label_key, learn_constraints
from demoplan.learning.states import ANYWHERE_NOTE, FOLLOWS_NOTE, PLACED_NOTE
from demoplan.model import State, TaskModel
from demoplan.wording import plural

__all__ = [
    "STATE_HEADER",
    "constraint_text",
    "format_orientation",
    "format_position",
    "role_header",
    "role_rows",
    "sequence_rows",
    "state_rows",
    "support_lines",
    "supported_constraint_text",
]

STATE_HEADER = (
    "State",
    "Object",
    "Relative Position",
    "Relative Orientation",
    "Position [m]",
    "Orientation [deg]",
    "Spread (RMS)",
    "Members",
    "Margin",
)


def _number(value: float, decimals: int) -> str:
    text = f"{value:.{decimals}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text  # no "-0.00"


def format_position(state: State, decimals: int = 2) -> str:
    """``(x, y)`` for planar states at table height, else ``(x, y, z)``."""
    x, y, z = state.position.value
    values = (x, y) if abs(z) < 0.5 * 10**-decimals else (x, y, z)
    return "(" + ", ".join(_number(v, decimals) for v in values) + ")"


def format_orientation(state: State, decimals: int = 0) -> str:
    """θ for a rotation about z only (as Table IV), else (roll, pitch, yaw); blank when unknown."""
    rpy = state.orientation.rpy
    if rpy is None:
        return ""
    roll, pitch, yaw = rpy
    if abs(roll) < 1e-6 and abs(pitch) < 1e-6:
        return _number(yaw, decimals)
    return "(" + ", ".join(_number(v, decimals) for v in rpy) + ")"


def _spread(state: State) -> str:
    parts = [f"{1000 * math.sqrt(state.position.spread):.1f} mm"]
    if state.orientation.value is not None:
        parts.append(f"{math.sqrt(state.orientation.spread):.1f}°")
    return ", ".join(parts)


def state_rows(model: TaskModel, decimals: int = 2) -> list[tuple[str, ...]]:
    """One row per state, as Tables II and IV (plus spread, member count and the
    margin of its closest decision in units of the precision)."""
    return [
        (
            s.id,
            s.object,  # as the demonstrations name it: --require takes the same
            position_reference_text(s),
            orientation_reference_text(s),
            format_position(s, decimals),
            format_orientation(s),
            _spread(s),
            str(len(s.members)),
            _margin(s),
        )
        for s in model.states
    ]


def orientation_reference_text(state: State) -> str:
    """The orientation's reference as the states table shows it: its name, or
    where it was a tie that went to the position's reference, the words for
    it (``turns with lunchbox: never seen turned``, docs/learning.md)."""
    reference = state.orientation.reference
    if reference is None:
        return ""
    return next((n for n in state.notes if n.startswith(f"{FOLLOWS_NOTE}{reference}:")), reference)


def position_reference_text(state: State) -> str:
    """The position's reference as the states table shows it: its name, blank
    for absolute, ``anywhere``; where the anywhere rule was a near call or
    decided with the other roles of its type, the words for it."""
    if state.position.reference is not None:
        return state.position.reference
    shown = "anywhere" if state.position.anywhere else ""
    return next((n for n in state.notes if n.startswith((ANYWHERE_NOTE, PLACED_NOTE))), shown)


def _margin(state: State) -> str:
    """The state's closest decision, in units of the precision (docs/learning.md)."""
    if not state.margins:
        return ""
    return f"{min(m for _, m in state.margins):+.1f}"


def sequence_rows(model: TaskModel) -> list[tuple[str, str, str]]:
    """Tables III and V: demonstration, its state sequence, its goal states."""
    names = [d.name for d in model.demonstrations] or [""] * len(model.sequences)
    return [
        (
            f"Demonstration {k + 1}" + (f" ({names[k]})" if names[k] else ""),
            "-".join(seq),
            ", ".join(goal),
        )
        for k, (seq, goal) in enumerate(zip(model.sequences, model.goals, strict=True))
    ]


def role_header(model: TaskModel, *, short: bool = False) -> tuple[str, ...]:
    """Header of :func:`role_rows`: role, type, then one column per demonstration
    (``Demonstration 1``, or ``1`` where ``short``), numbered as in :func:`sequence_rows`."""
    count = max([len(model.demonstrations), *(len(role.instances) for role in model.roles)])
    return (
        "Role",
        "Type",
        *(str(k) if short else f"Demonstration {k}" for k in range(1, count + 1)),
    )


def role_rows(model: TaskModel) -> list[tuple[str, ...]]:
    """One row per role of identical objects (docs/learning.md, "Roles in tables
    and figures"): its name (``plate#1``), its type and, per demonstration, the
    instance that filled it (``—``: that demonstration had no instance for it).
    No rows for a model whose objects are each of their own type."""
    count = len(role_header(model)) - 2
    return [
        (role.name, role.type, *(_instance(role.instances, k) for k in range(count)))
        for role in model.roles
    ]


def _instance(instances: Sequence[str | None], demonstration: int) -> str:
    filled = instances[demonstration] if demonstration < len(instances) else None
    return "—" if filled is None else filled


def constraint_text(pairs: Sequence[tuple[str, str]]) -> str:
    """``A<B, A<C, …`` in label order."""
    ordered = sorted(pairs, key=lambda p: (label_key(p[0]), label_key(p[1])))
    return ", ".join(f"{x}<{y}" for x, y in ordered)


def supported_constraint_text(model: TaskModel) -> str:
    """``A<B (3), A<C (1), …``: each constraint with its support, the number of
    demonstrations that show it (docs/learning.md), in label order."""
    support = dict(
        zip(model.constraints, constraint_support(model.sequences, model.constraints), strict=True)
    )
    ordered = sorted(model.constraints, key=lambda p: (label_key(p[0]), label_key(p[1])))
    return ", ".join(f"{x}<{y} ({support[(x, y)]})" for x, y in ordered)


def support_lines(model: TaskModel) -> list[str]:
    """How much the constraints rest on: how many are shown by 1, 2, …
    demonstrations, and how many ``min_support`` left out."""
    counts = Counter(constraint_support(model.sequences, model.constraints))
    lines = []
    if counts:
        parts = [f"{k}: {plural(counts[k], 'constraint')}" for k in sorted(counts)]
        lines.append(
            f"Support (demonstrations showing a constraint, of {len(model.sequences)}): "
            + ", ".join(parts)
        )
    least = model.settings.min_support
    if least > 1:
        every = learn_constraints(model.sequences, model.teacher_constraints).constraints
        dropped = len(set(every) - set(model.constraints))
        lines.append(
            f"Left out by --min-support {least}: {plural(dropped, 'constraint')} shown by "
            f"fewer than {plural(least, 'demonstration')}"
        )
    return lines


def precision_text(model: TaskModel) -> str | None:
    """The precision the decisions were measured against, for people."""
    if model.precision is None:
        return None
    position, orientation = model.precision
    how = "estimated from the demonstrations" if model.precision_estimated else "as set"
    return f"Precision: {position * 1000:.1f} mm, {orientation:.1f}° ({how})"


def distinct_demonstrations(model: TaskModel) -> int:
    """How many demonstrations the model rests on: those that do not repeat an
    earlier one exactly (a repeat adds no evidence, docs/learning.md); the
    count of sequences for a model file that keeps no demonstrations."""
    if not model.demonstrations:
        return len(model.sequences)
    return len({(d.steps, d.landmarks, d.initial) for d in model.demonstrations})


def diagnostic_lines(model: TaskModel) -> list[str]:
    """Warnings a teacher should read (issue 12 item 5): decisions taken within the
    precision (margin below 1), states seen once and decisions taken at an edge
    of the rules (the states' notes). A model learned from one demonstration
    (or from repeats of one) has one line instead: every state of it is seen
    once and every decision is a tie."""
    if distinct_demonstrations(model) < 2:
        repeats = len(model.sequences) - 1
        shown = "one demonstration" + (
            f" (and {plural(repeats, 'exact repeat')} of it)" if repeats > 0 else ""
        )
        return [
            f"learned from {shown}: every state is seen once and every reference is a "
            "guess; teach the task at least twice, the objects placed anew each time"
        ]
    lines = []
    for state in model.states:
        follows = orientation_reference_text(state) != (state.orientation.reference or "")
        close = [
            f"{d} {m:+.1f}"
            for d, m in state.margins
            if m < 1.0 and not (follows and d == "orientation reference")
        ]
        if close:
            lines.append(
                f"state {state.id} ({state.object}): decided within the precision "
                f"({', '.join(close)} × precision)"
            )
        if len(state.members) == 1:
            lines.append(f"state {state.id} ({state.object}): seen in one demonstration only")
        lines += [f"state {state.id} ({state.object}): {note}" for note in state.notes]
    return lines
