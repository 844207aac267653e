"""Colour differences as a camera's exposure does not change them.

Under more or less light (a longer or shorter exposure, a brighter or darker
day) every surface's XYZ scales alike, so its CIELAB a* and b* scale with
``L* + 16`` (all three are cube roots of the light): a dark purple cube beside a
dark blue one is as different in hue under less light, but its a*b* distance
from its neighbour shrinks with it (mrhan_touching, its encoded values × 0.75:
from 15 to 11.7).
A rule that parts two colours when their a*b* lie a fixed distance apart then
parts them in one exposure and merges them in the next. :func:`chroma_apart`
holds two dark colours to that distance scaled as their light is — as far apart
as they would be lit to mid grey (:data:`MID_GREY`), by the lighter of the two
(a top face beside its own darker side face is judged by the top's light); at
mid grey or brighter the distance is the rule's own.

:func:`chroma_at_mid_grey` is a colour's own chroma so judged: a side face too dark
to show its hue (:mod:`~demoplan.perception.side_faces`) is one whose chroma as lit to
mid grey is small, not one that less light made small (mrhan_touching's dark red top,
chroma 24.2 at L* 33 and 20 at L* 24 with the encoded values × 0.75, is 32.5 and 32.7
lit to mid grey).

:mod:`~demoplan.perception.colours` holds to it the colours no palette colour is
near (unnamed: they are split and merged by their a*b* alone); the named colours
keep the plain distance (a wood top and its darker brown side faces in
armlab_mrhan4 scaled by 0.6, between 11.3 and 12 apart at L* 46–48, stay one).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["MID_GREY", "chroma_apart", "chroma_at_mid_grey"]

MID_GREY = 50.0
"""L* of a mid grey (18 % reflectance, L* 49.5): where a camera's exposure puts the
average of a scene."""


def chroma_apart(
    first: Sequence[float],
    second: Sequence[float],
    lightness: tuple[float, float],
    distance: float,
) -> bool:
    """Whether colours of mean a*b* ``first`` and ``second`` and mean L*
    ``lightness`` lie at least ``distance`` apart in a*b* as lit to mid grey: the
    distance scaled by ``(L* + 16) / (MID_GREY + 16)`` of the lighter colour when it
    is darker than :data:`MID_GREY`."""
    light = min(max(lightness), MID_GREY)
    apart = math.hypot(float(first[0]) - float(second[0]), float(first[1]) - float(second[1]))
    return apart >= distance * ((max(light, 0.0) + 16.0) / (MID_GREY + 16.0))


def chroma_at_mid_grey(chroma: float, lightness: float) -> float:
    """The a*b* chroma of a colour of ``chroma`` and L* ``lightness`` as lit to mid
    grey: scaled by ``(MID_GREY + 16) / (L* + 16)`` when it is darker than
    :data:`MID_GREY`; at mid grey or brighter, its own."""
    light = min(max(lightness, 0.0), MID_GREY)
    return chroma * (MID_GREY + 16.0) / (light + 16.0)
