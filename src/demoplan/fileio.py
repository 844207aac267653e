"""Reading and writing demoplan's JSON/YAML files: format tags, units, atomic writes.

Every file carries ``"format": "demoplan/<kind>-<version>"`` (docs/formats.md). Files
are written atomically — to a temporary file in the target's folder, flushed
and renamed over the target — so a reader never sees half a file and a failed
write leaves the old one in place.
"""

from __future__ import annotations

import errno
import importlib
import json
import math
import os
import re
import stat
import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.errors import InputError

if TYPE_CHECKING:
    from pydantic import ValidationError

__all__ = [
    "FORMAT_VERSION",
    "MANIFEST",
    "StagedOutputs",
    "check_format",
    "check_output_folder",
    "describe_validation_error",
    "display_path",
    "dump_json",
    "file_inside",
    "locked_for_update",
    "make_folders",
    "os_error",
    "os_reason",
    "output_target",
    "read_document",
    "read_input_text",
    "refuse_overwriting_inputs",
    "remove_made_folders",
    "require_regular_file",
    "safe_file_name",
    "staged_folder",
    "write_atomic",
    "write_atomic_bytes",
]

FORMAT_VERSION = 1
_FORMAT = re.compile(r"^demoplan/([a-z][a-z0-9-]*?)-(\d{1,9})(?:\.(\d{1,9}))?$")
MAX_FILE_BYTES = 64 * 1024 * 1024


def require_regular_file(path: Path, expected: str, max_bytes: int | None = None) -> int:
    """The size of ``path`` if it is a regular file (after following links) of
    at most ``max_bytes``; else one clear InputError. A device (``/dev/zero``)
    or a pipe would be read forever or block, a folder is not a file, a loop of
    links never ends. ``expected`` says what should be there."""
    source = display_path(path)
    try:
        info = Path(path).stat()
    except OSError as exc:
        raise InputError(f"{os_reason(exc, path)}; {expected} expected", source=source) from None
    except ValueError:  # a NUL byte in the name
        raise InputError(f"not a valid file name; {expected} expected", source=source) from None
    if stat.S_ISDIR(info.st_mode):
        raise InputError(f"is a folder; {expected} expected", source=source)
    if not stat.S_ISREG(info.st_mode):
        raise InputError(
            f"not a regular file (a device, pipe or socket); {expected} expected", source=source
        )
    if max_bytes is not None and info.st_size > max_bytes:
        raise InputError(
            f"file is {info.st_size:,} bytes; at most {max_bytes:,} expected (a documented "
            "limit: docs/limits.md)",
            source=source,
        )
    return info.st_size


def read_input_text(path: Path, expected: str, max_bytes: int = MAX_FILE_BYTES) -> str:
    """The UTF-8 text of an input file (a byte-order mark is skipped), after
    :func:`require_regular_file`; one clear InputError otherwise."""
    require_regular_file(path, expected, max_bytes)
    source = display_path(path)
    try:
        # utf-8-sig: a byte-order mark (as some Windows editors write) is not an error.
        text = Path(path).read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise InputError(f"cannot read file ({os_reason(exc, path)})", source=source) from None
    except UnicodeDecodeError as exc:
        line = exc.object[: exc.start].count(b"\n") + 1
        raise InputError(
            f"not UTF-8 text (byte {exc.start} on line {line}); {expected} expected", source=source
        ) from None
    if "\x00" in text:
        line = text[: text.index("\x00")].count("\n") + 1
        raise InputError(f"a NUL byte on line {line}; {expected} expected", source=source)
    return text


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


def display_path(path: Path | str | bytes) -> str:
    """A file name as it can be shown on one line: bytes that are not UTF-8
    and control characters (a newline, an escape) are written as escapes."""
    text = os.fsdecode(path) if isinstance(path, bytes) else str(path)
    if text.isprintable():
        return text
    shown = text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in shown)


MAX_YAML_BYTES = 2 * 1024 * 1024
"""Largest YAML document read: PyYAML parses and builds in Python (libyaml's
parser too builds in Python), about 15–30 s a megabyte on the shared machine,
where JSON of 64 MiB reads in seconds (docs/limits.md)."""


