"""A file-access monitor for the hostile suite: a demoplan command run under
``strace -f``, every path it (or a thread or a child of it, ffmpeg included)
opened, created, renamed, linked or removed, and the check of those paths
against what the command was told to read and write.

The rule (docs/limits.md, "What demoplan opens"): a command reads only the
inputs it was named, its outputs (to replace them) and the files of Python,
of the installed libraries and of the system that any program on the machine
reads; it writes only its outputs — the files and folders named, and its own
temporary files beside them. The allowances, all of them:

Read (an open without write access, a folder listed):
  * the named inputs (a folder named: anything in it), the named outputs,
    and the folder an output is written in (synced after the rename that
    puts the output in place);
  * demoplan's own package folder (its modules);
  * Python and the libraries: ``sys.prefix``, ``sys.base_prefix``,
    ``sys.exec_prefix`` (the interpreter, the standard library, the virtual
    environment's site-packages); the folders on ``sys.path`` *listed* only
    (the import system lists each path entry; reading a file in one that is
    not a prefix above is not allowed);
  * the system's shared files: ``/usr``, ``/lib``, ``/lib64`` (shared
    libraries, fonts, locales, zoneinfo), ``/etc/ld.so.cache``,
    ``/etc/ld.so.preload``, ``/etc/localtime``, ``/etc/locale.alias``,
    ``/etc/ssl/openssl.cnf`` (where ``/usr`` links for them), ``/etc/fonts``
    and ``/var/cache/fontconfig`` (fontconfig's configuration and system
    cache), ``/etc/glvnd`` and ``/etc/drirc`` (the OpenGL loader's);
  * in ``HOME`` (a fresh empty folder), only what fontconfig and Mesa look
    for there: ``.fontconfig``, ``.fonts``, ``.local/share/fonts``,
    ``.config/fontconfig``, ``.drirc`` — read, never written;
  * the process's own kernel files: ``/proc/self``, ``/proc/<pid>`` of a
    traced process, ``/proc/cpuinfo``, ``/proc/meminfo``, ``/proc/stat``,
    ``/proc/sys/vm/overcommit_memory`` (the C library's allocator),
    ``/proc/sys/crypto/fips_enabled`` (OpenSSL's, loaded with OpenCV),
    ``/proc/filesystems`` (the behaviour tree engine's runtime), ``/proc/mounts``
    (llvmlite, numba's compiler, when it loads), the CPU
    topology under ``/sys/devices/system/cpu`` and the control group's
    limits under ``/sys/fs/cgroup`` (NumPy's BLAS and the libraries count
    the cores they may use); ``/sys/devices`` and ``/sys/bus`` only for the
    GPU probing of an OpenGL context (``run --video``, ``experiments``);
  * devices: ``/dev/null``, ``/dev/urandom``, ``/dev/dri`` (EGL rendering).

Written (an open for writing or creating, a rename, link, symlink, folder
made or removed, a file removed) — and read:
  * the named outputs: a file named, and the temporary files beside it whose
    names start with ``.<its name>.`` (:mod:`demoplan.fileio`'s staging); a
    folder named, anything in it, and the private folders beside it whose
    names start with ``.<its name>.``; the folders above an output that did
    not exist before the command (it makes them);
  * ``/dev/null``;
  * the libraries' caches, each pointed by the test to a folder of its own
    that it names (:func:`audit_environment`): ``MPLCONFIGDIR`` (matplotlib's
    font list) and ``XDG_CACHE_HOME`` (fontconfig's and Mesa's caches);
  * the temporary folder ``TMPDIR`` — set to a fresh empty folder — only
    inside a folder the command itself made there (a private ``mkdtemp``),
    and it must be empty again when the command ends.

Nothing else: ``HOME`` is a fresh empty folder nothing may be written to
(a cache or a configuration written there is a finding), bytecode is not
written (``PYTHONDONTWRITEBYTECODE``: a write into the source tree would be
one), and a failed attempt counts like a successful one — trying to open a
file outside is a finding even where it does not exist.

Paths are taken as the command named them, made absolute with the folder
its ``dirfd`` or working folder stood for (``strace -y``), ``..`` removed
lexically; for a successful open the file the kernel actually opened (the
returned descriptor's path, links followed) is checked too. Every string is
logged in hexadecimal (``-xx``): names with any byte are read back exactly.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pytest

import demoplan
from tests.hostile.harness import DEMOPLAN, HANG_SECONDS, Answer

TRACED = (
    "open,openat,openat2,creat,rename,renameat,renameat2,unlink,unlinkat,"
    "mkdir,mkdirat,rmdir,symlink,symlinkat,link,linkat,chdir,fchdir"
)
WRITE_FLAGS = ("O_WRONLY", "O_RDWR", "O_CREAT", "O_TRUNC", "O_APPEND", "O_TMPFILE")


def _strace_works() -> bool:
    strace = shutil.which("strace")
    if strace is None:
        return False
    done = subprocess.run(
        [strace, "-f", "-o", os.devnull, "true"], capture_output=True, check=False
    )
    return done.returncode == 0


STRACE = _strace_works()
SECCOMP = (
    STRACE
    and "--seccomp-bpf"
    in subprocess.run(["strace", "-h"], capture_output=True, text=True, check=False).stdout
)
"""strace can stop the process at the traced calls only (much faster)."""


@dataclass(frozen=True)
class Access:
    """One path one traced call touched."""

    pid: int
    call: str
    path: str  # absolute, lexically normalised
    writes: bool  # created, changed, renamed, linked or removed
    real: str | None = None  # the file a successful open opened (links followed)
    made_folder: bool = False
    line: str = field(default="", compare=False)

    def __str__(self) -> str:
        real = f" (opened {self.real})" if self.real and self.real != self.path else ""
        kind = "write" if self.writes else "read"
        return f"{kind} {self.call} {self.path!r}{real}"


@dataclass(frozen=True)
class Audit:
    """A command's answer and every access of it and its children."""

    answer: Answer
    accesses: tuple[Access, ...]

    def touched(self) -> set[str]:
        """Every path named or opened (links followed), read or written."""
        return {a.path for a in self.accesses} | {a.real for a in self.accesses if a.real}


