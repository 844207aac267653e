"""An HDF5 recording opened closed: only the named file is ever read (docs/limits.md).

An HDF5 file is a container that can point elsewhere, and h5py follows
where it points on a read:

* an **external link** (``data/demo_1`` → ``other.hdf5:/data``, or
  → ``/etc/passwd``) opens another file;
* **external storage** (``create_dataset(..., external=[("secret", 0, n)])``)
  keeps a dataset's bytes in another file, read as the dataset;
* a **virtual dataset** assembles its values from datasets of other files.

:func:`open_recording` refuses a file holding any of them, anywhere in it,
before any value is read: one :class:`~demoplan.errors.InputError` naming the
object and where it points. :func:`read_float_table` checks what a dataset
declares (real floating-point numbers, two dimensions, bytes the file holds,
at most :data:`MAX_ARRAY_BYTES`) before reading it, so a dataset declaring
156 GiB that were never written is one line, not a MemoryError.
:func:`attribute_text` decodes an attribute as strict UTF-8.
"""

from __future__ import annotations

import os
import shlex
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from demoplan.errors import InputError
from demoplan.fileio import require_regular_file
from demoplan.fileio.reading import HDF5_SIGNATURE, binary_container

if TYPE_CHECKING:
    import h5py

__all__ = [
    "MAX_ARRAY_BYTES",
    "MAX_LINKS",
    "attribute_text",
    "open_recording",
    "read_float_table",
]

MAX_ARRAY_BYTES = 2 * 1024**3
"""The most bytes one dataset of a recording may hold when read (2 GiB: 25
million samples of a 10-column state; robosuite's largest demonstration
holds 3 MB)."""
MAX_LINKS = 1_000_000
"""The most links (groups and datasets) a recording may hold."""
EXPECTED = "a robosuite / robomimic HDF5 recording"


def open_recording(path: Path) -> h5py.File:
    """``path`` opened read-only, once it is known to point nowhere else (module docstring)."""
    import h5py

    source = str(path)
    if Path(path).is_dir() and (Path(path) / "metadata.yaml").is_file():
        raise InputError(
            f"is a folder, a ROS 2 bag; {EXPECTED} expected (demoplan segment "
            f"{shlex.quote(source)} -o DEMO.json makes a demonstration of a bag)",
            source=source,
        )
    require_regular_file(path, EXPECTED)
    _refuse_another_kind(path, source)
    try:
        handle = h5py.File(path, "r")
    except OSError as exc:
        detail = " ".join(str(exc).split())
        raise InputError(
            f"not a readable HDF5 file ({detail}); {EXPECTED} expected", source=source
        ) from None
    try:
        _refuse_outside_reads(handle, source)
    except BaseException:
        handle.close()
        raise
    return handle


def _refuse_another_kind(path: Path, source: str) -> None:
    """One line saying what ``path`` is and what reads it, where its first
    bytes are not HDF5's and say it is a file demoplan reads otherwise: a
    bag's storage or a CSV pose stream (``segment``), a JSON or YAML document
    (``learn``), an image (``perceive``) — rather than h5py's "file signature
    not found"."""
    with Path(path).open("rb") as handle:
        head = handle.read(4104)
    if any(head[at : at + 8] == HDF5_SIGNATURE for at in (0, 512, 1024, 2048, 4096)):
        return
    quoted = shlex.quote(source)
    found = binary_container(head, source)
    text = head.decode("utf-8", "replace").lstrip("\ufeff \t\r\n")
    if found is not None:
        what = f"{found[0]}, a ROS 2 bag's storage"
        how = f"demoplan segment {quoted} -o DEMO.json makes a demonstration of a bag"
        if not source.lower().endswith((".db3", ".mcap")):
            how = found[1]
    elif text.startswith("rosbag2_bagfile_information"):
        what = "a ROS 2 bag's metadata.yaml"
        how = f"demoplan segment {quoted} -o DEMO.json makes a demonstration of a bag"
    elif head.startswith((b"\x89PNG", b"\xff\xd8\xff")):
        what = "an image"
        how = f"a photograph of the table? demoplan perceive {quoted} finds its blocks"
    else:
        if text.startswith(("{", "format:", "---")):
            what = "a JSON or YAML document"
            how = f"a demonstration? demoplan learn {quoted} -o MODEL.json reads it as it is"
        elif "," in text.split("\n", 1)[0] and "object" in text.split("\n", 1)[0]:
            what = "a CSV pose stream"
            how = f"demoplan segment {quoted} -o DEMO.json makes a demonstration of it"
        else:  # h5py would say "Unable to synchronously open file (file signature not found)"
            what = "an empty file" if not head else "no HDF5 signature in its first bytes"
            raise InputError(f"{what}; {EXPECTED} expected", source=source)
    raise InputError(f"{what}, not an HDF5 file; {EXPECTED} expected ({how})", source=source)


_CHECKED: dict[tuple[int, ...], None] = {}
"""Files found closed, by device, inode, size and change times: a recording is
opened once per demonstration, and checked once."""


