"""``run --video``'s encoder: frames piped into an ffmpeg process whose exit
status is checked.

imageio-ffmpeg's frame writer closes ffmpeg's input and waits for it, but
never looks at how it ended: an ffmpeg that could not write its file (a full
disk: its trailer, the MP4's index, is written last) exits 1 and the run said
success. :class:`FrameEncoder` runs the same ffmpeg (imageio-ffmpeg's binary,
its command line) and :meth:`FrameEncoder.close` raises ``OSError`` — with
ffmpeg's own last error line — when the pipe was closed under it or it ended
with any status but 0. The caller (:mod:`demoplan.execution.runner`) turns
that into one error line and removes the file (docs/limits.md "Outputs").
"""

from __future__ import annotations

import collections
import os
import subprocess
import threading
from fractions import Fraction
from pathlib import Path
from typing import IO

import numpy as np

__all__ = ["FrameEncoder"]

QUALITY_CRF = 25
"""libx264's constant rate factor (imageio-ffmpeg's default quality 5 of 10)."""
FINISH_SECONDS = 120.0
"""How long ffmpeg may take to finish its file once the last frame is sent."""


def _leads_its_session() -> bool:
    """Whether this process leads its own session (no terminal's Ctrl-C
    reaches its group)."""
    return os.getsid(0) == os.getpid()


class FrameEncoder:
    """RGB frames of ``size`` (width, height) → an H.264 MP4 at ``path``."""

    def __init__(self, path: Path, size: tuple[int, int], fps: float) -> None:
        import imageio_ffmpeg  # type: ignore[import-untyped]

        width, height = size
        command = [
            imageio_ffmpeg.get_ffmpeg_exe(),
            "-y",
            "-f",
            "rawvideo",
            "-vcodec",
            "rawvideo",
            "-s",
            f"{width}x{height}",
            "-pix_fmt",
            "rgb24",
            "-r",
            str(Fraction(fps).limit_denominator()),
            "-i",
            "-",
            "-an",
            "-vcodec",
            "libx264",
            "-pix_fmt",
            "yuv420p",
            "-crf",
            str(QUALITY_CRF),
            "-v",
            "error",
            str(path),
        ]
        self.size = size
        # At a terminal, a session of its own: Ctrl-C reaches demoplan, which
        # stops ffmpeg. A process leading its own session (the studio's run
        # worker, cancelled by signalling its group) keeps ffmpeg in its group,
        # so that nothing of the run outlives the group's SIGKILL.
        self._process = subprocess.Popen(
            command,
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            start_new_session=not _leads_its_session(),
        )
        try:  # a Ctrl-C from here on stops the ffmpeg just started (no one else could)
            self._errors: collections.deque[str] = collections.deque(maxlen=20)
            stderr = self._process.stderr
            assert stderr is not None
            self._reader = threading.Thread(target=self._read_errors, args=(stderr,), daemon=True)
            self._reader.start()
            self._broken: str | None = None
        except BaseException:
            self.kill()
            raise

    def _read_errors(self, stream: IO[bytes]) -> None:
        """Keep ffmpeg's last error lines (drained as they come, so that a
        chatty ffmpeg never blocks on a full pipe)."""
        for line in stream:
            text = line.decode("utf-8", "replace").strip()
            if text:
                self._errors.append(text)

    def send(self, frame: np.ndarray) -> None:
        """One frame (height × width × 3, uint8); OSError if ffmpeg is gone."""
        stdin = self._process.stdin
        assert stdin is not None
        try:
            stdin.write(np.ascontiguousarray(frame, dtype=np.uint8).tobytes())
        except OSError as exc:  # BrokenPipeError: ffmpeg stopped (a full disk)
            self._broken = f"ffmpeg stopped taking frames ({exc.strerror or exc})"
            raise OSError(self._reason(self._broken)) from None

    def close(self) -> None:
        """Finish the file: close ffmpeg's input and wait for it; OSError if a
        frame could not be sent or ffmpeg ended with a status other than 0."""
        process = self._process
        try:
            if process.stdin is not None:
                try:
                    process.stdin.close()
                except OSError as exc:  # the last frames could not be flushed
                    self._broken = self._broken or f"ffmpeg stopped taking frames ({exc})"
            status = process.wait(timeout=FINISH_SECONDS)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
            raise OSError(f"ffmpeg did not finish the file within {FINISH_SECONDS:g} s") from None
        except BaseException:  # Ctrl-C while ffmpeg finishes: stop it
            process.kill()
            process.wait()
            raise
        finally:
            self._reader.join(timeout=5)
        if status != 0:
            raise OSError(self._reason(f"ffmpeg exited with status {status}"))
        if self._broken is not None:
            raise OSError(self._reason(self._broken))

    def kill(self) -> None:
        """Stop ffmpeg at once (the run is abandoned; its file is removed)."""
        if self._process.poll() is None:
            self._process.kill()
        self._process.wait()

    def _reason(self, what: str) -> str:
        last = self._errors[-1] if self._errors else ""
        return f"{what}: {last}" if last else what