# --------------------------------------------------------------------------- the log

_LINE = re.compile(r"^(\d+) +(?P<resumed><\.\.\. )?(?P<call>\w+)(?:\(| resumed>)(?P<rest>.*)$")
_TOKEN = re.compile(
    r"(?P<fd>AT_FDCWD|-?\d+)<(?P<fdpath>(?:\\x[0-9a-f]{2})*)>"
    r'|"(?P<string>(?:\\x[0-9a-f]{2})*)"'
    r"|(?P<word>[A-Z][A-Z0-9_|]*)"
)
_RESULT = re.compile(r"\) += (-?\d+)(?:<((?:\\x[0-9a-f]{2})*)>)?")

# Per call: the argument positions (among its fd and string tokens) of each
# (dirfd, path) pair and whether the path is written; a dirfd of None: the cwd.
_PATHS: dict[str, list[tuple[int | None, int, bool | None]]] = {
    "open": [(None, 0, None)],  # None: written if the flags say so
    "creat": [(None, 0, True)],
    "openat": [(0, 1, None)],
    "openat2": [(0, 1, None)],
    "rename": [(None, 0, True), (None, 1, True)],
    "renameat": [(0, 1, True), (2, 3, True)],
    "renameat2": [(0, 1, True), (2, 3, True)],
    "unlink": [(None, 0, True)],
    "unlinkat": [(0, 1, True)],
    "rmdir": [(None, 0, True)],
    "mkdir": [(None, 0, True)],
    "mkdirat": [(0, 1, True)],
    "symlink": [(None, 1, True)],  # the target is only text, never opened
    "symlinkat": [(1, 2, True)],
    "link": [(None, 0, False), (None, 1, True)],
    "linkat": [(0, 1, False), (2, 3, True)],
    "chdir": [(None, 0, False)],
    "fchdir": [(None, 0, False)],  # its fd's path
}


def _text(hexed: str) -> str:
    return os.fsdecode(bytes.fromhex(hexed.replace("\\x", "")))


def _absolute(base: str, path: str) -> str:
    """``path`` from ``base``, ``..`` removed as the name says (not as links
    lead: the name as the command gave it is what is checked)."""
    return os.path.normpath(os.path.join(base, path))  # noqa: PTH118 (Path keeps "..")


