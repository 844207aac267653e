"""The work folder of ``demoplan studio``: the only place the studio reads and
writes files.

Names are flat (``[A-Za-z0-9._-]{1,80}`` ending in ``.json``, docs/studio-api.md):
no separators, no ``..``, no hidden files, and a link leading out of the folder
is refused. New files are created exclusively and whole: the text is written
to a temporary file beside the target, flushed, and linked under the new name
(``link`` fails when the name exists, so two saves at once never share a
file and a reader never sees half of one).
"""

from __future__ import annotations

import errno
import json
import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from demoplan.errors import InputError
from demoplan.fileio import (
    check_format,
    dump_json,
    file_inside,
    os_reason,
    read_document,
    write_atomic,
)

__all__ = [
    "FILE_NAME",
    "MAX_LISTED_BYTES",
    "FileConflictError",
    "FileMissingError",
    "WorkFolder",
]

FILE_NAME = re.compile(r"^[A-Za-z0-9._-]{1,80}$")
"""A file name in the work folder (it must also end in ``.json``)."""
MAX_LISTED_BYTES = 16 * 1024 * 1024
"""Files larger than this are left out of the listing (read, they are refused by size)."""
MAX_NUMBERED = 10_000
"""``demonstration-1.json`` … the highest number a name is chosen from."""
KINDS = {
    "demonstration": "demonstrations",
    "demonstrations": "demonstrations",
    "model": "models",
    "objects": "objects",
    "scene": "scenes",
}
SOURCE_FILE = ".studio-source.json"
"""Where the Teach view's template or file in use is kept across reloads
(hidden: never listed, never a name the API accepts)."""


class FileMissingError(LookupError):
    """The named file is not in the work folder (HTTP 404)."""


class FileConflictError(Exception):
    """A file of that name exists already (HTTP 409)."""


