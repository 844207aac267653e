"""Writing outputs all or none: atomic writes (a temporary file in the
target's folder, flushed and renamed over the target, so a reader never sees
half a file and a failed write leaves the old one in place), several files
staged together (:class:`StagedOutputs`), output targets (files, devices and
pipes), safe file names, and never an input overwritten."""

from __future__ import annotations

import json
import os
import re
import stat
import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

from demoplan.errors import InputError
from demoplan.fileio.paths import (
    display_path,
    file_kind,
    os_reason,
)

__all__ = [
    "MAX_FILE_NAME_BYTES",
    "UPDATE_WAIT_SECONDS",
    "StagedOutputs",
    "check_output_folder",
    "current_umask",
    "dump_json",
    "file_inside",
    "locked_for_update",
    "make_folders",
    "output_target",
    "refuse_overwriting_inputs",
    "remove_made_folders",
    "safe_file_name",
    "short_name",
    "sync_folder",
    "write_atomic",
    "write_atomic_bytes",
]


def dump_json(data: Any) -> str:
    """JSON text as demoplan writes it: indented, UTF-8, no NaN."""
    return json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False) + "\n"


UPDATE_WAIT_SECONDS = 60.0
"""How long ``learn --update`` waits for another update of the same folder."""


@contextmanager
def locked_for_update(path: Path, wait: float = UPDATE_WAIT_SECONDS) -> Iterator[None]:
    """Hold an exclusive lock (``fcntl.flock``) on the folder of ``path`` for a
    read-modify-write of it, so that two updates at once both land: the second
    waits for the first (up to ``wait`` seconds, then one InputError). The lock
    is on the folder, not the file, because the atomic write replaces the file
    (a lock on the old file would not keep a third process out); no lock file
    is left behind, and the lock goes with the process however it ends."""
    import fcntl

    folder = Path(path).parent if str(Path(path).parent) else Path()
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError as exc:
        raise InputError(f"cannot lock for update ({os_reason(exc)})", source=str(path)) from None
    try:
        deadline = time.monotonic() + wait
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise InputError(
                        f"another demoplan has been updating its folder for {wait:g} s; "
                        "try again when it has finished",
                        source=str(path),
                    ) from None
                time.sleep(0.02)
        yield
    finally:
        os.close(fd)  # releases the lock


def output_target(path: Path, *, stream_ok: bool = True) -> tuple[Path, bool]:
    """Where an output file named ``path`` is written, by the one rule every
    writer follows (docs/limits.md, "Outputs"): ``(target, stream)``.

    - missing, or a regular file: written atomically, a temporary file renamed
      over ``target`` — a link to a regular file is followed, so the link stays
      and the file it names is replaced;
    - a character device or a pipe (``/dev/null``, ``/dev/stdout``, a FIFO)
      when ``stream_ok``: ``stream`` is True and the bytes are written into it
      directly, never renamed over, removed or truncated;
    - anything else (a folder, a block device, a socket, a device where a
      seekable file is needed): one InputError, "not a regular file".
    """
    path = Path(path)
    shown = display_path(path)
    try:
        info = path.stat()  # follows links
    except FileNotFoundError:
        return path, False  # a new file (or a dangling link, replaced by the file)
    except OSError as exc:
        raise InputError(f"cannot write ({os_reason(exc, path)})", source=shown) from None
    except ValueError:  # a NUL byte in the name
        raise InputError("not a valid file name", source=shown) from None
    if stat.S_ISREG(info.st_mode):
        return (Path(os.path.realpath(path)) if path.is_symlink() else path), False
    if stat.S_ISDIR(info.st_mode):
        raise InputError("is a folder; a file name expected", source=shown)
    if stream_ok and (stat.S_ISCHR(info.st_mode) or stat.S_ISFIFO(info.st_mode)):
        return path, True
    needed = (
        "a regular file, a character device or a pipe expected"
        if stream_ok
        else "a regular file expected (this output is written as a whole file)"
    )
    raise InputError(f"is {file_kind(info.st_mode)}, not a regular file; {needed}", source=shown)


