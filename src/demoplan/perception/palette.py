"""Colour names and the contrasts that tell a block's colour from the table's.

A pixel's colour is named by the nearest plain colour in brightness-free
chromaticity (RGB divided by its largest channel, so shading does not change it):
:data:`PALETTE`, extended by a user's palette file (:func:`load_palette`); dark
pixels are ``black``, greyish ones ``grey`` and a colour no plain colour is near is
``block``. The CIELAB contrasts here (:data:`MIN_CHROMA`, :data:`SIDE_FACE_GAP`)
decide what stands out from the table and what is a side face.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from demoplan.errors import InputError
from demoplan.perception.masks import distances

__all__ = [
    "MIN_CHROMA",
    "PALETTE",
    "SIDE_FACE_GAP",
    "UNNAMED",
    "Palette",
    "classify",
    "load_palette",
    "name_colour",
    "palette_arrays",
]

MAX_CHROMA_DISTANCE = 0.3
"""A colour farther than this (in RGB / max RGB) from every plain colour has no name."""
MIN_CHROMA = 12.0
"""Foreground: CIELAB a*b* distance from the table's colour (a grey card is ~0, a
wooden block ~30, a saturated red ~70)."""
MIN_LIGHTNESS_CONTRAST = 12.0
"""Foreground in an image without colour: CIELAB L* difference from the table."""
SIDE_FACE_GAP = 12.0
"""L* between a class's two lightness modes for the darker one to be side faces."""
MAX_PALETTE_COLOURS = 64
"""Colours a palette file may add: a camera tells a few dozen apart at best."""
UNNAMED = -4
"""The class of colours no plain colour is near (``block``); the unnamed colours of one
region that differ are the classes −4, −5, … (:func:`~.colour_classes.unnamed_split`)."""
SPECIAL_NAMES = {-2: "black", -3: "grey", UNNAMED: "block"}

PALETTE: dict[str, tuple[float, float, float]] = {
    # brightness-free chromaticity: RGB / max(RGB)
    "red": (1.0, 0.2, 0.2),
    "orange": (1.0, 0.55, 0.12),
    "wood": (1.0, 0.75, 0.5),
    "yellow": (1.0, 0.85, 0.18),
    "green": (0.3, 1.0, 0.35),
    "blue": (0.2, 0.42, 1.0),
    "purple": (0.7, 0.35, 1.0),
}

Palette = Mapping[str, tuple[float, float, float]]


def load_palette(path: str | Path) -> dict[str, tuple[float, float, float]]:
    """Colours to add to :data:`PALETTE` from a JSON (or YAML) file mapping a name to
    the block's colour as the camera sees it, ``[R, G, B]`` in 0–255
    (docs/perception.md, "Colour names"); stored as RGB / max RGB."""
    from demoplan.fileio import display_path, read_document

    source = display_path(Path(path))
    document = read_document(Path(path))  # JSON, or YAML by extension; one-line errors
    if not document:
        raise InputError("a mapping of colour names to [R, G, B] expected", source=source)
    if len(document) > MAX_PALETTE_COLOURS:
        raise InputError(
            f"{len(document)} colours; at most {MAX_PALETTE_COLOURS} expected", source=source
        )
    palette: dict[str, tuple[float, float, float]] = {}
    for name, value in document.items():
        field = str(name)
        if not isinstance(name, str) or not name.isidentifier() or name.startswith("block"):
            raise InputError(
                "a colour name (letters, digits, _; not starting with 'block') expected",
                source=source,
                field=field,
            )
        if (
            not isinstance(value, list)
            or len(value) != 3
            or not all(isinstance(c, int | float) and not isinstance(c, bool) for c in value)
            or not all(0 <= c <= 255 for c in value)
            or max(value) <= 0
        ):
            raise InputError(
                "[R, G, B] with each in 0–255 (not all 0) expected", source=source, field=field
            )
        top = float(max(value))
        palette[name] = (value[0] / top, value[1] / top, value[2] / top)
    return palette


def name_colour(rgb: np.ndarray, palette: Palette | None = None) -> str:
    """The plain colour name nearest to ``rgb`` (dark or grey: ``black`` / ``grey``;
    ``block`` when no plain colour is near: docs/formats.md then names blocks block1, block2…)."""
    names, chroma = palette_arrays(palette)
    label = int(classify(np.asarray(rgb, dtype=float).reshape(1, 3), chroma)[0])
    return names[label] if label >= 0 else SPECIAL_NAMES[label]


def palette_arrays(extra: Palette | None = None) -> tuple[list[str], np.ndarray]:
    merged = dict(PALETTE)
    merged.update(extra or {})
    return list(merged), np.array(list(merged.values()), dtype=float)


def classify(pixels: np.ndarray, chroma: np.ndarray) -> np.ndarray:
    """Palette index per pixel (N × 3 RGB); dark → -2, greyish → -3."""
    red, green, blue = pixels[:, 0], pixels[:, 1], pixels[:, 2]
    top = np.maximum(np.maximum(red, green), blue)
    normal = pixels / np.maximum(top, 1.0)[:, None]
    distance = distances(normal, chroma)
    labels: np.ndarray = np.argmin(distance, axis=1)
    nearest = distance[np.arange(labels.size), labels]
    labels[nearest > MAX_CHROMA_DISTANCE] = UNNAMED  # no plain colour
    # the smallest channel over the largest: near 1 for grey
    labels[np.minimum(np.minimum(red, green), blue) / np.maximum(top, 1.0) > 0.82] = -3
    labels[top < 60] = -2
    return labels
