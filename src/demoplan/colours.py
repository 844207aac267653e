"""One colour per object, the same in every figure and render of a run.

An object named after a colour (``red``, ``wood``) gets that colour; any other
gets the next colour of a cycle the first time it is drawn, and keeps it for
the rest of the process — so the demonstrations, the plan, the storyboard and
the MuJoCo scene of one ``demoplan experiments`` agree (the glass is one
colour everywhere). NumPy- and matplotlib-free: the physics world uses it too.
"""

from __future__ import annotations

__all__ = ["object_colour", "object_rgba"]

NAMED = {
    "red": "#d62728",
    "green": "#2ca02c",
    "blue": "#1f77b4",
    "yellow": "#e6c619",
    "wood": "#b5875a",
    "orange": "#ff7f0e",
    "purple": "#9467bd",
    "brown": "#8c564b",
    "pink": "#e377c2",
    "grey": "#7f7f7f",
    "gray": "#7f7f7f",
    "black": "#303030",
    "white": "#f0f0f0",
}
CYCLE = (
    "#4c72b0",
    "#dd8452",
    "#55a868",
    "#c44e52",
    "#8172b3",
    "#937860",
    "#da8bc3",
    "#64b5cd",
    "#ccb974",
    "#8c8c8c",
)
_assigned: dict[str, str] = {}


def object_colour(name: str) -> str:
    """``name``'s colour as ``#rrggbb``: its own where it names one, else the
    first cycle colour no other object of this run has (cycling once all are
    taken)."""
    if name in NAMED:
        return NAMED[name]
    if name not in _assigned:
        taken = set(_assigned.values())
        free = [c for c in CYCLE if c not in taken]
        _assigned[name] = free[0] if free else CYCLE[len(_assigned) % len(CYCLE)]
    return _assigned[name]


def object_rgba(name: str) -> str:
    """:func:`object_colour` as MuJoCo's ``rgba`` attribute (``"r g b 1"``)."""
    hex_colour = object_colour(name).lstrip("#")
    red, green, blue = (int(hex_colour[k : k + 2], 16) / 255 for k in (0, 2, 4))
    return f"{red:.3f} {green:.3f} {blue:.3f} 1"