def _write_stream(path: Path, data: bytes) -> None:
    """``data`` written straight into a character device or a pipe: opened
    without creating or truncating anything (a pipe waits for its reader;
    Ctrl-C stops the wait)."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_NOCTTY | getattr(os, "O_CLOEXEC", 0))
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
    except OSError as exc:
        raise InputError(f"cannot write ({os_reason(exc)})", source=display_path(path)) from None


class StagedOutputs:
    """The output files of one command, written all or none.

    Each target follows :func:`output_target`. :meth:`add` stages a file in
    a temporary file beside its target (created exclusively, never through a
    link), making the folders it needs; leaving the ``with`` block normally
    first writes the character devices and pipes among the targets (which
    cannot be staged), then renames the staged files into place with SIGINT
    and SIGTERM held back, so that Ctrl-C cannot split the renames. Leaving it
    by an exception — a failed plot, a full disk, Ctrl-C — or a failed write
    into a device or a failed rename removes the temporary files and the
    folders it made, and puts back every file it had already replaced: every
    regular target is as it was. A special file is never renamed over,
    removed or truncated.
    """

    def __init__(self) -> None:
        self._staged: list[tuple[Path, Path]] = []
        self._streams: list[tuple[Path, bytes]] = []
        self._made: list[Path] = []

    def __enter__(self) -> StagedOutputs:
        return self

    def add(self, path: Path, data: bytes, *, stream_ok: bool = True) -> None:
        target, stream = output_target(Path(path), stream_ok=stream_ok)
        if stream:
            self._streams.append((target, data))
        else:
            temporary, made = _write_temporary(target, data)
            self._made.extend(made)
            self._staged.append((temporary, target))

    def __exit__(self, kind: object, error: object, trace: object) -> None:
        if kind is not None:
            self._discard()
            return
        try:
            for path, data in self._streams:
                _write_stream(path, data)
        except BaseException:
            self._discard()
            raise
        import signal

        held = {signal.SIGINT, signal.SIGTERM}
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
        try:
            self._rename_all()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)

    def _rename_all(self) -> None:
        """Every staged file renamed over its target, the old files kept aside
        (hard links) until all are in place; on a failure the replaced files
        are put back and the new ones removed."""
        done: list[tuple[Path, Path | None]] = []  # (target, the old file kept aside)
        try:
            for temporary, path in self._staged:
                kept = _keep_aside(path)
                try:
                    temporary.replace(path)
                except OSError:
                    if kept is not None:
                        kept.unlink(missing_ok=True)
                    raise
                done.append((path, kept))
        except (OSError, InputError) as exc:
            for replaced, kept in reversed(done):
                with suppress(OSError):
                    if kept is None:
                        replaced.unlink()
                    else:
                        kept.replace(replaced)
            self._discard()
            if isinstance(exc, InputError):
                raise
            raise InputError(
                f"cannot write ({os_reason(exc)})", source=display_path(path)
            ) from None
        for _, kept in done:
            if kept is not None:
                kept.unlink(missing_ok=True)
        for folder in {path.parent for _, path in self._staged}:
            sync_folder(folder if str(folder) else Path())

    def _discard(self) -> None:
        for temporary, _ in self._staged:
            temporary.unlink(missing_ok=True)
        remove_made_folders(self._made)
        self._staged.clear()
        self._streams.clear()
        self._made.clear()


def _keep_aside(path: Path) -> Path | None:
    """The file at ``path`` kept under a new name beside it — a hard link,
    made exclusively (or a copy where the file system has no hard links) —
    to put back if a later rename of the same command fails; None where
    there is no file yet."""
    import secrets
    import shutil

    folder = path.parent if str(path.parent) else Path()
    for _ in range(100):
        aside = folder / f".{short_name(path.name)}.{secrets.token_hex(4)}.old"
        try:
            os.link(path, aside, follow_symlinks=False)
        except FileNotFoundError:
            return None
        except FileExistsError:
            continue
        except OSError:  # no hard links here (EPERM, ENOTSUP): an exclusive copy
            break
        return aside
    try:
        fd, name = tempfile.mkstemp(prefix=f".{short_name(path.name)}.", suffix=".old", dir=folder)
        with os.fdopen(fd, "wb") as copy, path.open("rb") as original:
            shutil.copyfileobj(original, copy)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise InputError(f"cannot write ({os_reason(exc)})", source=display_path(path)) from None
    return Path(name)


def short_name(name: str) -> str:
    """A file name cut to leave room for a temporary name's additions (a name
    is at most 255 bytes)."""
    return name if len(os.fsencode(name)) <= 200 else name[:50]


def make_folders(folder: Path) -> list[Path]:
    """Make ``folder`` and the folders above it that are missing; the ones
    this call made, outermost first (for :func:`remove_made_folders` if the
    command fails). On an error, nothing is left made and OSError is raised."""
    missing: list[Path] = []
    current = Path(folder)
    while str(current) not in {"", "."} and not os.path.lexists(current):
        missing.append(current)
        if current.parent == current:
            break
        current = current.parent
    made: list[Path] = []
    try:
        for path in reversed(missing):
            try:
                path.mkdir()
            except FileExistsError:  # made meanwhile by someone else: not ours to remove
                continue
            made.append(path)
    except BaseException:
        remove_made_folders(made)
        raise
    return made


def remove_made_folders(made: Sequence[Path]) -> None:
    """Remove the folders :func:`make_folders` made, innermost first, each
    only if it is empty (someone else may have written there meanwhile)."""
    for path in reversed(made):
        with suppress(OSError):
            path.rmdir()


def check_output_folder(path: Path) -> None:
    """One InputError if ``path`` exists and is not a folder: a folder output
    never replaces a file, a device, a pipe or a socket (docs/limits.md)."""
    try:
        info = Path(path).stat()
    except FileNotFoundError:
        return
    except OSError as exc:
        raise InputError(
            f"cannot write ({os_reason(exc, path)})", source=display_path(path)
        ) from None
    if not stat.S_ISDIR(info.st_mode):
        kind = "a file" if stat.S_ISREG(info.st_mode) else file_kind(info.st_mode)
        raise InputError(
            f"exists and is {kind}, not a folder; a folder expected", source=display_path(path)
        )


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically; see :func:`write_atomic_bytes`.
    Characters UTF-8 cannot hold (a file name's undecodable bytes, kept by
    Python as lone surrogates) are written as ``\\udcXX`` escapes, which JSON
    reads back as the same string."""
    write_atomic_bytes(path, text.encode("utf-8", "backslashreplace"))