def read_document(path: Path) -> dict[str, Any]:
    """Parse a JSON (or YAML, by extension) file into a dict, or raise one clear InputError.

    NaN and ±Infinity literals are refused: JSON does not have them and a
    pose made of them is meaningless.
    """
    path = Path(path)
    source = display_path(path)
    if path.suffix.lower() in {".yaml", ".yml"}:
        size = require_regular_file(path, "a JSON or YAML document")
        if size > MAX_YAML_BYTES:
            raise InputError(
                f"a YAML document of {size:,} bytes; at most {MAX_YAML_BYTES:,} expected (YAML "
                "is parsed in Python: 5 MB took over a minute); write it as JSON (up to 64 MiB)",
                source=source,
            )
    text = read_input_text(path, "a JSON or YAML document")
    if path.suffix.lower() in {".yaml", ".yml"}:
        data = _parse_yaml(text, source)
    else:
        try:
            # NaN / Infinity literals become floats here and are refused below
            # with the field they stand in; so is a number that overflows (1e999).
            data = json.loads(text, object_pairs_hook=_unique_keys)
        except _DuplicateKeyError as exc:
            raise InputError(
                f"key {exc.key!r} appears twice in one object; each key once expected",
                source=source,
            ) from None
        except json.JSONDecodeError as exc:
            raise InputError(
                f"malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}", source=source
            ) from None
        except RecursionError:
            raise InputError("JSON nested too deeply", source=source) from None
        except ValueError as exc:  # e.g. an integer literal beyond Python's digit limit
            raise InputError(f"malformed JSON: {_value_problem(exc)}", source=source) from None
    if not isinstance(data, dict):
        raise InputError(
            f"expected an object (mapping) at top level, got {type(data).__name__}", source=source
        )
    try:
        _check_finite(data, source, "")
    except RecursionError:
        raise InputError("document nested too deeply", source=source) from None
    return data


def _value_problem(exc: ValueError) -> str:
    text = str(exc).splitlines()[0]
    if "digits" in text and "integer" in text:
        return "an integer of thousands of digits; a number of sensible size expected"
    return text


