"""A folder of outputs written all or none and swapped in for an earlier one
only where a manifest proves demoplan wrote every file in it (docs/limits.md,
"Outputs")."""

from __future__ import annotations

import json
import os
import stat
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from pathlib import Path

from demoplan.errors import InputError
from demoplan.fileio.paths import (
    display_path,
    os_reason,
)
from demoplan.fileio.reading import (
    FORMAT_VERSION,
    check_format,
)
from demoplan.fileio.writing import (
    check_output_folder,
    current_umask,
    dump_json,
    hold_signals,
    make_folders,
    remove_made_folders,
    restore_signals,
    short_name,
    sync_folder,
    write_atomic,
)

__all__ = [
    "MANIFEST",
    "staged_folder",
]

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

    target = Path(target)
    check_output_folder(target)
    if target.is_symlink() and target.is_dir():
        target = Path(os.path.realpath(target))  # the link stays; its folder is replaced
    if target.is_dir():
        _proven_outputs(target)  # refused before any work
    parent = target.parent if str(target.parent) else Path()
    made: list[Path] = []
    # SIGINT and SIGTERM held back from making the folder until the block that
    # removes it is entered: a signal between mkdtemp's mkdir and its return left
    # the private folder behind (a Ctrl-C that landed in the mkdir call, seen once
    # in test_interrupt_any's run --frames)
    previous = hold_signals()
    try:
        made = make_folders(parent)
        building = Path(
            tempfile.mkdtemp(prefix=f".{short_name(target.name)}.", suffix=".tmp", dir=parent)
        )
    except OSError as exc:
        _discard(None, made)
        restore_signals(previous)
        raise InputError(f"cannot write ({os_reason(exc)})", source=str(target)) from None
    try:
        restore_signals(previous)  # a signal held back is raised here, in the block
        yield building
        _write_manifest(building, writer)
        building.chmod(0o777 & ~current_umask())  # a folder as mkdir makes it, not mkdtemp's 0700
        if target.is_dir():
            _proven_outputs(target)  # again: the work took time, a file may have come
        _swap_in(building, target)
    except InputError as exc:  # name the file as the user will know it, not the temporary one
        _discard(building, made)
        inside = exc.source is not None and exc.source.startswith(str(building))
        if not inside:
            raise
        shown = str(target) + exc.source[len(str(building)) :]  # type: ignore[index]
        raise InputError(exc.message, source=shown, field=exc.field) from None
    except OSError as exc:
        _discard(building, made)
        raise InputError(f"cannot write ({os_reason(exc)})", source=str(target)) from None
    except BaseException:
        _discard(building, made)
        raise


def _discard(building: Path | None, made: list[Path]) -> None:
    """Remove the private folder and the folders made for it, with SIGINT and
    SIGTERM held back: a second signal (or the redelivery of the first,
    demoplan.frontends.interrupts) cannot cut the removal short."""
    import shutil

    previous = hold_signals()
    try:
        if building is not None:
            shutil.rmtree(building, ignore_errors=True)
        remove_made_folders(made)
    finally:
        restore_signals(previous)


def _swap_in(building: Path, target: Path) -> None:
    """Put ``building`` in ``target``'s place, an old ``target`` moved into a
    new private folder first (put back if the second rename fails); then
    remove what the old folder's manifest proves demoplan wrote. SIGINT and
    SIGTERM are held back throughout. OSError if a rename fails."""
    parent = target.parent if str(target.parent) else Path()
    aside: Path | None = None
    previous = hold_signals()
    try:
        if os.path.lexists(target):
            aside = Path(
                tempfile.mkdtemp(
                    prefix=f".{short_name(target.name)}.old-", suffix=".tmp", dir=parent
                )
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
        sync_folder(parent)
        if aside is not None:  # Ctrl-C waits for this too: no half-removed old folder
            _remove_old_outputs(aside / "old", target)
            with suppress(OSError):
                aside.rmdir()
    finally:
        restore_signals(previous)


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
