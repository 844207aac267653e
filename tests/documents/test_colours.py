"""A colour field (docs/formats.md, scene ``colour``) over any JSON value: read
as ``#rrggbb`` exactly when it is one, or three numbers in 0–1; anything else
is a ValueError saying what was expected, never another exception and never a
colour a renderer cannot take."""

from __future__ import annotations

import json
import re

from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.documents.colours import COLOUR_FORMS, parse_colour

RRGGBB = re.compile(r"#[0-9a-f]{6}")
HEX = "0123456789abcdefABCDEF"

hex_like = st.builds(
    lambda digits, before, after: before + "#" + digits + after,
    st.text(HEX + "g", min_size=5, max_size=7),
    st.sampled_from(["", "", " "]),
    st.sampled_from(["", "\n", " ", "0"]),  # `$` alone would take "#d62728\n"
)
json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=12)
    | hex_like,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=3), inner),
    max_leaves=8,
)


def is_channel(value: object) -> bool:
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and 0 <= value <= 1  # not NaN
    )


@settings(max_examples=300, deadline=None)
@given(
    value=json_values
    | hex_like
    | st.lists(  # JSON's integers have no bound: 10**400 is one too
        st.floats(-0.5, 1.5) | st.sampled_from([0, 1, True, 10**400, -(10**400)]),
        min_size=3,
        max_size=3,
    )
)
def test_a_colour_is_read_exactly_when_it_is_one(value: object) -> None:
    expected_hex = isinstance(value, str) and re.fullmatch(r"#[0-9a-fA-F]{6}", value) is not None
    expected_rgb = isinstance(value, list) and len(value) == 3 and all(map(is_channel, value))
    try:
        colour = parse_colour(value)
    except ValueError as error:
        assert not (expected_hex or expected_rgb), value
        assert str(error).endswith(f"{COLOUR_FORMS} expected") and "\n" not in str(error)
        return
    assert expected_hex or expected_rgb, value
    assert RRGGBB.fullmatch(colour), colour
    if expected_hex:
        assert colour == str(value).lower()
    else:
        assert isinstance(value, list)
        channels = [int(colour[k : k + 2], 16) / 255 for k in (1, 3, 5)]
        assert all(abs(c - float(v)) <= 0.5 / 255 for c, v in zip(channels, value, strict=True))
    assert parse_colour(json.loads(json.dumps(colour))) == colour  # read back as written