class _DuplicateKeyError(ValueError):
    def __init__(self, key: str):
        super().__init__(key)
        self.key = key


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object as a dict, refusing a key given twice (JSON allows it and
    the last one would silently win)."""
    data: dict[str, Any] = {}
    for key, value in pairs:
        if key in data:
            raise _DuplicateKeyError(key)
        data[key] = value
    return data


def _parse_yaml(text: str, source: str) -> Any:
    try:
        yaml: Any = importlib.import_module("yaml")  # Any: PyYAML ships no type stubs
    except ImportError:  # pragma: no cover - yaml is a dependency
        raise InputError("reading YAML needs PyYAML (pip install pyyaml)", source=source) from None

    class NoAliasLoader(yaml.SafeLoader):  # type: ignore[misc]
        """Refuses anchors/aliases: a few hundred bytes of nested aliases expand
        to billions of nodes (the YAML "billion laughs")."""

        def compose_node(self, parent: Any, index: Any) -> Any:
            if self.check_event(yaml.AliasEvent):
                event = self.peek_event()
                raise yaml.composer.ComposerError(
                    None, None, "aliases (*name) are not allowed", event.start_mark
                )
            return super().compose_node(parent, index)

        def construct_mapping(self, node: Any, deep: bool = False) -> Any:
            """A mapping; a key given twice is an error (the last would silently win)."""
            seen: set[Any] = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=deep)
                try:
                    duplicate = key in seen
                    seen.add(key)
                except TypeError:  # an unhashable key: the base class says so
                    break
                if duplicate:
                    raise yaml.constructor.ConstructorError(
                        None,
                        None,
                        f"key {key!r} appears twice in one mapping; each key once expected",
                        key_node.start_mark,
                    )
            return super().construct_mapping(node, deep=deep)

    try:
        return yaml.load(text, Loader=NoAliasLoader)  # a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        where = f" at line {mark.line + 1} column {mark.column + 1}" if mark is not None else ""
        raise InputError(
            f"malformed YAML{where}: {' '.join(str(problem).split())}", source=source
        ) from None
    except RecursionError:
        raise InputError("YAML nested too deeply", source=source) from None
    except ValueError as exc:  # an integer beyond Python's digit limit
        raise InputError(f"malformed YAML: {_value_problem(exc)}", source=source) from None


def _check_finite(value: Any, source: str, where: str) -> None:
    if isinstance(value, float) and not math.isfinite(value):
        shown = "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
        raise InputError(
            f"{shown} is not a number; a finite number expected", source=source, field=where or None
        )
    if isinstance(value, dict):
        for key, item in value.items():
            _check_finite(item, source, f"{where}.{key}" if where else str(key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            _check_finite(item, source, f"{where}[{index}]")


def check_format(data: dict[str, Any], kinds: set[str], source: str) -> tuple[str, int]:
    """Check ``data["format"]`` names one of ``kinds`` at a version this release reads."""
    tag = data.get("format")
    expected = " or ".join(f"'demoplan/{k}-{FORMAT_VERSION}'" for k in sorted(kinds))
    if tag is None:
        raise InputError(f"missing format tag; expected {expected}", source=source, field="format")
    if not isinstance(tag, str):
        raise InputError(
            f"expected a string such as {expected}, got {tag!r}", source=source, field="format"
        )
    match = _FORMAT.match(tag)
    if not match or match.group(1) not in kinds:
        shown = repr(tag) if len(tag) <= 60 else repr(tag[:60]) + "…"
        raise InputError(
            f"unknown format {shown}; expected {expected}", source=source, field="format"
        )
    version = int(match.group(2))
    if version > FORMAT_VERSION:
        raise InputError(
            f"{tag!r} is version {version}, newer than this demoplan reads "
            f"(up to {FORMAT_VERSION}); upgrade demoplan",
            source=source,
            field="format",
        )
    if version < 1:
        raise InputError(f"unknown format version in {tag!r}", source=source, field="format")
    return match.group(1), version


def describe_validation_error(error: ValidationError, source: str, prefix: str = "") -> InputError:
    """The first pydantic error as one line: file, dotted field path, expectation."""
    first = error.errors()[0]
    path = prefix
    for part in first["loc"]:
        if isinstance(part, int):
            path += f"[{part}]"
        elif part not in {"function-after", "function-before", "function-wrap"}:
            path += f".{part}" if path else str(part)
    message = str(first["msg"])
    if first["type"] == "missing":
        message = "missing; this field is required"
    elif first["type"] == "extra_forbidden":
        message = "unknown field"
    elif "input" in first and first["type"] not in {"value_error", "assertion_error"}:
        shown = repr(first["input"])
        message += f" (got {shown[:60]}{'…' if len(shown) > 60 else ''})"
    message = message.removeprefix("Value error, ")
    return InputError(message, source=source, field=path or None)


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


def _kind_of(mode: int) -> str:
    """A special file's kind, in words."""
    kinds = (
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a pipe (FIFO)"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISDIR, "a folder"),
    )
    return next((words for test, words in kinds if test(mode)), "not a regular file")


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
    raise InputError(f"is {_kind_of(info.st_mode)}, not a regular file; {needed}", source=shown)


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
            _sync_folder(folder if str(folder) else Path())

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
        aside = folder / f".{_short(path.name)}.{secrets.token_hex(4)}.old"
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
        fd, name = tempfile.mkstemp(prefix=f".{_short(path.name)}.", suffix=".old", dir=folder)
        with os.fdopen(fd, "wb") as copy, path.open("rb") as original:
            shutil.copyfileobj(original, copy)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise InputError(f"cannot write ({os_reason(exc)})", source=display_path(path)) from None
    return Path(name)


def _short(name: str) -> str:
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
        kind = "a file" if stat.S_ISREG(info.st_mode) else _kind_of(info.st_mode)
        raise InputError(
            f"exists and is {kind}, not a folder; a folder expected", source=display_path(path)
        )


MANIFEST = ".demoplan-manifest.json"
"""The file in each output folder (``run --frames``, ``experiments --out``)
that lists what demoplan wrote there: the files it may later replace."""


