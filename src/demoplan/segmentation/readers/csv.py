"""CSV pose streams (docs/formats.md "Pose stream").

Header ``t,object,x,y,z`` plus optionally ``yaw``, or ``roll,pitch,yaw``
(degrees, extrinsic x-y-z), or ``qx,qy,qz,qw``; one row per object per
sample, rows in any order, columns in any order. Blank lines and lines
starting with ``#`` are skipped, except a ``# units: mm`` comment above the
header (``m``, ``cm`` or ``mm``), which gives the unit of ``x,y,z``: positions
are converted to metres on reading. Orientation cells may be left empty for an
object without orientation (all of its rows, all the cells).

Without a declared unit (the comment, or ``units=``), positions are taken as
metres, and a stream no tabletop holds in metres — a coordinate beyond
:data:`PLAUSIBLE_METRES` (a millimetre stream's hundreds and thousands) — is
refused, naming ``units``: read as metres, a millimetre stream would show no
step of at least 2 cm.

Every problem is one :class:`~demoplan.errors.InputError` naming the file, the
line / column and what was expected.
"""

from __future__ import annotations

import csv
import re
import shlex
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from demoplan.documents.poses import LENGTH_SCALE
from demoplan.errors import InputError
from demoplan.fileio import read_input_text
from demoplan.segmentation.types import (
    FloatArray,
    PoseStream,
    normalise_quats,
    select_objects,
    stream_from_samples,
)

__all__ = ["PLAUSIBLE_METRES", "load_csv", "quats_from_rpy_array", "stream_units"]

_BASE_COLUMNS = ("t", "object", "x", "y", "z")
_ORIENTATION_SETS: dict[frozenset[str], tuple[str, ...]] = {
    frozenset(): (),
    frozenset({"yaw"}): ("yaw",),
    frozenset({"roll", "pitch", "yaw"}): ("roll", "pitch", "yaw"),
    frozenset({"qx", "qy", "qz", "qw"}): ("qx", "qy", "qz", "qw"),
}
MAX_STREAM_BYTES = 1024 * 1024 * 1024
"""The largest CSV stream read (1 GiB: about 10 hours of 10 objects at 100 Hz)."""
_EXPECTED_HEADER = "t,object,x,y,z plus optionally yaw | roll,pitch,yaw | qx,qy,qz,qw"
PLAUSIBLE_METRES = 10.0
"""The largest coordinate (m) of a stream without declared units: a room, not a
millimetre stream's hundreds (docs/formats.md "Pose stream")."""
_UNITS_COMMENT = re.compile(r"^\s*#\s*units\s*:\s*(\S*)\s*$", re.IGNORECASE)


def load_csv(
    path: str | Path, *, objects: Sequence[str] | None = None, units: str | None = None
) -> PoseStream:
    """Read a CSV pose stream (module docstring); angles in degrees, positions
    converted to metres.

    ``objects`` (names or :mod:`fnmatch` patterns) keeps only the matching
    objects; a pattern matching none is an error. By default all are kept.
    ``units`` (``"m"``, ``"cm"``, ``"mm"``; ``--units``) is the unit of
    ``x,y,z``; a ``# units:`` comment in the file must agree with it
    (:func:`stream_units`). Without either, positions are metres, and beyond
    :data:`PLAUSIBLE_METRES` they are refused as undeclared units.
    """
    path = Path(path)
    source = str(path)
    text = read_input_text(path, "a CSV pose stream", MAX_STREAM_BYTES)
    _refuse_a_document(text, source)
    declared = stream_units(text, units, source)
    table = _read_table(_data_lines(text, source), source)
    times = _number_column(table, "t")
    positions = np.stack(
        [_number_column(table, "x"), _number_column(table, "y"), _number_column(table, "z")],
        axis=1,
    )
    if declared is None:
        _check_metres(positions, table.names, source)
    else:
        positions = positions * LENGTH_SCALE[declared]
    orientations = _orientations(table)
    stream = stream_from_samples(
        table.names, times, positions, orientations, source=source, where=table.where
    )
    if objects is None:
        return stream
    chosen = set(select_objects(objects, stream.objects, stream.objects, source=source))
    return PoseStream(tuple(t for t in stream.tracks if t.name in chosen), source)


