"""A photograph's white balance, taken back to the table's grey.

A camera's white balance multiplies each colour channel by a gain (the light of a
tungsten lamp or a shaded window, a fixed preset, an automatic balance gone
astray). In the encoded (sRGB) values such a gain is again a gain per channel
(the encoding is close to a power law), so in the log-chromaticity plane
``(ln R/G, ln B/G)`` it moves every pixel — bright or dark, table or cube — by the
same step; lightness leaves that plane unchanged. The thresholds of perception are
CIELAB distances measured on photographs whose grey board looks grey: a cast moves
the board's a*b* by an amount that grows with its lightness (the black grid
lines move less than the board, so they stand out in colour), and it moves every
block's chromaticity away from the palette colour that names it.

The table is the largest surface of one colour in a top view, and a camera's
automatic white balance makes it close to grey: the development photographs'
boards lie 0.04–0.08 from grey in that plane (a light wooden board 0.05), the
rendered board and paper 0.03–0.04. :func:`table_cast` finds the image's most
common chromaticity (the table's, a mode: the cubes, the wooden table around a
board and the arm do not move it) and :func:`white_balanced` divides out, von
Kries' way — the red and blue channels over the green by gains of the table's
own ratios — what of the table's cast lies beyond :data:`NEUTRAL_CAST` of grey,
when it lies no farther than :data:`MAX_CAST`: within :data:`NEUTRAL_CAST` the
photograph is taken as its camera balanced it (the thresholds were measured on
such photographs), and a cast a little beyond it is taken back to it, not to
grey, so that no photograph's colours jump with a small change of its light;
farther than :data:`MAX_CAST` the table is taken to be of a colour of its own (a
blue table top lies 0.63 from grey, over-exposed 0.35–0.42), which no white
balance explains.
"""

from __future__ import annotations

import math

import numpy as np

from demoplan.perception.opencv import cv2

__all__ = ["MAX_CAST", "NEUTRAL_CAST", "table_cast", "white_balanced"]

NEUTRAL_CAST = 0.1
"""The table's distance from grey in ``(ln R/G, ln B/G)`` up to which a photograph is
taken as balanced (the development photographs' boards: 0.04–0.08; a factor of about
1.1 between two channels)."""
MAX_CAST = 0.3
"""The farthest the table may lie from grey for its colour to be taken for a cast
(a factor of about 1.35 between two channels of the encoded values, about 1.9 in linear
light); farther, the table has a colour of its own."""
_STEP = 4
"""Every 4th pixel of every 4th row measures the table's chromaticity."""
_BIN = 0.02
"""The histogram's bin in ``(ln R/G, ln B/G)``."""
_SPAN = 1.0
"""The histogram covers ±1 (a factor e between two channels) around grey."""
_NEAR = 0.05
"""The pixels within this of the histogram's peak give the table's chromaticity (their
median)."""
_DARK, _CLIPPED = 20, 250
"""Pixels with a channel below 20 (noise dominates the ratios) or above 250 (clipped:
the ratios are the sensor's limit) say nothing of the light."""


_LOGS = np.log(np.maximum(np.arange(256, dtype=np.float32), 1.0))
"""ln of each 8-bit level (a table: the sampled pixels' logs looked up, not computed)."""


def table_cast(image: np.ndarray) -> tuple[float, float] | None:
    """The most common chromaticity of ``image`` (H × W × 3, 8-bit RGB) as
    ``(ln R/G, ln B/G)`` — the table's, in a top view — or ``None`` when too few pixels
    are neither dark nor clipped (or the image is not RGB)."""
    if image.ndim != 3 or image.shape[2] != 3:
        return None
    red, green, blue = cv2.split(np.ascontiguousarray(image[::_STEP, ::_STEP], dtype=np.uint8))
    lowest = cv2.min(cv2.min(red, green), blue)
    usable = (lowest >= _DARK) & (cv2.max(cv2.max(red, green), blue) <= _CLIPPED)
    if int(usable.sum()) < 100:
        return None
    log_green = _LOGS[green[usable]]
    red_ratio, blue_ratio = _LOGS[red[usable]] - log_green, _LOGS[blue[usable]] - log_green
    bins = round(2 * _SPAN / _BIN)
    rows = np.clip(((red_ratio + _SPAN) / _BIN).astype(np.intp), 0, bins - 1)
    cols = np.clip(((blue_ratio + _SPAN) / _BIN).astype(np.intp), 0, bins - 1)
    counts = np.bincount(rows * bins + cols, minlength=bins * bins).reshape(bins, bins)
    smooth = cv2.GaussianBlur(counts.astype(np.float32), (0, 0), 1.5)
    row, col = np.unravel_index(int(np.argmax(smooth)), smooth.shape)
    peak_red, peak_blue = -_SPAN + (row + 0.5) * _BIN, -_SPAN + (col + 0.5) * _BIN
    near = (np.abs(red_ratio - peak_red) < _NEAR) & (np.abs(blue_ratio - peak_blue) < _NEAR)
    return float(np.median(red_ratio[near])), float(np.median(blue_ratio[near]))


def white_balanced(image: np.ndarray) -> np.ndarray:
    """``image`` (H × W × 3, 8-bit RGB) with what of its table's cast
    (:func:`table_cast`) lies beyond :data:`NEUTRAL_CAST` divided out of its red and
    blue channels (the cast shortened to :data:`NEUTRAL_CAST`, its direction kept),
    when the table lies between :data:`NEUTRAL_CAST` and :data:`MAX_CAST` from grey;
    else ``image`` itself (the same array)."""
    cast = table_cast(image)
    if cast is None:
        return image
    distance = math.hypot(*cast)
    if not NEUTRAL_CAST < distance <= MAX_CAST:
        return image
    beyond = 1.0 - NEUTRAL_CAST / distance  # the share of the cast divided out
    levels = np.arange(256, dtype=np.float64)
    tables = [
        np.clip(np.round(levels * math.exp(-beyond * cast[0])), 0, 255),
        levels,
        np.clip(np.round(levels * math.exp(-beyond * cast[1])), 0, 255),
    ]
    lut = np.stack(tables, axis=1).astype(np.uint8).reshape(256, 1, 3)
    return np.asarray(cv2.LUT(np.ascontiguousarray(image, dtype=np.uint8), lut))
