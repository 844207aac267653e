"""Reading demoplan's JSON/YAML documents: regular files of bounded size,
UTF-8, unique keys, finite numbers, and the ``format`` tag every file carries
(``"format": "demoplan/<kind>-<version>"``, docs/formats.md)."""

from __future__ import annotations

import importlib
import json
import math
import re
import shlex
import stat
from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.errors import InputError
from demoplan.fileio.paths import (
    display_path,
    os_reason,
)

if TYPE_CHECKING:
    from pydantic import ValidationError

__all__ = [
    "FORMAT_VERSION",
    "MAX_FILE_BYTES",
    "MAX_YAML_BYTES",
    "check_format",
    "describe_validation_error",
    "read_document",
    "read_input_text",
    "require_regular_file",
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
        container = binary_container(exc.object, source)
        if container is not None:
            kind, hint = container
            raise InputError(
                f"{kind}, not text; {expected} expected ({hint})", source=source
            ) from None
        line = exc.object[: exc.start].count(b"\n") + 1
        raise InputError(
            f"not UTF-8 text (byte {exc.start} on line {line}); {expected} expected", source=source
        ) from None
    if "\x00" in text:
        container = binary_container(text[:8192].encode(), source)
        if container is not None:
            kind, hint = container
            raise InputError(f"{kind}, not text; {expected} expected ({hint})", source=source)
        line = text[: text.index("\x00")].count("\n") + 1
        raise InputError(f"a NUL byte on line {line}; {expected} expected", source=source)
    return text


HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
"""An HDF5 file's first 8 bytes — or after a user block of 512, 1024, 2048… bytes."""

_BAG_STORAGE = (
    "a ROS 2 bag's storage? segment and learn read a bag from its folder, its "
    "metadata.yaml or its {suffix} file"
)


def binary_container(data: bytes, source: str) -> tuple[str, str] | None:
    """What a file that is not text is, and the way demoplan reads it, where its
    first bytes say it is a recording: an HDF5 file (robosuite, robomimic:
    ``demoplan import``), a ROS 2 bag's SQLite or MCAP storage (under another
    name than ``.db3`` / ``.mcap``); else None. Given to a command that reads
    text (``segment``, ``learn``), such a file is a common mistake, and "not
    UTF-8 text" alone does not say what to do."""
    if any(data[at : at + 8] == HDF5_SIGNATURE for at in (0, 512, 1024, 2048, 4096)):
        return (
            "an HDF5 file",
            f"a robosuite / robomimic recording? demoplan import {shlex.quote(source)} -o FOLDER "
            "makes its demonstration files",
        )
    if data.startswith(b"SQLite format 3\x00"):
        return "an SQLite database", _BAG_STORAGE.format(suffix=".db3")
    if data.startswith(b"\x89MCAP"):
        return "an MCAP file", _BAG_STORAGE.format(suffix=".mcap")
    return None


def _top_level(data: Any) -> str:
    """What a document that is not an object holds, in JSON's words (not
    Python's: ``NoneType``, ``list``)."""
    if data is None:
        return "an empty document (or null)"
    if isinstance(data, bool):
        return f"{str(data).lower()} at top level"
    kinds = {list: "an array", str: "a string", int: "a number", float: "a number"}
    return f"{kinds.get(type(data), 'a value')} at top level"


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
            f"{_top_level(data)}; an object ({{…}}, a mapping in YAML) at top level expected",
            source=source,
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
        elif part in {"function-after", "function-before", "function-wrap", "[key]"}:
            continue
        elif not part or any(c.isspace() or not c.isprintable() for c in part):
            path += f"[{part!r}]"  # a key of spaces, a line break or an escape: quoted
        else:
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