def _refuse_a_document(text: str, source: str) -> None:
    """A JSON or YAML document — a demonstration, most likely — given where a
    pose stream is read is said to be one, with what reads it (before, its
    first line was refused as a CSV header lacking t, object, x, y, z)."""
    start = text.lstrip("\ufeff \t\r\n")
    if start.startswith(("{", "[")) or re.match(r"format:\s*['\"]?demoplan/", start):
        how = (
            "learn reads a demonstration from a .json, .yaml or .yml file"
            if source.lower().endswith(".csv")
            else f"demoplan learn {shlex.quote(source)} -o MODEL.json reads it as it is"
        )
        raise InputError(
            f"a JSON or YAML document, not a CSV pose stream (a demonstration? {how}); a CSV "
            f"header {_EXPECTED_HEADER} expected",
            source=source,
        )


def _data_lines(text: str, source: str) -> list[tuple[int, str]]:
    """The numbered lines of ``text`` that are neither blank nor comments; none,
    or a quote left open on its line, is an input error."""
    lines = [
        (number, line)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise InputError(f"empty file; a CSV header {_EXPECTED_HEADER} expected", source=source)
    for number, line in lines:
        if line.count('"') % 2:  # a quoted field would run on into the next line
            raise InputError(
                "a quote that is not closed on its line; one sample per line expected",
                source=source,
                field=f"line {number}",
            )
    return lines


@dataclass(frozen=True, slots=True)
class _Table:
    """A CSV stream's checked header and sample rows."""

    source: str
    columns: dict[str, Any]
    """Column name → index, and ``__orientation__`` → the orientation columns."""
    body: list[list[str]]
    where: list[str]
    """Each row's ``line N``."""
    names: list[str]
    """Each row's object name."""


def _read_table(lines: list[tuple[int, str]], source: str) -> _Table:
    """``lines`` parsed as CSV: a header (:func:`_check_header`) and at least one
    row, every row as wide as the header and naming its object."""
    reader = csv.reader(line for _, line in lines)
    try:
        rows = list(reader)
    except csv.Error as exc:  # e.g. a field beyond csv's field size limit
        raise InputError(
            f"not CSV ({exc}); {_EXPECTED_HEADER} expected",
            source=source,
            field=f"line {lines[reader.line_num - 1][0]}",
        ) from None
    header = [cell.strip().lower() for cell in rows[0]]
    columns = _check_header(header, source, lines[0][0])
    body = rows[1:]
    numbers = [number for number, _ in lines[1:]]
    if not body:
        raise InputError("no samples; at least one row after the header expected", source=source)
    width = len(header)
    for row, number in zip(body, numbers, strict=True):
        if len(row) != width:
            raise InputError(
                f"{len(row)} cells; {width} expected ({','.join(header)})",
                source=source,
                field=f"line {number}",
            )
    where = [f"line {number}" for number in numbers]
    names = [row[columns["object"]].strip() for row in body]
    for i, name in enumerate(names):
        if not name:
            raise InputError(
                "empty object name", source=source, field=f"{where[i]}, column 'object'"
            )
    return _Table(source, columns, body, where, names)


def _number_column(table: _Table, name: str, *, optional: bool = False) -> FloatArray:
    """A numeric column; with ``optional``, empty cells are NaN (no orientation)."""
    source, where = table.source, table.where
    cells = [row[table.columns[name]] for row in table.body]
    empty = np.array([not c.strip() for c in cells]) if optional else None
    if empty is not None and empty.any():
        cells = ["nan" if e else c for c, e in zip(cells, empty.tolist(), strict=True)]
    try:
        values = np.array(cells, dtype=float)
    except ValueError:
        i = next(i for i, c in enumerate(cells) if not _is_number(c))
        raise InputError(
            f"{cells[i].strip()!r} is not a number; a number expected",
            source=source,
            field=f"{where[i]}, column {name!r}",
        ) from None
    finite = np.isfinite(values)
    if empty is not None:
        finite |= empty
    bad_values = np.flatnonzero(~finite)
    if bad_values.size:
        i = int(bad_values[0])
        raise InputError(
            f"{cells[i].strip()!r} is not a finite number; a finite number expected",
            source=source,
            field=f"{where[i]}, column {name!r}",
        )
    return values


def _orientation_columns(table: _Table, names: tuple[str, ...]) -> FloatArray:
    """The orientation columns ``names``, each row all given or all empty (NaN)."""
    values = np.stack([_number_column(table, c, optional=True) for c in names], axis=1)
    missing = np.isnan(values)
    partial = np.flatnonzero(missing.any(axis=1) & ~missing.all(axis=1))
    if partial.size:
        i = int(partial[0])
        raise InputError(
            f"orientation cells {','.join(names)} must be all given or all empty",
            source=table.source,
            field=table.where[i],
        )
    return values


def _orientations(table: _Table) -> FloatArray | None:
    """The rows' orientations as quaternions (x, y, z, w) from whichever
    orientation columns the header has; None without any."""
    kind = table.columns["__orientation__"]
    if kind == ("yaw",):
        yaw = np.radians(_orientation_columns(table, kind)[:, 0]) / 2.0
        zeros = np.zeros_like(yaw)
        return np.stack([zeros, zeros, np.sin(yaw), np.cos(yaw)], axis=1)
    if kind == ("roll", "pitch", "yaw"):
        return quats_from_rpy_array(_orientation_columns(table, kind))
    if kind:
        return normalise_quats(_orientation_columns(table, kind), table.source, table.where)
    return None


def stream_units(text: str, given: str | None, source: str) -> str | None:
    """The unit of a CSV stream's positions: ``given`` (``--units``) or the
    ``# units: mm`` comment above the header; both must agree. ``None``: neither
    (metres, checked for plausibility)."""
    if given is not None and given not in LENGTH_SCALE:
        raise InputError(
            f"{given!r} is not a unit of length; m, cm or mm expected", source=source, field="units"
        )
    in_file: str | None = None
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        if not line.lstrip().startswith("#"):
            break  # the header: a units comment below it is a plain comment
        match = _UNITS_COMMENT.match(line)
        if match is None:
            continue
        value = match.group(1).lower()
        if value not in LENGTH_SCALE:
            raise InputError(
                f"'# units: {match.group(1)}' names no unit of length; m, cm or mm expected",
                source=source,
                field=f"line {number}",
            )
        if in_file is not None and value != in_file:
            raise InputError(
                f"a second units comment says {value}, the first {in_file}; one unit expected",
                source=source,
                field=f"line {number}",
            )
        in_file = value
    if given is not None and in_file is not None and given != in_file:
        raise InputError(
            f"the file says '# units: {in_file}', --units says {given}; they must agree",
            source=source,
            field="units",
        )
    return given or in_file


def _check_metres(positions: FloatArray, names: Sequence[str], source: str) -> None:
    """Positions without declared units are metres: refuse a stream no room
    holds in metres (a coordinate beyond :data:`PLAUSIBLE_METRES`), which a
    millimetre or centimetre stream is."""
    peak = np.abs(positions).max(axis=1)
    far = int(np.argmax(peak))
    if peak[far] <= PLAUSIBLE_METRES:
        return
    codes = {name: k for k, name in enumerate(dict.fromkeys(names))}
    index = np.fromiter((codes[n] for n in names), np.intp, len(names))
    span = max(float(np.ptp(positions[index == k], axis=0).max()) for k in range(len(codes)))
    raise InputError(
        f"positions reach {float(peak[far]):g} ({names[far]!r}) and objects move up to "
        f"{span:g}: not metres on a table; declare the unit with a '# units: mm' (or cm) "
        "line above the header or --units mm|cm (--units m if they are metres)",
        source=source,
        field="units",
    )


def _check_header(header: list[str], source: str, line: int) -> dict[str, Any]:
    field = f"line {line} (header)"
    seen: set[str] = set()
    for name in header:
        if name in seen:
            raise InputError(f"column {name!r} appears twice", source=source, field=field)
        seen.add(name)
    missing = [c for c in _BASE_COLUMNS if c not in seen]
    if missing:
        raise InputError(
            f"missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)}; "
            f"expected {_EXPECTED_HEADER}",
            source=source,
            field=field,
        )
    extra = frozenset(seen - set(_BASE_COLUMNS))
    if extra not in _ORIENTATION_SETS:
        raise InputError(
            f"unknown orientation columns {','.join(sorted(extra))}; expected {_EXPECTED_HEADER}",
            source=source,
            field=field,
        )
    columns: dict[str, Any] = {name: index for index, name in enumerate(header)}
    columns["__orientation__"] = _ORIENTATION_SETS[extra]
    return columns


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def quats_from_rpy_array(angles_deg: FloatArray) -> FloatArray:
    """``(n, 3)`` extrinsic x-y-z Euler angles (degrees) → ``(n, 4)`` quaternions (x, y, z, w).

    The vectorised form of :func:`demoplan.rotations.quat_from_rpy`.
    """
    half = np.radians(np.asarray(angles_deg, dtype=float)) / 2.0
    cr, cp, cy = np.cos(half).T
    sr, sp, sy = np.sin(half).T
    quats = np.stack(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ],
        axis=1,
    )
    quats[quats[:, 3] < 0] *= -1.0
    return np.asarray(quats, dtype=float)
