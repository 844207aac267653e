"""``run --video``: where the MP4 is recorded and how it reaches its name.

ffmpeg writes the video into a new private folder beside the target
(``mkdtemp``: created exclusively, mode 0700, so no file or link planted
beside the target is ever opened, followed or truncated); when the run is
over the file is checked to be a complete MP4 and renamed over the target.
A run that fails, a video ffmpeg could not finish (a full disk, an exit
status other than 0: :mod:`demoplan.execution.encoder`) or Ctrl-C
removes the private folder and the folders made for it: nothing is left
(docs/limits.md, "Outputs").
"""

from __future__ import annotations

import glob
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from demoplan.errors import InputError, UsageError
from demoplan.fileio import (
    display_path,
    make_folders,
    os_reason,
    output_target,
    remove_made_folders,
)

__all__ = ["VideoOutput", "check_video_path", "complete_mp4", "partial_folders"]

_PARTIAL = "recording.mp4"  # ffmpeg picks the container from the extension


def check_video_path(video: Path) -> None:
    """Before any work: ``video`` can be written — an .mp4 path that is not a
    folder or a device, in a folder that exists or can be made and takes a
    new file. The check makes a private folder there and removes it (and any
    folder it made) at once: it creates nothing else and opens no file."""
    if video.suffix.lower() != ".mp4":
        raise UsageError(f"--video {video}: an .mp4 file expected")
    # An MP4 is finished by seeking back to its index: never a device or a pipe.
    target = output_target(video, stream_ok=False)[0]
    with _signals_held():  # Ctrl-C cannot come between making the probe and removing it
        VideoOutput(target).discard()


class VideoOutput:
    """The recording of one ``run --video``: :attr:`recording` is where
    ffmpeg writes; :meth:`finish` puts a complete MP4 at the target,
    :meth:`discard` leaves nothing. The target is ``output_target``'s: a
    link's file, not the link."""

    def __init__(self, target: Path) -> None:
        self.target = target
        folder = target.parent if str(target.parent) else Path()
        self._made: list[Path] = []
        try:
            with _signals_held():  # made and remembered, or not made
                self._made = make_folders(folder)
                self._private = Path(
                    tempfile.mkdtemp(prefix=f".{_short(target.name)}.", suffix=".part", dir=folder)
                )
        except OSError as exc:
            remove_made_folders(self._made)
            raise self.error(os_reason(exc)) from None
        except BaseException:  # a Ctrl-C held over the making comes as the hold ends
            if hasattr(self, "_private"):
                self.discard()
            else:
                remove_made_folders(self._made)
            raise
        self.recording = self._private / _PARTIAL

    def error(self, reason: str) -> InputError:
        """The one line for a video that cannot be written, naming the target
        (a full disk said as such: ffmpeg does not say why it stopped)."""
        if _disk_full(self.target.parent if str(self.target.parent) else Path()):
            reason = "no space left on the device"
        return InputError(f"cannot write the video ({reason})", source=display_path(self.target))

    def finish(self) -> None:
        """Rename the finished recording over the target, once it is checked
        to be a complete MP4; else :meth:`discard` and one InputError."""
        if not complete_mp4(self.recording):
            error = self.error("ffmpeg did not finish the file")
            self.discard()
            raise error
        try:
            self.recording.replace(self.target)  # ffmpeg made it 0666 less the umask
        except OSError as exc:
            self.discard()
            raise self.error(os_reason(exc)) from None
        self._private.rmdir()

    def discard(self) -> None:
        """Remove the recording, its private folder and the folders made for it."""
        shutil.rmtree(self._private, ignore_errors=True)
        remove_made_folders(self._made)


def partial_folders(target: Path) -> list[Path]:
    """The private folders a recording of ``target`` left beside it: none
    unless the process recording was killed (SIGKILL) before :meth:`VideoOutput.discard`
    ran. Its folders only, never a link."""
    folder = target.parent if str(target.parent) else Path()
    # mkdtemp's part: 8 of [a-z0-9_] (another target's folder, ``.NAME.mp4.….part``, is not)
    named = re.compile(rf"\.{re.escape(_short(target.name))}\.[a-z0-9_]{{8}}\.part")
    return [
        path
        for path in folder.glob(f".{glob.escape(_short(target.name))}.*.part")
        if named.fullmatch(path.name) and path.is_dir() and not path.is_symlink()
    ]


def complete_mp4(path: Path) -> bool:
    """Whether ``path`` is a whole MP4: top-level boxes that tile the file
    exactly, among them the header (``ftyp``), the frames (``mdat``) and the
    index (``moov``), which ffmpeg writes last — a file cut short by a full
    disk or a killed ffmpeg fails."""
    try:
        size = path.stat().st_size
        kinds: set[bytes] = set()
        with path.open("rb") as handle:
            position = 0
            while position < size:
                handle.seek(position)
                header = handle.read(8)
                if len(header) < 8:
                    return False
                length = int.from_bytes(header[:4], "big")
                if length == 1:  # a 64-bit size follows the kind
                    wide = handle.read(8)
                    if len(wide) < 8:
                        return False
                    length = int.from_bytes(wide, "big")
                elif length == 0:  # to the end of the file
                    length = size - position
                if length < 8 or position + length > size:
                    return False
                kinds.add(header[4:8])
                position += length
    except OSError:
        return False
    return {b"ftyp", b"mdat", b"moov"} <= kinds


@contextmanager
def _signals_held() -> Iterator[None]:
    """SIGINT and SIGTERM held back over a few system calls (delivered after)."""
    import signal

    held = {signal.SIGINT, signal.SIGTERM}
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _disk_full(folder: Path) -> bool:
    """Whether the disk of ``folder`` is (nearly) full, under a megabyte
    free: the likely reason ffmpeg could not finish a video (it says none)."""
    try:
        info = os.statvfs(folder)
    except OSError:
        return False
    return info.f_bavail * info.f_frsize < 1 << 20


def _short(name: str) -> str:
    return name if len(os.fsencode(name)) <= 200 else name[:50]
