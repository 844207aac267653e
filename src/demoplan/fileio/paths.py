"""File names and OS errors in words, for one-line errors that name the file."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from demoplan.errors import InputError

__all__ = [
    "display_path",
    "file_kind",
    "os_error",
    "os_reason",
]


def display_path(path: Path | str | bytes) -> str:
    """A file name as it can be shown on one line: bytes that are not UTF-8
    and control characters (a newline, an escape) are written as escapes."""
    text = os.fsdecode(path) if isinstance(path, bytes) else str(path)
    if text.isprintable():
        return text
    shown = text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in shown)


def os_reason(exc: OSError, path: Path | str | None = None) -> str:
    """What an OSError means, in words (no errno, no repeated file name)."""
    reasons = {
        errno.ENOENT: "no such file",
        errno.ELOOP: "a loop of symbolic links",
        errno.EACCES: "permission denied",
        errno.EPERM: "permission denied",
        errno.ENAMETOOLONG: "file name too long",
        errno.ENOTDIR: "a part of the path is not a folder",
        errno.EISDIR: "is a folder",
        errno.ENOSPC: "no space left on the device",
        errno.EDQUOT: "disk quota exceeded",
        errno.EROFS: "read-only file system",
        errno.EIO: "input/output error",
    }
    reason = reasons.get(exc.errno or -1) or (exc.strerror or type(exc).__name__).lower()
    if exc.errno == errno.ENOENT and path is not None and Path(path).is_symlink():
        reason = "a symbolic link to a missing file"
    return reason


def os_error(exc: OSError) -> InputError:
    """An OSError as demoplan's one-line error, naming its file (exit 1)."""
    name = exc.filename if exc.filename is not None else None
    source = display_path(name) if name is not None else None
    return InputError(os_reason(exc, name), source=source)


def file_kind(mode: int) -> str:
    """A special file's kind, in words."""
    kinds = (
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a pipe (FIFO)"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISDIR, "a folder"),
    )
    return next((words for test, words in kinds if test(mode)), "not a regular file")
