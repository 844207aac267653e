"""Camera frames from files: image files in the order given, or one video file
(read with imageio-ffmpeg, the ``sim`` extra). Frames are read one at a time,
never all held; the limits are docs/limits.md's.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from demoplan.errors import InputError
from demoplan.fileio import display_path, require_regular_file
from demoplan.perception.camera import load_image
from demoplan.perception.sequence import Frame

__all__ = [
    "MAX_FRAMES",
    "MAX_FRAME_PIXELS",
    "VIDEO_SUFFIXES",
    "FrameSource",
    "frame_source",
]

MAX_FRAMES = 10_000
"""Frames of one sequence at most (5.5 minutes at 30 frames a second)."""
MAX_FRAME_PIXELS = 8_294_400
"""Pixels of one frame at most (3840 × 2160, a 4K frame)."""
MAX_VIDEO_BYTES = 4 * 1024**3
VIDEO_SUFFIXES = frozenset({".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg"})


class FrameSource:
    """The frames of image files or of one video file, and how many (None: a
    video's count is known only once read)."""

    def __init__(self, paths: Sequence[Path]):
        if not paths:
            raise InputError("no frames; one or more image files, or one video file, expected")
        videos = [p for p in paths if p.suffix.lower() in VIDEO_SUFFIXES]
        if videos and len(paths) > 1:
            raise InputError(
                "a video is a sequence of its own; one video file, or image files only, expected",
                source=display_path(videos[0]),
            )
        if len(paths) > MAX_FRAMES:
            raise InputError(
                f"{len(paths):,} frames; at most {MAX_FRAMES:,} expected (docs/limits.md)"
            )
        self.paths = list(paths)
        self.video = paths[0] if videos else None
        self.total: int | None = None if videos else len(paths)

    def __iter__(self) -> Iterator[Frame]:
        if self.video is not None:
            yield from _video_frames(self.video)
            return
        for path in self.paths:
            image = load_image(path)
            height, width = image.shape[:2]
            if height * width > MAX_FRAME_PIXELS:
                raise InputError(
                    f"{width} × {height} pixels; a frame of at most {MAX_FRAME_PIXELS:,} "
                    "pixels expected (docs/limits.md)",
                    source=display_path(path),
                )
            yield Frame(display_path(path), image)


def frame_source(paths: Sequence[Path]) -> FrameSource:
    """The frames ``paths`` hold (see :class:`FrameSource`)."""
    return FrameSource(paths)


def _video_frames(path: Path) -> Iterator[Frame]:
    source = display_path(path)
    try:
        import imageio_ffmpeg  # type: ignore[import-untyped]
    except ImportError:
        raise InputError(
            "reading a video needs imageio-ffmpeg: pip install 'demoplan[sim]' "
            "(or give the frames as image files)",
            source=source,
        ) from None
    require_regular_file(path, "a video file (MP4, AVI, MOV, MKV, WebM)", MAX_VIDEO_BYTES)
    reader = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    try:
        try:
            meta = reader.__next__()
        except (OSError, RuntimeError, StopIteration, ValueError) as exc:
            reason = str(exc).strip().splitlines()[0] if str(exc).strip() else "no video stream"
            raise InputError(f"not a readable video ({reason[:120]})", source=source) from None
        width, height = (int(v) for v in meta.get("size", (0, 0)))
        if width <= 0 or height <= 0:
            raise InputError("not a readable video (no frame size)", source=source)
        if width * height > MAX_FRAME_PIXELS:
            raise InputError(
                f"frames of {width} × {height} pixels; at most {MAX_FRAME_PIXELS:,} "
                "pixels expected (docs/limits.md)",
                source=source,
            )
        for index, data in enumerate(reader, start=1):
            if index > MAX_FRAMES:
                raise InputError(
                    f"more than {MAX_FRAMES:,} frames; at most that many expected (docs/limits.md)",
                    source=source,
                )
            image = np.frombuffer(data, dtype=np.uint8)
            if image.size != width * height * 3:
                raise InputError(f"frame {index} is truncated", source=source)
            yield Frame(f"{source} frame {index}", image.reshape(height, width, 3))
    except (OSError, RuntimeError) as exc:
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else "unreadable"
        raise InputError(f"not a readable video ({reason[:120]})", source=source) from None
    finally:
        reader.close()