@contextmanager
def staged_folder(target: Path, writer: str) -> Iterator[Path]:
    """A folder of outputs written all or none, that replaces an earlier one
    only where demoplan can prove it wrote every file in it (docs/limits.md,
    "Outputs").

    The block fills a new private folder beside ``target`` (``mkdtemp``:
    exclusive, never through a link). Leaving it normally writes the
    manifest :data:`MANIFEST` into it — every file and folder written, each
    file with its SHA-256, and ``writer`` (the command) — and puts it in
    ``target``'s place: an old ``target`` is moved aside, then only the files
    its own manifest lists (unchanged) are removed, with SIGINT and SIGTERM
    held back over the two renames. A link to a folder is followed: the link
    stays, the folder it names is replaced.

    An existing ``target`` is replaced only if it is empty or holds exactly
    what its manifest lists, unchanged: a folder with other files, a changed
    file or no manifest (an older demoplan's output) is refused in one line,
    before the work and again before the swap, and never removed. Leaving
    the block by an exception removes the private folder and the folders
    made for it: ``target`` is as it was."""
    import shutil

    target = Path(target)
    check_output_folder(target)
    if target.is_symlink() and target.is_dir():
        target = Path(os.path.realpath(target))  # the link stays; its folder is replaced
    if target.is_dir():
        _proven_outputs(target)  # refused before any work
    parent = target.parent if str(target.parent) else Path()
    made: list[Path] = []
    try:
        made = make_folders(parent)
        building = Path(
            tempfile.mkdtemp(prefix=f".{_short(target.name)}.", suffix=".tmp", dir=parent)
        )
    except OSError as exc:
        remove_made_folders(made)
        raise InputError(f"cannot write ({os_reason(exc)})", source=str(target)) from None
    try:
        yield building
        _write_manifest(building, writer)
        building.chmod(0o777 & ~_umask())  # a folder as mkdir makes it, not mkdtemp's 0700
        if target.is_dir():
            _proven_outputs(target)  # again: the work took time, a file may have come
        _swap_in(building, target)
    except InputError as exc:  # name the file as the user will know it, not the temporary one
        shutil.rmtree(building, ignore_errors=True)
        remove_made_folders(made)
        inside = exc.source is not None and exc.source.startswith(str(building))
        if not inside:
            raise
        shown = str(target) + exc.source[len(str(building)) :]  # type: ignore[index]
        raise InputError(exc.message, source=shown, field=exc.field) from None
    except OSError as exc:
        shutil.rmtree(building, ignore_errors=True)
        remove_made_folders(made)
        raise InputError(f"cannot write ({os_reason(exc)})", source=str(target)) from None
    except BaseException:
        shutil.rmtree(building, ignore_errors=True)
        remove_made_folders(made)
        raise


def _swap_in(building: Path, target: Path) -> None:
    """Put ``building`` in ``target``'s place, an old ``target`` moved into a
    new private folder first (put back if the second rename fails); then
    remove what the old folder's manifest proves demoplan wrote. SIGINT and
    SIGTERM are held back throughout. OSError if a rename fails."""
    import signal

    parent = target.parent if str(target.parent) else Path()
    aside: Path | None = None
    held = {signal.SIGINT, signal.SIGTERM}
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        if os.path.lexists(target):
            aside = Path(
                tempfile.mkdtemp(prefix=f".{_short(target.name)}.old-", suffix=".tmp", dir=parent)
            )
            try:
                target.replace(aside / "old")
            except OSError:
                aside.rmdir()
                raise
        try:
            building.replace(target)
        except OSError:
            if aside is not None:
                (aside / "old").replace(target)
                aside.rmdir()
            raise
        _sync_folder(parent)
        if aside is not None:  # Ctrl-C waits for this too: no half-removed old folder
            _remove_old_outputs(aside / "old", target)
            with suppress(OSError):
                aside.rmdir()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _sha256(path: Path) -> str:
    import hashlib

    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _folder_entries(folder: Path) -> tuple[dict[str, Path], list[str], list[str]]:
    """Everything under ``folder`` (links not followed), by path relative to
    it: the regular files, the folders, and anything else (links, devices)."""
    files: dict[str, Path] = {}
    folders: list[str] = []
    others: list[str] = []
    for root, dirs, names in os.walk(folder, followlinks=False):
        for name in sorted(dirs + names):
            path = Path(root) / name
            relative = path.relative_to(folder).as_posix()
            info = path.lstat()
            if stat.S_ISDIR(info.st_mode):
                folders.append(relative)
            elif stat.S_ISREG(info.st_mode):
                files[relative] = path
            else:
                others.append(relative)
    return files, folders, others


def _write_manifest(folder: Path, writer: str) -> None:
    """The manifest of ``folder``: every file with its SHA-256, every folder."""
    files, folders, _ = _folder_entries(folder)
    document = {
        "format": f"demoplan/manifest-{FORMAT_VERSION}",
        "written_by": writer,
        "files": {name: _sha256(path) for name, path in files.items()},
        "folders": folders,
    }
    write_atomic(folder / MANIFEST, dump_json(document))