def parse_log(text: str, cwd: Path) -> list[Access]:
    """The accesses of an ``strace -f -y -xx`` log, paths made absolute."""
    cwds: dict[int, str] = {}
    pending: dict[int, list[Access]] = {}  # unfinished calls, by pid
    found: list[Access] = []
    for line in text.splitlines():
        match = _LINE.match(line)
        if not match or match.group("call") not in _PATHS:
            continue
        pid, call, rest = int(match.group(1)), match.group("call"), match.group("rest")
        if match.group("resumed"):
            _finish(pending.pop(pid, []), rest, found)
            continue
        head = rest.split(" <unfinished ...>")[0]
        tokens = list(_TOKEN.finditer(head))
        args: list[str | None] = []
        words: list[str] = []
        for token in tokens:
            if token.group("fd") is not None:
                fd_path = _text(token.group("fdpath"))
                if token.group("fd") == "AT_FDCWD":
                    cwds[pid] = fd_path
                args.append(fd_path)
            elif token.group("string") is not None:
                args.append(_text(token.group("string")))
            else:
                words.append(token.group("word"))
        base = cwds.get(pid, str(cwd))
        accesses = []
        for dirfd, index, writes in _PATHS[call]:
            if index >= len(args) or args[index] is None:
                continue
            folder = base if dirfd is None or dirfd >= len(args) else args[dirfd]
            path = _absolute(folder or base, args[index] or "")
            if writes is None:
                writes = any(flag in word for word in words for flag in WRITE_FLAGS)
            accesses.append(
                Access(pid, call, path, writes, made_folder=call in {"mkdir", "mkdirat"}, line=line)
            )
        if call in {"chdir", "fchdir"} and accesses:
            cwds[pid] = accesses[0].path
        if " <unfinished ...>" in rest:
            pending[pid] = accesses
        else:
            _finish(accesses, rest, found)
    for accesses in pending.values():  # killed mid-call: still attempted
        found.extend(accesses)
    return found


def _finish(accesses: list[Access], rest: str, found: list[Access]) -> None:
    """The accesses of a call with its result: the file opened, a folder made."""
    result = _RESULT.search(rest)
    failed = result is None or result.group(1).startswith("-")
    for access in accesses:
        real = None
        if result and result.group(2) is not None and access.call.startswith("open"):
            real = _text(result.group(2))
        made = access.made_folder and not failed
        found.append(
            Access(access.pid, access.call, access.path, access.writes, real, made, access.line)
        )


# --------------------------------------------------------------------------- running


def audit_environment(root: Path, caches: Path) -> dict[str, str]:
    """The environment an audited command runs in: ``HOME`` and ``TMPDIR``
    fresh empty folders under ``root``, the libraries' caches in ``caches``
    (one folder for the session: matplotlib builds its font list once)."""
    for name in ("home", "tmp"):
        (root / name).mkdir(exist_ok=True)
    env = dict(
        os.environ,
        COLUMNS="100",
        PYTHONWARNINGS="default",
        PYTHONDONTWRITEBYTECODE="1",
        HOME=str(root / "home"),
        TMPDIR=str(root / "tmp"),
        MPLCONFIGDIR=str(caches / "matplotlib"),
        XDG_CACHE_HOME=str(caches / "xdg"),
    )
    for name in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_RUNTIME_DIR", "TEMP", "TMP"):
        env.pop(name, None)
    return env


def skip_without_strace() -> None:
    """Skip the audit where strace is missing or not permitted; fail instead
    under ``DEMOPLAN_REQUIRE_STRACE=1`` (CI, whose .ci/run installs it)."""
    if os.environ.get("DEMOPLAN_REQUIRE_STRACE") == "1":
        pytest.fail("strace is required (DEMOPLAN_REQUIRE_STRACE=1): missing or not permitted")
    pytest.skip("strace is not installed or not permitted here")


def strace_command(log: Path) -> list[str]:
    """``strace`` following every process and thread, logging the traced calls
    (:data:`TRACED`) to ``log`` with descriptors' paths and every string in
    hexadecimal, as :func:`parse_log` reads them; the command goes after it."""
    command = ["strace", "-f", "-y", "-xx", "-s", "4096", "-e", f"trace={TRACED}", "-o", str(log)]
    if SECCOMP:
        command.append("--seccomp-bpf")
    return command


