"""Running a demoplan command and checking docs/cli.md's promises about its answer."""

from __future__ import annotations

import errno
import hashlib
import os
import stat
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from tests.support import forkserver

DEMOPLAN = forkserver.DEMOPLAN  # the installed console script
EXIT_CODES = {0, 1, 2, 3, 4}  # docs/cli.md (130 / 143: interrupted, tested apart)
REFUSED = {1, 2, 3, 4}
HANG_SECONDS = 60.0
"""How long a command may take before the checks call it hung: not a speed
target (a loaded machine takes many times the usual seconds; speed is
benchmarks/'s), but far below what a hang or reading /dev/zero would take."""
ERROR_PREFIX = "demoplan: error: "
NOT_SEEN = ("Traceback", "Warning:", "RuntimeWarning", "UserWarning", "DeprecationWarning")


@dataclass(frozen=True)
class Answer:
    """What a command did: exit code, its output streams and the time it took."""

    args: tuple[str, ...]
    code: int
    stdout: str
    stderr: str
    seconds: float

    def __str__(self) -> str:
        shown = " ".join(self.args).encode("utf-8", "surrogateescape").decode("utf-8", "replace")
        return (
            f"demoplan {shown} -> exit {self.code} in {self.seconds:.1f} s\n{self.stderr[-2000:]}"
        )


def run(
    args: Sequence[str | os.PathLike[str] | bytes],
    cwd: Path,
    *,
    timeout: float = 2 * HANG_SECONDS,
    stdin: bytes | None = None,
    stdout_path: str | None = None,
) -> Answer:
    """Run ``demoplan ARGS`` in a process of its own (special files can block a
    reader, so nothing runs in the test's process): forked from the tests' fork
    server, which has imported what the commands import, unless the process's
    start could matter (tests/support/forkserver.py). ``stdout_path``: a file
    to send stdout to (``/dev/full``)."""
    argv = [os.fsencode(a) if not isinstance(a, bytes) else a for a in args]
    env = forkserver.command_env()
    started = time.monotonic()
    out_file = Path(stdout_path).open("wb") if stdout_path else None  # noqa: SIM115
    try:
        completed = forkserver.run(
            argv, cwd, env, timeout=timeout, stdin=stdin, stdout_file=out_file
        )
    finally:
        if out_file:
            out_file.close()
    seconds = time.monotonic() - started
    shown = tuple(os.fsdecode(a) for a in argv)
    return Answer(
        shown,
        completed.returncode,
        (completed.stdout or b"").decode("utf-8", "replace"),
        completed.stderr.decode("utf-8", "replace"),
        seconds,
    )


def check_refused(
    answer: Answer,
    names: Iterable[str],
    *,
    codes: set[int] = REFUSED,
    max_seconds: float = HANG_SECONDS,
) -> None:
    """docs/cli.md for bad input: an exit code from ``codes``, exactly one stderr
    line, starting ``demoplan: error:`` and naming one of ``names`` (the file
    or the option), no traceback or warning text, within ``max_seconds``."""
    assert answer.code in codes, f"exit code not in {sorted(codes)}: {answer}"
    lines = answer.stderr.splitlines()
    assert len(lines) == 1, f"{len(lines)} stderr lines, one expected: {answer}"
    line = lines[0]
    assert line.startswith(ERROR_PREFIX), f"not an error line: {answer}"
    wanted = [n for n in names if n]
    assert any(n in line for n in wanted), f"names none of {wanted}: {answer}"
    for text in NOT_SEEN:
        assert text not in answer.stderr, f"{text!r} printed: {answer}"
    assert answer.seconds <= max_seconds, f"took {answer.seconds:.1f} s > {max_seconds} s: {answer}"


def check_clean(answer: Answer, *, max_seconds: float = HANG_SECONDS) -> None:
    """A command that may succeed or refuse: if it refuses, as
    :func:`check_refused` (with any name); never a traceback or warning."""
    assert answer.code in EXIT_CODES, f"exit code not in docs/cli.md: {answer}"
    for text in NOT_SEEN:
        assert text not in answer.stderr, f"{text!r} printed: {answer}"
    if answer.code:
        lines = answer.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith(ERROR_PREFIX), (
            f"not one error line: {answer}"
        )
    assert answer.seconds <= max_seconds, f"took {answer.seconds:.1f} s: {answer}"


def fingerprint(folder: Path) -> dict[str, str]:
    """Every regular file under ``folder`` with a hash of its content (special
    files and links by kind only: reading a FIFO would block)."""
    found: dict[str, str] = {}
    for root, dirs, files in os.walk(folder, followlinks=False):
        for name in sorted(files + dirs):
            path = Path(root) / name
            key = os.fsdecode(path.relative_to(folder))
            if path.is_symlink():
                found[key] = "link -> " + os.fsdecode(path.readlink())
            elif path.is_file():
                found[key] = _content_hash(path)
            elif path.is_dir():
                found[key] = "folder"
            else:
                found[key] = "special"
    return found


def _content_hash(path: Path) -> str:
    """A hash of a file's content read by its data extents (``SEEK_DATA`` /
    ``SEEK_HOLE``): the size, then each extent's offset and bytes. A hole reads
    as NUL bytes, so two files with the same size and extents hold the same
    bytes, and a byte written anywhere changes an extent (NUL bytes written
    into a hole too: stricter than the content, never weaker). A sparse file of
    200 MB of holes is hashed without reading 200 MB of NUL bytes."""
    digest = hashlib.sha256()
    with path.open("rb") as f:
        size = os.fstat(f.fileno()).st_size
        digest.update(f"size {size}\n".encode())
        offset = 0
        while offset < size:
            try:
                start = os.lseek(f.fileno(), offset, os.SEEK_DATA)
            except OSError as exc:
                if exc.errno == errno.ENXIO:  # only a hole after offset
                    break
                raise  # a file system that cannot tell holes: never a weaker check
            end = os.lseek(f.fileno(), start, os.SEEK_HOLE)
            f.seek(start)
            digest.update(f"extent {start} {end}\n".encode())
            digest.update(f.read(end - start))
            offset = end
    return digest.hexdigest()


MEMORY_DEVICES = {"null": 3, "zero": 5, "full": 7, "urandom": 9}
"""The kernel's memory devices by minor number (major 1), as under /dev."""


def private_device(path: Path, name: str) -> Path:
    """A character device node at ``path`` that is the kernel's ``/dev/<name>``
    (null, zero, full, urandom): the tests point demoplan at their own nodes,
    never the machine's, so that no defect can replace a device every program
    shares. Skips the test where making a node is not permitted."""
    import pytest

    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, MEMORY_DEVICES[name]))
    except PermissionError:
        pytest.skip("making a device node is not permitted here")
    return path