def _proven_outputs(folder: Path) -> dict[str, str]:
    """The files of ``folder`` (relative path: SHA-256) that its manifest
    proves demoplan wrote, if that is everything in it; else one InputError
    saying what is there and what to do. An empty folder proves nothing and
    holds nothing: ``{}``."""
    shown = display_path(folder)
    files, folders, others = _folder_entries(folder)
    if not files and not folders and not others:
        return {}
    if MANIFEST not in files:
        listed = sorted([*files, *folders, *others])
        raise InputError(
            f"holds files ({_first_names(listed)}) and no {MANIFEST}, so demoplan did not "
            "write them (or an older demoplan did); remove the folder yourself or choose "
            "another name",
            source=shown,
        )
    proven, proven_folders = _read_manifest(folder)
    del files[MANIFEST]
    foreign = sorted(
        [n for n in files if n not in proven]
        + [n for n in folders if n not in proven_folders]
        + others
    )
    changed = sorted(n for n, p in files.items() if n in proven and _sha256(p) != proven[n])
    if foreign or changed:
        what = (
            f"holds files demoplan did not write ({_first_names(foreign)})"
            if foreign
            else f"holds files changed since demoplan wrote them ({_first_names(changed)})"
        )
        raise InputError(
            f"{what}; an empty folder, one demoplan wrote or a new name expected (demoplan "
            "never removes a file it did not write)",
            source=shown,
        )
    return {n: proven[n] for n in files}


def _read_manifest(folder: Path) -> tuple[dict[str, str], set[str]]:
    """The files (relative path: SHA-256) and folders that the manifest of
    ``folder`` lists; one InputError if it is not a manifest demoplan wrote."""
    manifest = folder / MANIFEST
    try:
        if not stat.S_ISREG(manifest.lstat().st_mode):
            raise ValueError("not a regular file")
        data = json.loads(manifest.read_text(encoding="utf-8"))
        check_format(data, {"manifest"}, str(manifest))
        files = {str(k): str(v) for k, v in data["files"].items() if isinstance(v, str)}
        folders = {str(f) for f in data["folders"]}
    except (OSError, ValueError, TypeError, KeyError, AttributeError, InputError):
        raise InputError(
            f"its {MANIFEST} is not one demoplan wrote; remove the folder yourself or "
            "choose another name",
            source=display_path(folder),
        ) from None
    return files, folders


def _first_names(names: Sequence[str]) -> str:
    shown = ", ".join(display_path(n) for n in names[:3])
    return shown + (", …" if len(names) > 3 else "")


def _remove_old_outputs(old: Path, target: Path) -> None:
    """Remove the files of a replaced output folder ``old`` that its manifest
    proves demoplan wrote — checked again, file by file — then its folders
    when empty; anything else stays, and a warning says where."""
    import logging

    try:
        proven, _ = _read_manifest(old)
    except InputError:  # an empty folder (or a manifest changed since the check): no proof
        proven = None
    files, folders, _ = _folder_entries(old)
    for name, digest in (proven or {}).items():
        path = files.get(name)
        if name != MANIFEST and path is not None and _sha256(path) == digest:
            path.unlink()
    if proven is not None:
        (old / MANIFEST).unlink()
    for name in sorted(folders, key=lambda n: -n.count("/")):
        with suppress(OSError):
            (old / name).rmdir()
    try:
        old.rmdir()
    except OSError:
        logging.getLogger(__name__).warning(
            "%s: files appeared in it while it was replaced; they are kept in %s",
            display_path(target),
            display_path(old),
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
    try:
        made = make_folders(folder)
        fd, name = tempfile.mkstemp(prefix=f".{_short(path.name)}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        remove_made_folders(made)
        raise InputError(f"cannot write ({os_reason(exc)})", source=display_path(path)) from None
    temporary = Path(name)
    try:
        with os.fdopen(fd, "wb") as handle:
            _set_mode(handle.fileno(), path)
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
    except BaseException as exc:
        temporary.unlink(missing_ok=True)
        remove_made_folders(made)
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
        mode = 0o666 & ~_umask()
    os.fchmod(fd, mode)


def _umask() -> int:
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


def _sync_folder(folder: Path) -> None:
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