def run_audited(
    args: Sequence[str | os.PathLike[str]],
    cwd: Path,
    env: dict[str, str] | None = None,
    timeout: float = 4 * HANG_SECONDS,
) -> Audit:
    """Run ``demoplan ARGS`` in ``cwd`` under ``strace -f``: its answer and accesses."""
    if not STRACE:
        skip_without_strace()
    log = cwd.parent / f".{cwd.name}.strace.log"  # outside the folder the command works in
    started = time.monotonic()
    process = subprocess.Popen(
        [*strace_command(log), os.fspath(DEMOPLAN), *(os.fspath(a) for a in args)],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env if env is not None else dict(os.environ, COLUMNS="100", PYTHONWARNINGS="default"),
        start_new_session=True,  # strace and the command: one group to end on a hang
    )
    try:
        stdout, stderr = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)  # the traced command too, not only strace
        process.communicate()
        raise
    answer = Answer(
        tuple(os.fsdecode(os.fspath(a)) for a in args),
        process.returncode,
        stdout.decode("utf-8", "replace"),
        stderr.decode("utf-8", "replace"),
        time.monotonic() - started,
    )
    accesses = parse_log(log.read_bytes().decode("ascii"), cwd)
    log.unlink()
    return Audit(answer, tuple(accesses))


# --------------------------------------------------------------------------- the rule


def _under(path: str, folder: str | Path) -> bool:
    folder = os.path.normpath(os.fspath(folder))
    return path == folder or path.startswith(folder.rstrip("/") + "/")


SYSTEM_READS = (
    "/usr",
    "/lib",
    "/lib64",
    "/etc/ld.so.cache",
    "/etc/ld.so.preload",
    "/etc/localtime",
    "/etc/fonts",
    "/etc/ssl/openssl.cnf",
    "/etc/locale.alias",
    "/var/cache/fontconfig",
    "/etc/glvnd",
    "/etc/drirc",
    "/proc/self",
    "/proc/cpuinfo",
    "/proc/meminfo",
    "/proc/stat",
    "/proc/sys/vm/overcommit_memory",
    "/proc/sys/crypto/fips_enabled",  # OpenSSL's libcrypto (loaded with OpenCV) asks
    "/proc/filesystems",  # the C++ runtime of the behaviour tree engine asks (run --bt)
    "/proc/mounts",  # llvmlite, numba's compiler (perception's compiled loops), on loading
    "/sys/devices/system/cpu",
    "/sys/fs/cgroup",
    "/dev/null",
    "/dev/urandom",
    "/dev/dri",
)
"""The system's shared files every program reads (the module docstring)."""
HOME_READS = (".fontconfig", ".fonts", ".local/share/fonts", ".config/fontconfig", ".drirc")
"""Read (never written) in ``HOME``: fontconfig's user fonts and caches and
Mesa's user configuration, which the libraries look for (the folder is fresh
and empty: they find nothing)."""
GPU_PROBES = ("/sys/devices", "/sys/bus")
"""What an OpenGL context probes for a GPU; only where the command renders."""


@dataclass(frozen=True)
class Allowed:
    """What one command was named: its inputs and outputs, and the folders
    the test pointed the caches, ``HOME`` and ``TMPDIR`` to."""

    inputs: tuple[Path, ...]
    outputs: tuple[Path, ...]
    env: dict[str, str]
    renders: bool = False  # an OpenGL context: GPU probing allowed

    def python_reads(self) -> tuple[str, ...]:
        package = Path(demoplan.__file__).resolve().parent
        return (str(package), sys.prefix, sys.base_prefix, sys.exec_prefix)

    def cache_folders(self) -> tuple[str, ...]:
        return (self.env["MPLCONFIGDIR"], self.env["XDG_CACHE_HOME"])


def _output_allows(output: str, path: str) -> bool:
    """``path`` is ``output``, in it, or in one of its staged siblings (a
    name starting ``.<its name>.`` in the same folder, as demoplan.fileio
    and the video writer make them)."""
    if _under(path, output):
        return True
    parent, name = os.path.split(output)
    staged = "." + (name if len(os.fsencode(name)) <= 200 else name[:50]) + "."
    if not _under(path, parent) or path == parent:
        return False
    first = path[len(parent.rstrip("/")) + 1 :].split("/")[0]
    return first.startswith(staged)