class WorkFolder:
    """The folder the studio works in (made if missing)."""

    def __init__(self, root: Path) -> None:
        if root.exists() and not root.is_dir():  # mkdir would say "file exists"
            kind = "a file" if root.is_file() else "a device, pipe or socket"
            raise InputError(f"is {kind}, not a folder; a work folder expected", source=str(root))
        try:
            root.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(
                f"cannot make the work folder ({os_reason(exc)})", source=str(root)
            ) from None
        if not root.is_dir():
            raise InputError("is not a folder; a work folder expected", source=str(root))
        self.root = root.resolve()

    def path(self, name: str, field: str = "name") -> Path:
        """The file ``name`` inside the folder, or an InputError naming ``field``:
        a flat safe name ending in ``.json``, not a link leading out."""
        if not isinstance(name, str) or not FILE_NAME.match(name) or not name.endswith(".json"):
            raise InputError(
                f"{_shown(name)} is not a file name of the work folder; "
                "[A-Za-z0-9._-]{1,80} ending in .json expected",
                field=field,
            )
        if name.startswith(".") or ".." in name:
            raise InputError(
                f"{_shown(name)}: no hidden names and no '..'; a plain file name expected",
                field=field,
            )
        try:
            target = file_inside(self.root, name.removesuffix(".json"), ".json")
        except InputError as exc:
            raise InputError(exc.message, field=field) from None
        if target.name != name:  # file_inside reduced it: it was not a plain name
            raise InputError(f"{_shown(name)} is not a plain file name", field=field)
        return target

    def read(self, name: str, field: str = "name") -> dict[str, Any]:
        """The document in file ``name`` (FileMissingError when there is none)."""
        path = self.path(name, field)
        if not path.is_file():
            raise FileMissingError(f"{field}: no file {name!r} in the work folder")
        return read_document(path)

    def kind(self, document: dict[str, Any], name: str) -> str | None:
        """``demonstrations``, ``models``, ``objects`` or ``scenes``: where the listing shows it."""
        try:
            kind, _ = check_format(document, set(KINDS), name)
        except InputError:
            return None
        return KINDS[kind]

    def listing(self) -> dict[str, list[str]]:
        """The files of the folder by kind (by their ``format``; others left out)."""
        found: dict[str, list[str]] = {
            "demonstrations": [],
            "models": [],
            "objects": [],
            "scenes": [],
        }
        for name in sorted(self._names()):
            try:
                path = self.path(name)
                if not path.is_file() or path.stat().st_size > MAX_LISTED_BYTES:
                    continue
                document = json.loads(path.read_bytes())
            except (InputError, OSError, ValueError, RecursionError):
                continue
            kind = self.kind(document, name) if isinstance(document, dict) else None
            if kind is not None:
                found[kind].append(name)
        return found

    def latest_model(self, models: list[str]) -> str | None:
        """Of ``models`` (names the listing gives), the one written last — the
        model learned most recently (by the page or ``demoplan learn``); the
        later name where two were written at the same time; None for none."""
        written: list[tuple[int, str]] = []
        for name in models:
            try:
                written.append((self.path(name).stat().st_mtime_ns, name))
            except (InputError, OSError):
                continue
        return max(written)[1] if written else None

    def source(self) -> dict[str, str] | None:
        """The Teach view's source as last chosen (``{"kind", "id"}``), or None."""
        keys = ("kind", "id")
        try:
            data = json.loads((self.root / SOURCE_FILE).read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):
            return None
        if not isinstance(data, dict) or not all(isinstance(data.get(k), str) for k in keys):
            return None
        return {"kind": data["kind"], "id": data["id"]}

    def keep_source(self, kind: str, name: str) -> None:
        """Keep the Teach view's source (written whole, replacing the last)."""
        write_atomic(self.root / SOURCE_FILE, dump_json({"kind": kind, "id": name}))

    def _names(self) -> Iterator[str]:
        for entry in os.scandir(self.root):
            name = entry.name
            if name.endswith(".json") and FILE_NAME.match(name) and not name.startswith("."):
                yield name

    def create(self, document: dict[str, Any], name: str | None, stem: str) -> str:
        """Write ``document`` as a new file: ``name``, or with None the first free
        ``{stem}-N.json``. Never replaces a file (FileConflictError)."""
        data = dump_json(document).encode("utf-8")
        if name is not None:
            self._link_new(data, self.path(name))
            return name
        for number in range(1, MAX_NUMBERED + 1):
            candidate = f"{stem}-{number}.json"
            try:
                self._link_new(data, self.path(candidate))
            except FileConflictError:
                continue
            return candidate
        raise FileConflictError(f"name: {stem}-1 … {stem}-{MAX_NUMBERED}.json are all taken")

    def replace(self, document: dict[str, Any], name: str, field: str = "name") -> Path:
        """Write ``document`` to ``name``, replacing what was there, atomically."""
        path = self.path(name, field)
        write_atomic(path, dump_json(document))
        return path

    def _link_new(self, data: bytes, target: Path) -> None:
        fd, temporary = tempfile.mkstemp(prefix=".studio-", suffix=".tmp", dir=self.root)
        try:
            with os.fdopen(fd, "wb") as handle:
                handle.write(data)
                handle.flush()
                os.fsync(handle.fileno())
            Path(temporary).chmod(0o644)
            try:
                os.link(temporary, target)  # atomic, and fails where the name exists
            except FileExistsError:
                raise FileConflictError(
                    f"name: {target.name} exists in the work folder; files are never replaced"
                ) from None
            except OSError as exc:
                if exc.errno == errno.EEXIST:
                    raise FileConflictError(f"name: {target.name} exists") from None
                raise InputError(f"cannot write ({os_reason(exc)})", source=target.name) from None
        finally:
            Path(temporary).unlink(missing_ok=True)


def _shown(name: object) -> str:
    text = repr(name)
    return text if len(text) <= 90 else text[:87] + "…"
