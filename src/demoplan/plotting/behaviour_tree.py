"""A behaviour tree written by ``export bt``, drawn (``export bt --plot``;
docs/execution.md "Behaviour trees").

The main tree as an outline: one row per node, indented by depth, joined to
its parent by an elbow; control nodes in grey (``→`` Sequence, ``?``
Fallback, ``↻`` RetryUntilSuccessful with its attempts), conditions as rounded
green boxes, actions as blue boxes, each action naming its object and, for a
put-down, the target. matplotlib is imported lazily (the ``plot`` extra).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from defusedxml.ElementTree import fromstring

__all__ = ["behaviour_tree_figure", "save_behaviour_tree", "tree_rows"]

ROW_INCHES = 0.26
INDENT = 1.0
CONTROL = {"Sequence": "→", "Fallback": "?", "RetryUntilSuccessful": "↻"}
COLOURS = {"control": "#e6e6e6", "condition": "#d4edda", "action": "#d6e4f5", "other": "#fff3cd"}


@dataclass(frozen=True, slots=True)
class Row:
    """A node of the drawing: its depth, parent row (-1: the root), kind and text."""

    depth: int
    parent: int
    kind: str
    text: str


def tree_rows(xml: str) -> list[Row]:
    """The main tree's nodes in document order (module docstring)."""
    root = fromstring(xml)
    main = root.get("main_tree_to_execute", "")
    task = next(t for t in root.iter("BehaviorTree") if t.get("ID") == main)
    rows: list[Row] = []

    def visit(element: Any, depth: int, parent: int) -> None:
        rows.append(Row(depth, parent, *_describe(element)))
        here = len(rows) - 1
        for child in element:
            visit(child, depth + 1, here)

    for child in task:
        visit(child, 0, -1)
    return rows


def _describe(element: Any) -> tuple[str, str]:
    tag = element.tag
    name = element.get("name", "")
    if tag in CONTROL:
        extra = f" ×{element.get('num_attempts')}" if tag == "RetryUntilSuccessful" else ""
        return "control", f"{CONTROL[tag]} {tag}{extra}" + (f": {name}" if name else "")
    if tag == "SubTree":
        node = element.get("ID", "")
        obj = element.get("object", "")
        kind = "condition" if node == "IsAt" else "action"
        if node in ("IsAt", "PutDown", "MoveToFree"):
            where = ", ".join(f"{float(element.get(k, 'nan')):.3f}" for k in ("x", "y", "z"))
            reference = element.get("reference", "")
            relative = f", relative to {reference}" if reference not in ("", "world") else ""
            return kind, f"{node} {obj} at ({where}){relative}"
        return kind, f"{node} {obj}"
    if tag == "Script":
        return "other", f"Script {element.get('code', '')}"
    return "other", tag


def save_behaviour_tree(xml: str, path: Path) -> None:
    """Draw the tree of ``xml`` into ``path`` (its extension: the format), atomically."""
    from demoplan.fileio import write_atomic_bytes

    write_atomic_bytes(path, behaviour_tree_figure(xml, path))


def behaviour_tree_figure(xml: str, path: Path) -> bytes:
    """The drawing of the tree of ``xml``, encoded in the format of ``path``'s
    extension (written by the caller: ``export -o`` and ``--plot`` together)."""
    from demoplan.plotting.backend import use_agg

    use_agg()
    import matplotlib.pyplot as plt

    from demoplan.plotting.output import figure_bytes

    rows = tree_rows(xml)
    depth = max(r.depth for r in rows)
    height = ROW_INCHES * (len(rows) + 1)
    figure, ax = plt.subplots(figsize=(7.5 + 0.4 * depth, height))
    try:
        for index, row in enumerate(rows):
            x, y = row.depth * INDENT, -index
            if row.parent >= 0:
                px = rows[row.parent].depth * INDENT + 0.15
                ax.plot([px, px, x], [-row.parent - 0.3, y, y], color="#888888", lw=0.8)
            style = "round,pad=0.25" if row.kind == "condition" else "square,pad=0.25"
            ax.text(
                x + 0.1,
                y,
                row.text,
                va="center",
                ha="left",
                fontsize=8,
                bbox={
                    "boxstyle": style,
                    "facecolor": COLOURS[row.kind],
                    "edgecolor": "#555555",
                    "linewidth": 0.6,
                },
            )
        ax.set_xlim(-0.2, depth * INDENT + 9.5)
        ax.set_ylim(-len(rows), 1)
        ax.axis("off")
        figure.subplots_adjust(left=0.01, right=0.99, top=0.99, bottom=0.01)
        return figure_bytes(figure, path, 110)
    finally:
        plt.close(figure)
