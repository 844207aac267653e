"""What several stages of perception measure of one photograph, measured once.

The colour regions (:mod:`demoplan.perception.colours`), the seams between touching
tops (:mod:`demoplan.perception.seams`) and a stack's side faces
(:mod:`demoplan.perception.stack_sides`, twice: the lower cubes' faces in
:func:`~demoplan.perception.blocks.detect_blocks`, the standing tops when the sizes
are held, :mod:`demoplan.perception.sizes`) each converted the whole photograph to
CIELAB on their own. An :class:`ImageMeasures` of the photograph is handed from stage
to stage instead: each conversion is made the first time a stage asks for it, by the
code that stage ran before, and kept — the same values, a full-image conversion
(several milliseconds of a 1280 × 720 photograph) made once.
"""

from __future__ import annotations

from collections.abc import Hashable
from functools import cached_property
from typing import Any

import numpy as np

from demoplan.perception.opencv import cv2
from demoplan.perception.white_balance import white_balanced

__all__ = ["ImageMeasures", "measures_of"]


class ImageMeasures:
    """One RGB photograph (H × W × 3, 8-bit) and its conversions, each made once;
    ``image`` is the photograph with its table's colour cast divided out
    (:func:`~demoplan.perception.white_balance.white_balanced`: the photograph
    itself when its table is grey, or of a colour no white balance explains)."""

    def __init__(self, image: np.ndarray) -> None:
        self.image = white_balanced(image)
        self.answers: dict[Hashable, Any] = {}
        """What a stage worked out about this photograph that another stage asks
        again, by a key that starts with the stage's own name: made once per
        photograph, gone with it."""

    @cached_property
    def lab8(self) -> np.ndarray:
        """OpenCV's 8-bit CIELAB of the image (L* scaled by 255/100, a* and b* + 128)."""
        return np.asarray(
            cv2.cvtColor(np.ascontiguousarray(self.image, dtype=np.uint8), cv2.COLOR_RGB2Lab)
        )

    @cached_property
    def lightness(self) -> np.ndarray:
        """CIELAB L* (0–100, float32) from :attr:`lab8`."""
        return np.asarray(self.lab8[..., 0], dtype=np.float32) * np.float32(100.0 / 255.0)

    @cached_property
    def smooth_lab(self) -> np.ndarray:
        """CIELAB (L* 0–100, float32) of the image smoothed over 3 × 3 px."""
        smooth = cv2.blur(np.ascontiguousarray(self.image, dtype=np.uint8), (3, 3))
        return np.asarray(cv2.cvtColor(smooth.astype(np.float32) / 255.0, cv2.COLOR_RGB2Lab))


def measures_of(image: np.ndarray | ImageMeasures) -> ImageMeasures:
    """``image``'s measures: itself when it is an :class:`ImageMeasures`."""
    return image if isinstance(image, ImageMeasures) else ImageMeasures(image)
