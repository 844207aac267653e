"""A labelled photograph as another camera, or another day, would give it: the
same cubes under another exposure, white balance, tone curve, sensor noise, JPEG
compression, resolution, focus or orientation — the image changed and its label
changed with it, so that the same scoring (``demoplan.perception.labelled``)
tells whether the detector still finds the cubes a person sees.

A :class:`CameraVariation` names its parameters (all neutral by default);
:func:`vary_image` and :func:`vary_label` apply it to an image and to its label
(pure functions: the sensor noise is drawn from ``seed``). The image is changed
in this order: the geometry (mirror, quarter turns, scale), the optics (a
Gaussian blur), the light on the encoded values (white balance gains per channel,
then the exposure gain, clipped at 255 as a sensor clips, then the tone curve
``255 · (value / 255) ** gamma``), the sensor noise (Gaussian, σ in encoded
levels, clipped) and last the JPEG compression. :data:`VARIATIONS` are the
variations the camera benchmark (``benchmarks/perception_camera.py``) tables.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from demoplan.errors import UsageError
from demoplan.perception.labelled import LabelledBlock, LabelledPhoto

__all__ = [
    "VARIATIONS",
    "CameraVariation",
    "varied_photo",
    "vary_image",
    "vary_label",
]


@dataclass(frozen=True, slots=True)
class CameraVariation:
    """One camera's (or day's) difference from the photograph as taken.

    ``gain`` multiplies the encoded (sRGB) values — not the light: 0.75 there is
    about 0.8–0.9 of a stop under in linear light; ``white`` multiplies the red,
    green and blue values (a white balance);
    ``gamma`` is the exponent of the tone curve; ``noise`` the sensor noise's σ
    in 8-bit levels; ``jpeg`` the JPEG quality (1–95; ``None``: not compressed);
    ``scale`` the resolution's factor (Lanczos); ``blur`` the σ (px, after
    scaling) of a Gaussian blur; ``mirror`` mirrors left to right and ``turns``
    turns the image by that many quarter turns counter-clockwise (after the
    mirror)."""

    gain: float = 1.0
    white: tuple[float, float, float] = (1.0, 1.0, 1.0)
    gamma: float = 1.0
    noise: float = 0.0
    jpeg: int | None = None
    scale: float = 1.0
    blur: float = 0.0
    mirror: bool = False
    turns: int = 0

    def __post_init__(self) -> None:
        if not (self.gain > 0 and self.gamma > 0 and self.scale > 0):
            raise UsageError("gain, gamma and scale must be positive")
        if len(self.white) != 3 or not all(w > 0 for w in self.white):
            raise UsageError("white: three positive channel gains expected")
        if not (self.noise >= 0 and self.blur >= 0):
            raise UsageError("noise and blur must not be negative")
        if self.jpeg is not None and not 1 <= self.jpeg <= 95:
            raise UsageError("jpeg: a quality from 1 to 95 expected")

    @property
    def photometric(self) -> bool:
        """Whether it changes the values only (the label stays as it is)."""
        return self.scale == 1.0 and not self.mirror and self.turns % 4 == 0


VARIATIONS: Mapping[str, CameraVariation] = {
    "none": CameraVariation(),
    "mirror": CameraVariation(mirror=True),
    "turn90": CameraVariation(turns=1),
    "turn180": CameraVariation(turns=2),
    "scale0.6": CameraVariation(scale=0.6),
    "scale0.8": CameraVariation(scale=0.8),
    "scale1.25": CameraVariation(scale=1.25),
    "jpeg40": CameraVariation(jpeg=40),
    "gamma0.7": CameraVariation(gamma=0.7),
    "gamma1.4": CameraVariation(gamma=1.4),
    "gain0.75": CameraVariation(gain=0.75),
    "gain1.2": CameraVariation(gain=1.2),
    "noise6": CameraVariation(noise=6.0),
    "blur1.5": CameraVariation(blur=1.5),
    "warm": CameraVariation(white=(1.12, 1.0, 0.85)),
    "cool": CameraVariation(white=(0.88, 1.0, 1.12)),
}
"""The named variations the camera benchmark tables: each one parameter away from
the photograph as taken (the encoded values × 0.75, about 0.8–0.9 of a stop
under, is ``gain0.75``; ``warm`` is a tungsten-leaning white balance, ``cool`` a
shade-leaning one)."""


def _resized_shape(width: int, height: int, scale: float) -> tuple[int, int]:
    return max(1, round(width * scale)), max(1, round(height * scale))


def vary_image(
    image: NDArray[np.uint8], variation: CameraVariation, *, seed: int = 0
) -> NDArray[np.uint8]:
    """``image`` (H × W × 3, 8-bit RGB) as ``variation`` gives it (a new array);
    the sensor noise drawn from ``seed``."""
    from PIL import Image, ImageFilter

    picture = np.asarray(image, dtype=np.uint8)
    if variation.mirror:
        picture = picture[:, ::-1]
    picture = np.rot90(picture, variation.turns % 4)
    pil = Image.fromarray(np.ascontiguousarray(picture))
    if variation.scale != 1.0:
        pil = pil.resize(
            _resized_shape(pil.width, pil.height, variation.scale), Image.Resampling.LANCZOS
        )
    if variation.blur > 0:
        pil = pil.filter(ImageFilter.GaussianBlur(variation.blur))
    values = np.asarray(pil, dtype=np.float64)
    if variation.white != (1.0, 1.0, 1.0) or variation.gain != 1.0:
        values = values * (np.asarray(variation.white) * variation.gain)
    if variation.gamma != 1.0:
        values = 255.0 * (np.clip(values, 0.0, 255.0) / 255.0) ** variation.gamma
    if variation.noise > 0:
        values = values + np.random.default_rng(seed).normal(0.0, variation.noise, values.shape)
    out = np.clip(values, 0.0, 255.0).round().astype(np.uint8)
    if variation.jpeg is not None:
        buffer = io.BytesIO()
        Image.fromarray(out).save(buffer, "JPEG", quality=variation.jpeg)
        buffer.seek(0)
        with Image.open(buffer) as compressed:
            out = np.asarray(compressed.convert("RGB"), dtype=np.uint8)
    return np.ascontiguousarray(out)


def _moved(
    block: LabelledBlock, variation: CameraVariation, width: int, height: int
) -> LabelledBlock:
    """``block``'s centre where the image's geometry puts it (pixel centres at
    integers; a turn maps the old pixel (u, v) of a W-wide image to (v, W − 1 − u))."""
    u, v = block.u, block.v
    if variation.mirror:
        u = width - 1 - u
    for _ in range(variation.turns % 4):
        u, v, width, height = v, width - 1 - u, height, width
    side = block.side_px
    if variation.scale != 1.0:
        new_w, new_h = _resized_shape(width, height, variation.scale)
        sx, sy = new_w / width, new_h / height
        u, v, side = (u + 0.5) * sx - 0.5, (v + 0.5) * sy - 0.5, side * (sx + sy) / 2
    return replace(block, u=u, v=v, side_px=side)


def vary_label(photo: LabelledPhoto, variation: CameraVariation) -> LabelledPhoto:
    """``photo``'s label for the image ``variation`` makes of it: the faces'
    centres and sides moved with the image, its size and scale (px per m) with
    them. The image file is left as it was (:func:`varied_photo` writes one)."""
    width, height = photo.width, photo.height
    if variation.turns % 2:
        width, height = height, width
    scale = 1.0
    if variation.scale != 1.0:
        new_w, new_h = _resized_shape(width, height, variation.scale)
        scale = (new_w / width + new_h / height) / 2
        width, height = new_w, new_h
    blocks = tuple(_moved(b, variation, photo.width, photo.height) for b in photo.blocks)
    return replace(
        photo, width=width, height=height, px_per_m=photo.px_per_m * scale, blocks=blocks
    )


def varied_photo(
    photo: LabelledPhoto,
    variation: CameraVariation,
    folder: str | Path,
    name: str,
    *,
    seed: int = 0,
) -> LabelledPhoto:
    """``photo`` as ``variation`` gives it: its image varied and written to
    ``folder`` (PNG, named ``name``), its label varied to match."""
    from PIL import Image

    with Image.open(photo.image) as opened:
        image = np.asarray(opened.convert("RGB"), dtype=np.uint8)
    varied = vary_image(image, variation, seed=seed)
    path = Path(folder) / f"{name}.png"
    Image.fromarray(varied).save(path)
    label = vary_label(photo, variation)
    return replace(label, name=name, image=path)