def violations(audit: Audit, allowed: Allowed, existed: Iterable[Path] = ()) -> list[str]:
    """Every access the rule (module docstring) does not allow, as text.
    ``existed``: folders above the outputs that existed before the command
    (the others it may make)."""
    existed_before = {os.path.normpath(os.fspath(p)) for p in existed}
    outputs = [os.path.normpath(os.fspath(o)) for o in allowed.outputs]
    above = {
        os.fspath(parent)
        for o in allowed.outputs
        for parent in Path(os.path.normpath(os.fspath(o))).parents
        if os.fspath(parent) not in existed_before
    }
    inputs = [os.path.normpath(os.fspath(i)) for i in allowed.inputs]
    inputs += [os.path.realpath(i) for i in inputs]
    temporary = os.path.normpath(allowed.env["TMPDIR"])
    private = {a.path for a in audit.accesses if a.made_folder and _under(a.path, temporary)}
    traced = {a.pid for a in audit.accesses}
    listed = {os.path.normpath(p) for p in sys.path if p} | {os.fspath(DEMOPLAN.parent)}

    def written_ok(path: str) -> bool:
        if path == "/dev/null" or path in above:
            return True
        if any(_output_allows(o, path) for o in outputs):
            return True
        if any(_under(path, c) for c in allowed.cache_folders()):
            return True
        return any(_under(path, p) and path != temporary for p in private)

    def read_ok(access: Access, path: str) -> bool:
        if written_ok(path) or any(_under(path, i) for i in inputs):
            return True
        if any(_under(path, p) for p in (*allowed.python_reads(), *SYSTEM_READS)):
            return True
        if any(_under(path, f"{allowed.env['HOME']}/{p}") for p in HOME_READS):
            return True
        if path in {str(Path(o).parent) for o in outputs}:  # synced after a rename
            return True
        if allowed.renders and any(_under(path, p) for p in GPU_PROBES):
            return True
        if path in listed and "O_DIRECTORY" in access.line:
            return True
        proc = re.match(r"/proc/(\d+)(/|$)", path)
        return bool(proc and int(proc.group(1)) in traced)

    found = []
    for access in audit.accesses:
        for path in {access.path, access.real or access.path}:
            ok = written_ok(path) if access.writes else read_ok(access, path)
            if not ok:
                found.append(f"{access} (process {access.pid})")
                break
    return sorted(set(found))


def audited(
    args: Sequence[str | os.PathLike[str]],
    cwd: Path,
    allowed: Allowed,
    *,
    never: Iterable[Path] = (),
    timeout: float = 4 * HANG_SECONDS,
) -> Audit:
    """Run ``demoplan ARGS`` in ``cwd`` under the monitor, in ``allowed.env``,
    and check every access (:func:`check_accesses`): its audit, for more checks."""
    existed = [
        parent
        for output in allowed.outputs
        for parent in Path(os.path.normpath(os.fspath(output))).parents
        if parent.exists()
    ]
    audit = run_audited(args, cwd, allowed.env, timeout)
    check_accesses(audit, allowed, existed=existed, never=never)
    return audit


def check_accesses(
    audit: Audit,
    allowed: Allowed,
    *,
    existed: Iterable[Path] = (),
    never: Iterable[Path] = (),
) -> None:
    """Fail on any access the rule does not allow, on any access at all of a
    path in ``never`` (a secret: by its name or as the file opened), and on
    anything left in the private temporary folder; and, lest a monitor that
    sees nothing pass everything, where the command succeeded, unless the
    first named input was seen opened."""
    if audit.answer.code == 0 and allowed.inputs:
        first = os.path.normpath(os.fspath(allowed.inputs[0]))
        seen = any(_under(path, first) for path in audit.touched())
        assert seen, f"the audit saw no open of {first}: {len(audit.accesses)} accesses"
    for secret in never:
        names = {os.path.normpath(os.fspath(secret)), os.path.realpath(secret)}
        touched = [str(a) for a in audit.accesses if {a.path, a.real} & names]
        assert not touched, f"{secret} touched: {touched}\n{audit.answer}"
    found = violations(audit, allowed, existed)
    assert not found, "accesses outside the rule:\n  " + "\n  ".join(found) + f"\n{audit.answer}"
    left = sorted(p.name for p in Path(allowed.env["TMPDIR"]).iterdir())
    assert not left, f"left in the temporary folder: {left}\n{audit.answer}"
    home = sorted(p.name for p in Path(allowed.env["HOME"]).iterdir())
    assert not home, f"made in HOME: {home}\n{audit.answer}"
