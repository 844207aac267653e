"""The top-down orthographic camera of docs/formats.md "Camera image".

``px_per_m`` pixels per metre; ``origin`` = world (x, y) of the image's
bottom-left corner; image x to the right = world x, image up = world y. A
pixel's centre (row r, column c) of an H-row image lies at
``x = X0 + (c + 0.5) / S``, ``y = Y0 + (H − r − 0.5) / S``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from demoplan.errors import InputError
from demoplan.fileio import require_regular_file

__all__ = ["Camera", "encode_png", "load_image", "save_image"]

MAX_PIXELS = 50_000_000  # a larger "image" is a mistake or an attack (decompression bomb)
MAX_IMAGE_BYTES = 256 * 1024 * 1024  # the file itself
MAX_SIDE = 20_000  # pixels on a side: a 1 × 40,000,000 strip is no camera image


@dataclass(frozen=True, slots=True)
class Camera:
    """Scale (px/m) and the world position of the image's bottom-left corner (m)."""

    px_per_m: float
    origin: tuple[float, float] = (0.0, 0.0)

    def to_world(self, u: float, v: float) -> tuple[float, float]:
        """(u, v) in pixels from the bottom-left corner (v up) → world (x, y)."""
        return self.origin[0] + u / self.px_per_m, self.origin[1] + v / self.px_per_m

    def image_outline_to_world(
        self, outline: np.ndarray, height: int
    ) -> tuple[tuple[float, float], ...]:
        """An outline's points (x right, y down: whole pixels of an image ``height``
        rows tall, N × 2) → the world (x, y) of their pixels' centres: what
        :meth:`to_world` gives for each, with NumPy (a photograph's rejected regions
        have tens of thousands of outline points)."""
        points = np.asarray(outline, dtype=float).reshape(-1, 2)
        xs = self.origin[0] + (points[:, 0] + 0.5) / self.px_per_m
        ys = self.origin[1] + (height - points[:, 1] - 0.5) / self.px_per_m
        return tuple(zip(xs.tolist(), ys.tolist(), strict=True))

    def to_pixels(self, x: float, y: float) -> tuple[float, float]:
        """World (x, y) → (u, v) in pixels from the bottom-left corner (v up)."""
        return (x - self.origin[0]) * self.px_per_m, (y - self.origin[1]) * self.px_per_m


def load_image(path: str | Path) -> np.ndarray:
    """An RGB image as ``uint8`` (H × W × 3); alpha is dropped, grey is made RGB."""
    from PIL import Image, UnidentifiedImageError

    # PIL's own bomb check would refuse a header past twice its limit in its words,
    # before the size check below can name the size and the limits: that check
    # runs on the header alone, before anything is decoded
    Image.MAX_IMAGE_PIXELS = None
    require_regular_file(Path(path), "an image (PNG, JPEG)", MAX_IMAGE_BYTES)
    try:
        with Image.open(path) as opened:  # reads the header only
            width, height = opened.size
            if width * height > MAX_PIXELS or max(width, height) > MAX_SIDE:
                raise InputError(
                    f"not a readable image ({width} × {height} pixels; at most "
                    f"{MAX_PIXELS:,} pixels and {MAX_SIDE:,} on a side expected)",
                    source=str(path),
                )
            if opened.mode in {"I", "I;16", "I;16B", "I;16L", "I;16N"}:
                # 16-bit grey: keep the top 8 bits (convert("RGB") would clip to white)
                grey = np.asarray(opened).astype(np.int64)
                scale = 8 if grey.max(initial=0) > 255 else 0
                eight = np.clip(grey >> scale, 0, 255).astype(np.uint8)
                return np.repeat(eight[..., None], 3, axis=2)
            if opened.format == "PNG" and opened.mode in {"RGB", "RGBA"}:
                decoded = _eight_bit_png(Path(path), (height, width))
                if decoded is not None:
                    return decoded
            rgb = opened.convert("RGB")
            return np.asarray(rgb, dtype=np.uint8).copy()
    except InputError:
        raise
    except FileNotFoundError:
        raise InputError("no such file", source=str(path)) from None
    except (UnidentifiedImageError, Image.DecompressionBombError, OSError, ValueError) as exc:
        raise InputError(f"not a readable image ({exc})", source=str(path)) from None


def _eight_bit_png(path: Path, shape: tuple[int, int]) -> np.ndarray | None:
    """An 8-bit RGB or RGBA PNG (its header says so) decoded by OpenCV, alpha
    dropped: the pixels PIL gives, for 85-90 % of PIL's CPU (a 1280 × 720
    photograph: 20-21.5 ms against 23-24); ``None`` for any other PNG."""
    data = np.fromfile(path, dtype=np.uint8)
    if (
        data.size < 26
        or data[12:16].tobytes() != b"IHDR"
        or data[24] != 8
        or data[25] not in (2, 6)
    ):
        return None  # IHDR: bit depth 8, colour type 2 (RGB) or 6 (RGBA)
    from demoplan.perception.opencv import cv2

    bgr = cv2.imdecode(data, cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION)
    if bgr is None or bgr.shape != (*shape, 3):
        return None
    return np.asarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))


def encode_png(image: np.ndarray) -> bytes:
    """An RGB ``uint8`` image as PNG bytes."""
    import io

    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(np.asarray(image, dtype=np.uint8)).save(buffer, format="PNG")
    return buffer.getvalue()


def save_image(image: np.ndarray, path: str | Path) -> None:
    """Write an RGB ``uint8`` image as PNG, atomically."""
    from demoplan.fileio import write_atomic_bytes

    write_atomic_bytes(Path(path), encode_png(image))
