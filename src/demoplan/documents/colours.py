"""An object's colour as a file gives it (docs/formats.md, scene ``colour``):
``"#rrggbb"`` or ``[r, g, b]`` with each channel in 0–1, kept as ``#rrggbb``
(lower case) — the form every renderer takes (:mod:`demoplan.plotting.colours`).
"""

from __future__ import annotations

import re
from typing import Annotated

from pydantic import BeforeValidator

__all__ = ["COLOUR_FORMS", "HEX_COLOUR", "GivenColour", "parse_colour"]

HEX_COLOUR = re.compile(r"^#[0-9a-fA-F]{6}$")
"""``#rrggbb``, to be matched whole (:meth:`re.Pattern.fullmatch`: ``$`` alone
also matches before a last newline); the studio's requests check the same."""
COLOUR_FORMS = '"#rrggbb" or [r, g, b] with each in 0–1'
"""What a colour field holds, as error lines say it."""


def parse_colour(value: object) -> str:
    """``value`` as ``#rrggbb``; a ValueError saying what was expected otherwise."""
    if isinstance(value, str) and HEX_COLOUR.fullmatch(value):
        return value.lower()
    if (
        isinstance(value, list | tuple)
        and len(value) == 3
        # compared, not converted: NaN is in no range, and JSON's integers have
        # no bound (10**400 overflows a float)
        and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        and all(0.0 <= v <= 1.0 for v in value)
    ):
        return "#" + "".join(f"{round(float(v) * 255):02x}" for v in value)
    shown = repr(value)
    shown = shown if len(shown) <= 40 else shown[:40] + "…"
    raise ValueError(f"{shown} is not a colour; {COLOUR_FORMS} expected")


def _given_colour(value: object) -> str | None:
    return None if value is None else parse_colour(value)


GivenColour = Annotated[str | list[float] | None, BeforeValidator(_given_colour)]
"""A document's ``colour`` field (a scene's object or landmark), as a file may
give it (a string or [r, g, b]: the generated docs/formats.md says so), read as
``#rrggbb``, or None where it gives none."""