def _refuse_outside_reads(handle: h5py.File, source: str) -> None:
    """One InputError for the first external link, externally stored or virtual
    dataset of the file; nothing it points to is opened. h5py's low-level
    interface: links listed with their kinds, datasets' creation properties
    read without building Dataset objects (4,000 datasets: 0.7 s)."""
    import h5py

    info = os.fstat(handle.id.get_vfd_handle()) if handle.driver == "sec2" else None
    identity = (
        (info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns, info.st_ctime_ns)
        if info is not None
        else None
    )
    if identity is not None and identity in _CHECKED:
        return
    refusal = "; a recording is read alone, from the one file named (docs/limits.md)"
    links: list[tuple[bytes, int]] = []

    def collect(name: bytes, link: Any) -> bool | None:
        links.append((name, link.type))
        return True if len(links) > MAX_LINKS else None  # not None: stop (h5py's visit)

    handle.id.links.visit(collect, info=True)  # the links themselves, never followed
    if len(links) > MAX_LINKS:
        raise InputError(
            f"more than {MAX_LINKS:,} groups and datasets; {EXPECTED} expected", source=source
        )
    for name, kind in links:
        if kind == h5py.h5l.TYPE_EXTERNAL:
            file_name, inside = handle.id.links.get_val(name)
            raise InputError(
                f"an external link to {_decoded(file_name)}:{_decoded(inside)}" + refusal,
                source=source,
                field=_decoded(name),
            )
    datasets: list[bytes] = []

    def collect_dataset(name: bytes, item: Any) -> None:
        if item.type == h5py.h5o.TYPE_DATASET:
            datasets.append(name)

    h5py.h5o.visit(handle.id, collect_dataset, info=True)  # hard links only
    for name in datasets:
        properties = h5py.h5d.open(handle.id, name).get_create_plist()
        if properties.get_external_count():
            files = sorted(
                {
                    _decoded(properties.get_external(i)[0])
                    for i in range(properties.get_external_count())
                }
            )
            raise InputError(
                f"a dataset whose bytes are stored in {', '.join(files)}" + refusal,
                source=source,
                field=_decoded(name),
            )
        if properties.get_layout() == h5py.h5d.VIRTUAL:
            origins = sorted(
                {
                    f"{properties.get_virtual_filename(i)}:{properties.get_virtual_dsetname(i)}"
                    for i in range(properties.get_virtual_count())
                }
            )
            raise InputError(
                f"a virtual dataset made of {', '.join(origins)}" + refusal,
                source=source,
                field=_decoded(name),
            )
    if identity is not None:
        if len(_CHECKED) > 64:
            _CHECKED.clear()
        _CHECKED[identity] = None


def _decoded(name: bytes | str) -> str:
    """An HDF5 name or file name as text (bytes that are not UTF-8 escaped)."""
    return name if isinstance(name, str) else name.decode("utf-8", "backslashreplace")


def read_float_table(
    dataset: h5py.Dataset, source: str, field: str, file_size: int
) -> NDArray[np.float64]:
    """A two-dimensional dataset of real floating-point numbers, read after
    checking what it declares against the file's size and :data:`MAX_ARRAY_BYTES`."""
    dtype = dataset.dtype
    if dtype.kind != "f":
        raise InputError(
            f"values of type {dtype}; real floating-point numbers expected",
            source=source,
            field=field,
        )
    shape = tuple(int(n) for n in dataset.shape)
    if len(shape) != 2 or shape[0] == 0:
        raise InputError(
            f"a table of shape {shape}; samples × (1 + nq + nv) expected",
            source=source,
            field=field,
        )
    declared = shape[0] * shape[1] * dtype.itemsize
    if declared > MAX_ARRAY_BYTES:
        raise InputError(
            f"declares {shape[0]:,} × {shape[1]:,} values ({declared / 1024**3:.1f} GiB); at "
            f"most {MAX_ARRAY_BYTES // 1024**3} GiB are read (a documented limit: docs/limits.md)",
            source=source,
            field=field,
        )
    stored = int(dataset.id.get_storage_size())
    filtered = bool(dataset.id.get_create_plist().get_nfilters())
    if stored == 0 or (not filtered and (stored < declared or declared > file_size)):
        raise InputError(
            f"declares {declared:,} bytes of values but the file holds {stored:,} of them "
            "(never written, or cut short)",
            source=source,
            field=field,
        )
    values = np.asarray(dataset[()], dtype=np.float64)
    return values


def attribute_text(attrs: Any, name: str, source: str) -> str | None:
    """Attribute ``name`` as text (UTF-8, strictly), or None when absent or not text."""
    try:
        value = attrs.get(name)
    except UnicodeDecodeError:
        raise InputError("text that is not UTF-8", source=source, field=name) from None
    return _text(value, source, name)


def _text(value: Any, source: str, name: str) -> str | None:
    if isinstance(value, bytes):
        try:
            return value.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise InputError(
                f"text that is not UTF-8 (byte {exc.start})", source=source, field=name
            ) from None
    if (isinstance(value, np.ndarray) and value.shape == ()) or isinstance(value, np.generic):
        return _text(value.item(), source, name)
    return value if isinstance(value, str) else None