def write_atomic_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temp file in the same folder + rename),
    by the rule of :func:`output_target`: a character device or a pipe
    (``/dev/null``, ``/dev/stdout``) is written into directly, never replaced.

    The new file gets the old file's permissions, or the usual ones for a new
    file (0666 less the umask) — not the 0600 of a bare temporary file. Any
    failure leaves ``path`` as it was, removes the temporary file and raises
    :class:`InputError` naming ``path``.
    """
    with StagedOutputs() as outputs:
        outputs.add(path, data)


def hold_signals() -> set[int]:
    """Hold SIGINT and SIGTERM back (this thread); the mask before, to restore."""
    import signal

    return signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})


def restore_signals(previous: set[int]) -> None:
    """Put back the signal mask ``previous`` (:func:`hold_signals`): a signal held
    back meanwhile is delivered here."""
    import signal

    signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _write_temporary(path: Path, data: bytes) -> tuple[Path, list[Path]]:
    """``data`` in a new temporary file beside ``path`` with ``path``'s
    permissions, flushed to disk: the first half of an atomic write (the
    caller renames it into place). The temporary file is created
    exclusively (``mkstemp``: ``O_EXCL``, never through a link). Returns it
    and the folders made for it. On failure nothing is left (the folders
    made are removed) and one InputError names ``path``."""
    if path.is_dir():
        raise InputError("is a folder; a file name expected", source=display_path(path))
    folder = path.parent if str(path.parent) else Path()
    made: list[Path] = []
    # SIGINT and SIGTERM held back from making the file until the block that
    # removes it is entered (a signal landing in mkstemp, after its open and before
    # it returned, left the file behind), and while it is removed
    previous = hold_signals()
    try:
        made = make_folders(folder)
        fd, name = tempfile.mkstemp(prefix=f".{short_name(path.name)}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        remove_made_folders(made)
        restore_signals(previous)
        raise InputError(f"cannot write ({os_reason(exc)})", source=display_path(path)) from None
    except BaseException:
        restore_signals(previous)
        raise
    temporary = Path(name)
    try:
        with os.fdopen(fd, "wb") as handle:
            restore_signals(previous)  # a signal held back is raised here, in the block
            _set_mode(handle.fileno(), path)
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
    except BaseException as exc:
        hold_signals()
        try:
            temporary.unlink(missing_ok=True)
            remove_made_folders(made)
        finally:
            restore_signals(previous)
        if isinstance(exc, OSError):
            reason = os_reason(exc)
            raise InputError(f"cannot write ({reason})", source=display_path(path)) from None
        raise
    return temporary, made


def _set_mode(fd: int, path: Path) -> None:
    """Give the temporary file ``path``'s permissions, or a new file's (0666 & ~umask)."""
    if not hasattr(os, "fchmod"):  # pragma: no cover - Windows before 3.13
        return
    try:
        mode = stat.S_IMODE(path.stat().st_mode)
    except OSError:
        mode = 0o666 & ~current_umask()
    os.fchmod(fd, mode)


def current_umask() -> int:
    # Linux tells the umask without changing it (os.umask would, racing other threads).
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    umask = os.umask(0o022)
    os.umask(umask)
    return umask


def sync_folder(folder: Path) -> None:
    """Best effort: make the rename itself durable (POSIX)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def refuse_overwriting_inputs(target: Path, inputs: Sequence[Path]) -> None:
    """``-o`` must not name one of the input files (or lie in a folder read)."""
    # os.path.realpath, not Path.resolve: it does not raise on a loop of links
    resolved = Path(os.path.realpath(target))
    for path in inputs:
        source = Path(os.path.realpath(path))
        if resolved == source:
            raise InputError("is also an input; write the output elsewhere", source=str(target))
        if (
            source.is_dir()
            and resolved.parent == source
            and resolved.suffix in {".json", ".yaml", ".yml"}
        ):
            raise InputError(
                f"lies in the demonstration folder {path}, which would read it back as a "
                "demonstration next time; write the model elsewhere",
                source=str(target),
            )


