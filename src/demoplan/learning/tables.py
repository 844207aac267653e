"""The model as the paper's tables (Tables II–V), as plain rows.

Functions here return rows of strings; the command line renders them with
rich and the experiment report as Markdown, so both show the same numbers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from demoplan.learning.constraints import label_key
from demoplan.model import State, TaskModel

__all__ = [
    "STATE_HEADER",
    "constraint_text",
    "format_orientation",
    "format_position",
    "sequence_rows",
    "state_rows",
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
            s.position.reference or "",
            s.orientation.reference or "",
            format_position(s, decimals),
            format_orientation(s),
            _spread(s),
            str(len(s.members)),
            _margin(s),
        )
        for s in model.states
    ]


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


def constraint_text(pairs: Sequence[tuple[str, str]]) -> str:
    """``A<B, A<C, …`` in label order."""
    ordered = sorted(pairs, key=lambda p: (label_key(p[0]), label_key(p[1])))
    return ", ".join(f"{x}<{y}" for x, y in ordered)


def precision_text(model: TaskModel) -> str | None:
    """The precision the decisions were measured against, for people."""
    if model.precision is None:
        return None
    position, orientation = model.precision
    how = "estimated from the demonstrations" if model.precision_estimated else "as set"
    return f"Precision: {position * 1000:.1f} mm, {orientation:.1f}° ({how})"


def diagnostic_lines(model: TaskModel) -> list[str]:
    """Warnings a teacher should read (issue 12 item 5): decisions taken within the
    precision (margin below 1) and states seen once."""
    lines = []
    for state in model.states:
        close = [f"{d} {m:+.1f}" for d, m in state.margins if m < 1.0]
        if close:
            lines.append(
                f"state {state.id} ({state.object}): decided within the precision "
                f"({', '.join(close)} × precision)"
            )
        if len(state.members) == 1:
            lines.append(f"state {state.id} ({state.object}): seen in one demonstration only")
    return lines
