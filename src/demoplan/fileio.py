"""Reading and writing demoplan's JSON/YAML files: format tags, units, atomic writes.

Every file carries ``"format": "demoplan/<kind>-<version>"`` (SPEC §2). Files
are written atomically — to a temporary file in the target's folder, flushed
and renamed over the target — so a reader never sees half a file and a failed
write leaves the old one in place.
"""

from __future__ import annotations

import json
import math
import os
import re
import tempfile
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from demoplan.errors import InputError

__all__ = [
    "FORMAT_VERSION",
    "check_format",
    "describe_validation_error",
    "dump_json",
    "read_document",
    "write_atomic",
]

FORMAT_VERSION = 1
_FORMAT = re.compile(r"^demoplan/([a-z][a-z0-9-]*?)-(\d+)(?:\.(\d+))?$")
MAX_FILE_BYTES = 64 * 1024 * 1024


def read_document(path: Path) -> dict[str, Any]:
    """Parse a JSON (or YAML, by extension) file into a dict, or raise one clear InputError.

    NaN and ±Infinity literals are refused: JSON does not have them and a
    pose made of them is meaningless.
    """
    source = str(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise InputError(f"cannot read file ({exc.strerror or exc})", source=source) from None
    if size > MAX_FILE_BYTES:
        raise InputError(f"file is {size} bytes; at most {MAX_FILE_BYTES} expected", source=source)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read file as UTF-8 text ({exc})", source=source) from None
    if path.suffix.lower() in {".yaml", ".yml"}:
        data = _parse_yaml(text, source)
    else:
        try:
            data = json.loads(text, parse_constant=_refuse_constant)
        except _NonFiniteError as exc:
            raise InputError(f"{exc} is not a number; finite numbers expected", source=source) from None
        except json.JSONDecodeError as exc:
            raise InputError(
                f"malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}", source=source
            ) from None
        except RecursionError:
            raise InputError("JSON nested too deeply", source=source) from None
    if not isinstance(data, dict):
        raise InputError(f"expected a JSON object at top level, got {type(data).__name__}", source=source)
    return data


class _NonFiniteError(ValueError):
    pass


def _refuse_constant(name: str) -> float:
    raise _NonFiniteError(name)


def _parse_yaml(text: str, source: str) -> Any:
    try:
        import yaml
    except ImportError:  # pragma: no cover - yaml is a dependency
        raise InputError("reading YAML needs PyYAML (pip install pyyaml)", source=source) from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputError(f"malformed YAML: {str(exc).splitlines()[0]}", source=source) from None
    _check_finite(data, source, "")
    return data


def _check_finite(value: Any, source: str, where: str) -> None:
    if isinstance(value, float) and not math.isfinite(value):
        raise InputError(f"{value} is not a finite number", source=source, field=where or None)
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
    if not isinstance(tag, str):
        raise InputError(f"missing format tag; expected {expected}", source=source, field="format")
    match = _FORMAT.match(tag)
    if not match or match.group(1) not in kinds:
        raise InputError(f"unknown format {tag!r}; expected {expected}", source=source, field="format")
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


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (temp file in the same folder + rename)."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise InputError(f"cannot write ({exc.strerror or exc})", source=str(path)) from None
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        Path(tmp).replace(path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