MAX_FILE_NAME_BYTES = 120
"""The longest file name (UTF-8 bytes, before its extension) made from a name
read in an input (a recording's environment or keys): a file system takes 255."""


_UNSAFE_IN_FILE_NAME = re.compile(r"[^\w.+-]")


def safe_file_name(name: str, tag: str = "") -> str:
    """``name`` (drawn from an input file) reduced to one safe file name
    (docs/limits.md): every character but letters, digits and ``. _ + -`` —
    separators, control characters, spaces — becomes ``_``, a run of dots one
    dot, leading dots and dashes go (no ``..``, no hidden file, nothing a
    command would read as an option), the length is bounded by
    :data:`MAX_FILE_NAME_BYTES`; ``unnamed`` when nothing is left. ``tag``
    (safe already: ``-2``) is kept whole at the end."""
    reduced = re.sub(r"\.{2,}", ".", _UNSAFE_IN_FILE_NAME.sub("_", name)).lstrip(".-")
    reduced = reduced or "unnamed"
    while len((reduced + tag).encode("utf-8", "surrogatepass")) > MAX_FILE_NAME_BYTES:
        reduced = reduced[:-1]
    return reduced + tag


def file_inside(folder: Path, name: str, suffix: str, taken: Sequence[Path] = ()) -> Path:
    """``folder / (safe_file_name(name) + suffix)`` — with ``-2``, ``-3``, …
    after the name when that file is ``taken`` already — checked to stay in
    ``folder`` once resolved: a link planted there under that name, leading
    elsewhere, is refused (it would be written through)."""
    target = folder / (safe_file_name(name) + suffix)
    repeat = 1
    while target in taken:
        repeat += 1
        target = folder / (safe_file_name(name, f"-{repeat}") + suffix)
    inside = folder.resolve(strict=False)
    try:
        resolved = target.resolve(strict=False)
    except (OSError, RuntimeError):  # a loop of links
        resolved = Path("/")
    if resolved.parent != inside or target.name in {".", ".."}:
        raise InputError(
            f"is a link leading outside the folder {display_path(folder)} (to "
            f"{display_path(resolved)}); a file inside the folder expected",
            source=display_path(target),
        )
    return target
