"""One colour per object, the same in every figure and render — and in every
command, so that ``learn``'s figure, ``plan --plot`` and ``run --frames`` of
one task agree.

An object whose scene file gives its ``colour`` (the studio writes the colour a
user chose) has that colour in every renderer: :func:`assign_colours` takes the
given colours first. Any other object named after a colour (``red``, ``wood``)
gets that colour, and so does a numbered one (``red2``, ``red-2``, the role
``red#2``: identical blocks as perception and learning name them). Any other
gets a colour of :data:`CYCLE` chosen from its name alone (a stable
hash), so it does not depend on which object happened to be drawn first;
where two objects of one task would share a colour, :func:`assign_colours`,
given the task's objects, moves the later name (in sorted order) to the next
free colour — the same way in every command that sees the same objects.
NumPy- and matplotlib-free: the physics world uses it too.
"""

from __future__ import annotations

import re
import zlib
from collections.abc import Iterable, Mapping

__all__ = [
    "CYCLE",
    "INK_LUMINANCE",
    "NAMED",
    "assign_colours",
    "ink",
    "luminance",
    "object_colour",
    "rgba",
]

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
    "#2f4b7c",
    "#a05195",
    "#f95d6a",
    "#00a3a3",
    "#7a5195",
    "#ffa600",
    "#5b8c2a",
    "#b2456e",
    "#3d85c6",
    "#9c6644",
)
_assigned: dict[str, str] = {}
_given: dict[str, str] = {}


def object_colour(name: str) -> str:
    """``name``'s colour as ``#rrggbb``: the one its file gives (as last passed
    to :func:`assign_colours`), else its own where it names one, else the one
    :func:`assign_colours` gave it, else its preferred cycle colour."""
    if name in _given:
        return _given[name]
    named = _named(name)
    if named is not None:
        return named
    return _assigned.get(name) or _preferred(name)


_NUMBERED = re.compile(r"^([a-z]+)(?:[-#]?\d+)$")


def _named(name: str) -> str | None:
    """The colour ``name`` names: ``red``, or a numbered ``red2`` / ``red-2`` / ``red#2``."""
    if name in NAMED:
        return NAMED[name]
    numbered = _NUMBERED.match(name)
    return NAMED.get(numbered.group(1)) if numbered else None


def assign_colours(names: Iterable[str], given: Mapping[str, str] | None = None) -> dict[str, str]:
    """Colours for the objects of one task, distinct where the cycle allows:
    each of ``given`` (name → ``#rrggbb``, the colours a scene file gives) its
    own; the others, in sorted order, the colour they name, else their
    preferred colour or the next one in the cycle that no other of ``names``
    has. Remembered for :func:`object_colour` for the rest of the process (a
    name not in ``given`` forgets a colour given before)."""
    given = given or {}
    unique = sorted(set(names) | set(given))
    taken = {colour for n in unique if (colour := given.get(n) or _named(n)) is not None}
    colours: dict[str, str] = {}
    for name in unique:
        if name in given:
            colours[name] = _given[name] = given[name].lower()
            continue
        _given.pop(name, None)
        named = _named(name)
        if named is not None:
            colours[name] = named
            continue
        start = CYCLE.index(_preferred(name))
        for step in range(len(CYCLE)):
            colour = CYCLE[(start + step) % len(CYCLE)]
            if colour not in taken:
                break
        else:
            colour = CYCLE[start]  # more objects than colours
        taken.add(colour)
        colours[name] = _assigned[name] = colour
    return colours


def _preferred(name: str) -> str:
    return CYCLE[zlib.crc32(name.encode("utf-8", "surrogatepass")) % len(CYCLE)]


INK_LUMINANCE = 0.3
"""The highest relative luminance (0 black … 1 white) of a line or a number
drawn in an object's colour on a figure's white ground (:func:`ink`): a
contrast of 3 : 1 with white, WCAG 2's least for graphics."""


def luminance(colour: str) -> float:
    """``#rrggbb``'s relative luminance (WCAG 2: 0 black, 1 white)."""
    hex_colour = colour.lstrip("#")
    channels = [int(hex_colour[k : k + 2], 16) / 255 for k in (0, 2, 4)]
    red, green, blue = (
        c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in channels
    )
    return 0.2126 * red + 0.7152 * green + 0.0722 * blue


def ink(colour: str) -> str:
    """``colour`` for what is drawn in it on white — a move's arrow, its number:
    itself, or as dark as :data:`INK_LUMINANCE` where it is lighter (a white
    mug's arrow was invisible, its number white on white). The same hue; the
    object's own patches keep its colour."""
    if luminance(colour) <= INK_LUMINANCE:
        return colour.lower()
    hex_colour = colour.lstrip("#")
    channels = [int(hex_colour[k : k + 2], 16) for k in (0, 2, 4)]
    low, high = 0.0, 1.0  # the scale that brings it to the threshold, by bisection
    for _ in range(30):
        middle = (low + high) / 2
        scaled = "#" + "".join(f"{round(c * middle):02x}" for c in channels)
        low, high = (middle, high) if luminance(scaled) <= INK_LUMINANCE else (low, middle)
    return "#" + "".join(f"{round(c * low):02x}" for c in channels)


def rgba(colour: str) -> str:
    """``#rrggbb`` as MuJoCo's ``rgba`` attribute (``"r g b 1"``)."""
    hex_colour = colour.lstrip("#")
    red, green, blue = (int(hex_colour[k : k + 2], 16) / 255 for k in (0, 2, 4))
    return f"{red:.3f} {green:.3f} {blue:.3f} 1"
