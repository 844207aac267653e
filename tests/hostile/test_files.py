"""Every file argument of every command, given a hostile file (issue 14).

A table: each *slot* (a command and which of its arguments is the file) is
given each *kind* of hostile file — missing, a folder, a FIFO, a device, a
link that dangles or loops, empty, binary, invalid UTF-8, NUL bytes, too big,
one enormous line — and must answer as docs/cli.md says (:mod:`.harness`): one
line naming the file, an exit code of §4, short of the hang bound, nothing in
the working folder changed. File names with bytes that are not UTF-8, a
newline or rich markup must work, or be refused in one line all the same.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.hostile.harness import check_clean, check_refused, fingerprint, private_device, run
from tests.support.helpers import EXAMPLES


@dataclass(frozen=True)
class Slot:
    """A command with one file argument: ``args`` has ``FILE`` where it goes."""

    name: str
    args: tuple[str, ...]
    suffix: str
    valid: str  # a valid file for the slot, in the workspace
    may_work: frozenset[str] = frozenset()  # kinds of file the command may accept


FILE = "FILE"
SLOTS = [
    Slot("learn", ("learn", FILE, "-o", "out.json"), ".json", "demos.json"),
    Slot("learn-yaml", ("learn", FILE, "-o", "out.json"), ".yaml", "demos.yaml"),
    Slot("learn-stream", ("learn", FILE, "-o", "out.json"), ".csv", "stream.csv"),
    Slot("learn-update", ("learn", "--update", FILE, "demos.json"), ".json", "model.json"),
    Slot(
        "learn-require-file",
        ("learn", "demos.json", "-o", "out.json", "--require-file", FILE),
        ".txt",
        "require.txt",
        frozenset({"empty"}),  # no requirement
    ),
    Slot("show", ("show", FILE), ".json", "model.json"),
    Slot("solve", ("solve", FILE), ".xml", "problem.xml"),
    Slot("pddl", ("pddl", FILE, "-o", "pddl-out"), ".xml", "problem.xml"),
    Slot("problem-model", ("problem", FILE, "scene.json", "-o", "out.xml"), ".json", "model.json"),
    Slot("problem-scene", ("problem", "model.json", FILE, "-o", "out.xml"), ".json", "scene.json"),
    Slot("plan-model", ("plan", FILE, "scene.json"), ".json", "model.json"),
    Slot("plan-scene", ("plan", "model.json", FILE), ".json", "scene.json"),
    Slot("run-model", ("run", FILE, "scene.json"), ".json", "model.json"),
    Slot("run-scene", ("run", "model.json", FILE), ".json", "scene.json"),
    Slot(
        "perceive",
        ("perceive", FILE, "--px-per-m", "1000", "--origin", "0.05", "-0.21"),
        ".png",
        "top.png",
    ),
    Slot(
        "calibrate-image",
        ("calibrate", FILE, "--markers", "markers.json", "-o", "camera-out.json"),
        ".png",
        "oblique.png",
    ),
    Slot(
        "calibrate-markers",
        ("calibrate", "oblique.png", "--markers", FILE, "-o", "camera-out.json"),
        ".json",
        "markers.json",
    ),
    Slot(
        "perceive-camera",
        ("perceive", "oblique.png", "--camera", FILE, "--side", "0.04"),
        ".json",
        "camera.json",
    ),
    Slot(
        "perceive-colours",
        (
            "perceive",
            "top.png",
            "--px-per-m",
            "1000",
            "--origin",
            "0.05",
            "-0.21",
            "--colours",
            FILE,
        ),
        ".json",
        "colours.json",
    ),
    Slot("segment", ("segment", FILE, "-o", "out.json"), ".csv", "stream.csv"),
    Slot("segment-bag", ("segment", FILE, "-o", "out.json"), ".mcap", ""),
    Slot("import", ("import", FILE, "-o", "imported"), ".hdf5", ""),
]


def _folder(path: Path) -> Path:
    path.mkdir()
    return path


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def _link(path: Path, target: str) -> Path:
    path.symlink_to(target)
    return path


def _loop(path: Path) -> Path:
    other = path.with_name("loop-other" + path.suffix)
    path.symlink_to(other.name)
    other.symlink_to(path.name)
    return path


def _sparse(path: Path) -> Path:
    with path.open("wb") as f:
        f.truncate(200 * 1024 * 1024)  # 200 MB of holes: read, it is all NUL bytes
    return path


def _bytes(data: bytes) -> Callable[[Path], Path]:
    def make(path: Path) -> Path:
        path.write_bytes(data)
        return path

    return make


KINDS: dict[str, Callable[[Path], Path]] = {
    "missing": lambda p: p,
    "folder": _folder,
    "fifo": _fifo,
    # the kernel's devices, as private nodes: never the machine's own /dev
    "dev-zero": lambda p: private_device(p, "zero"),
    "dev-urandom": lambda p: private_device(p, "urandom"),
    "dev-null": lambda p: private_device(p, "null"),
    "dangling-link": lambda p: _link(p, "nowhere" + p.suffix),
    "link-loop": _loop,
    "empty": _bytes(b""),
    "binary": _bytes(bytes(range(256)) * 16),
    "not-utf8": _bytes(b'{"format": "\xff\xfe\xfd"}\n'),
    "nul-bytes": _bytes(b"\x00" * 4096),
    "sparse-200MB": _sparse,
    "long-line": _bytes(b"1," * (4 * 1024 * 1024) + b"\n"),
}


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Valid inputs for every slot: a model, a scene, a problem, a stream, an image."""
    import json

    import yaml

    folder = tmp_path_factory.mktemp("workspace")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", folder / "scene.json")
    shutil.copy(EXAMPLES / "planning" / "paper-example.xml", folder / "problem.xml")
    shutil.copy(EXAMPLES / "streams" / "set-table-1.csv", folder / "stream.csv")
    shutil.copy(EXAMPLES / "perception" / "blocks-top.png", folder / "top.png")
    shutil.copy(EXAMPLES / "perception" / "markers-oblique.png", folder / "oblique.png")
    shutil.copy(EXAMPLES / "perception" / "markers.json", folder / "markers.json")
    shutil.copy(EXAMPLES / "perception" / "colours.json", folder / "colours.json")
    answer = run(
        ["calibrate", "oblique.png", "--markers", "markers.json", "-o", "camera.json"], folder
    )
    assert answer.code == 0, str(answer)
    (folder / "require.txt").write_text("wood<green\n")
    data = json.loads((folder / "demos.json").read_text())
    (folder / "demos.yaml").write_text(yaml.safe_dump(data))
    answer = run(["learn", "demos.json", "--paper", "-o", "model.json"], folder)
    assert answer.code == 0, str(answer)
    return folder


def _case_folder(workspace: Path, tmp_path: Path) -> Path:
    folder = tmp_path / "case"
    shutil.copytree(workspace, folder, symlinks=True)
    return folder


CASES = [(slot, kind) for slot in SLOTS for kind in KINDS]


@pytest.mark.parametrize(
    ("slot", "kind"), CASES, ids=[f"{slot.name}-{kind}" for slot, kind in CASES]
)
def test_a_hostile_file_is_refused_in_one_line(
    workspace: Path, tmp_path: Path, slot: Slot, kind: str
) -> None:
    folder = _case_folder(workspace, tmp_path)
    hostile = KINDS[kind](folder / f"hostile{slot.suffix}")
    shown = str(hostile.relative_to(folder)) if hostile.is_relative_to(folder) else str(hostile)
    before = fingerprint(folder)
    args = [shown if a == FILE else a for a in slot.args]
    answer = run(args, folder)
    if kind in slot.may_work and answer.code == 0:
        check_clean(answer)
        return
    check_refused(answer, [shown])
    assert fingerprint(folder) == before, f"files changed: {answer}"


ODD_NAMES = {
    "not-utf8-name": b"odd-\xff\xfe",
    "newline-name": b"odd\nname",
    "markup-name": b"[bold]odd[red]",
    "control-name": b"odd\x1b[31mred",
}
NAMED = [
    (slot, name)
    for slot in SLOTS
    if slot.valid and not slot.name.startswith("learn-")
    for name in ODD_NAMES
]


@pytest.mark.parametrize(
    ("slot", "name"), NAMED, ids=[f"{slot.name}-{name}" for slot, name in NAMED]
)
def test_an_odd_file_name_works_or_is_refused_in_one_line(
    workspace: Path, tmp_path: Path, slot: Slot, name: str
) -> None:
    folder = _case_folder(workspace, tmp_path)
    odd = os.fsencode(folder) + b"/" + ODD_NAMES[name] + slot.suffix.encode()
    shutil.copy(folder / slot.valid, os.fsdecode(odd))
    args: list[str | bytes] = [
        ODD_NAMES[name] + slot.suffix.encode() if a == FILE else a for a in slot.args
    ]
    answer = run(args, folder)  # type: ignore[arg-type]
    check_clean(answer)


def _hdf5(path: Path) -> Path:
    import h5py
    import numpy as np

    with h5py.File(path, "w") as recording:  # a robosuite recording's outline
        recording.create_dataset("data/demo_1/states", data=np.zeros((3, 4)))
    return path


def _sqlite(path: Path) -> Path:
    import sqlite3

    with contextlib.closing(sqlite3.connect(path)) as database, database:
        database.execute("CREATE TABLE messages (id INTEGER PRIMARY KEY, data BLOB)")
    return path


def _mcap(path: Path) -> Path:
    path.write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)))  # MCAP's magic, then records
    return path


RECORDINGS = {
    # kind: (make it, its name, what the one line must point to)
    "hdf5": (_hdf5, "demo.hdf5", "demoplan import demo.hdf5 -o FOLDER"),
    "hdf5-named-csv": (_hdf5, "demo.csv", "demoplan import demo.csv -o FOLDER"),
    "sqlite-bag-storage": (_sqlite, "bag_0.sqlite", "its .db3 file"),
    "mcap-bag-storage": (_mcap, "bag_0.bin", "its .mcap file"),
}
OPTIONS = {
    # the rest of the command line: a complete one, none, --json alone, an unknown option
    "-o": ["-o", "out.json"],
    "no-o": [],
    "json": ["--json"],
    "plot-no-o": ["--plot", "speeds.png"],
    "unknown-option": ["-o", "out.json", "--no-such-option"],
}
READ_AS_TEXT = [
    (command, kind, options)
    for command in ("learn", "segment")
    for kind in RECORDINGS
    for options in OPTIONS
    if not (command == "learn" and options == "plot-no-o")
]


@pytest.mark.parametrize(
    ("command", "kind", "options"),
    READ_AS_TEXT,
    ids=[f"{c}-{k}-{o}" for c, k, o in READ_AS_TEXT],
)
def test_a_recording_given_where_text_is_read_says_how_it_is_read(
    tmp_path: Path, command: str, kind: str, options: str
) -> None:
    """``segment demo.hdf5`` answered "not UTF-8 text …; a CSV pose stream
    expected", which does not say that ``demoplan import`` reads robosuite's
    and robomimic's recordings; a bag's storage file under another name, that
    it is read by its folder or its own suffix. Whatever the options: a usage
    error found before the file is read (``segment demo.hdf5`` without ``-o``,
    exit 2) says it too — before, it named the missing option alone."""
    make, name, pointer = RECORDINGS[kind]
    make(tmp_path / name)
    answer = run([command, name, *OPTIONS[options]], tmp_path)
    check_refused(answer, [name], codes={1, 2})
    assert pointer in answer.stderr, answer
    assert "not UTF-8" not in answer.stderr, answer
    assert sorted(f.name for f in tmp_path.iterdir()) == [name]


DOCUMENTS_AS_STREAMS = [
    # the file's name, its text, the command, what the one line must say
    ("demo.json", "JSON", "segment", "demoplan learn demo.json -o MODEL.json"),
    ("demo.yaml", "YAML", "segment", "demoplan learn demo.yaml -o MODEL.json"),
    ("demo.csv", "JSON", "segment", "learn reads a demonstration from a .json"),
    ("demo.csv", "JSON", "learn", "learn reads a demonstration from a .json"),
    ("demo.txt", "JSON", "segment", "demoplan learn demo.txt -o MODEL.json"),
]


@pytest.mark.parametrize(("name", "text", "command", "pointer"), DOCUMENTS_AS_STREAMS)
def test_a_demonstration_given_where_a_stream_is_read_says_what_reads_it(
    tmp_path: Path, name: str, text: str, command: str, pointer: str
) -> None:
    """``segment demo.json`` answered ``line 1 (header): missing columns t,
    object, x, y, z``: the file is a demonstration, which ``learn`` reads as
    it is (and a demonstration named ``.csv`` is read as a stream)."""
    demo = (EXAMPLES / "blocks" / "demonstrations.json").read_text()
    body = demo if text == "JSON" else 'format: "demoplan/demonstration-1"\nsteps: []\n'
    (tmp_path / name).write_text(body)
    answer = run([command, name, "-o", "out.json"], tmp_path)
    check_refused(answer, [name], codes={1})
    assert "a JSON or YAML document, not a CSV pose stream" in answer.stderr, answer
    assert pointer in answer.stderr and "missing column" not in answer.stderr, answer


@pytest.mark.parametrize("kind", ["hdf5", "hdf5-named-csv"])
def test_a_usage_error_of_import_names_no_other_command(tmp_path: Path, kind: str) -> None:
    """``import demo.hdf5`` without ``-o`` is the right command missing an
    option: its one line points to nothing else."""
    make, name, _ = RECORDINGS[kind]
    make(tmp_path / name)
    answer = run(["import", name], tmp_path)
    assert answer.code == 2 and "Missing option" in answer.stderr, answer
    assert "demoplan import" not in answer.stderr.split("--help", 1)[1], answer


def test_a_folder_of_recordings_given_to_learn_says_how_they_are_read(tmp_path: Path) -> None:
    """``learn FOLDER`` of HDF5 recordings answered that the folder holds no
    demonstration files, without saying what reads them."""
    (tmp_path / "recordings").mkdir()
    _hdf5(tmp_path / "recordings" / "demo.hdf5")
    answer = run(["learn", "recordings", "-o", "out.json"], tmp_path)
    check_refused(answer, ["recordings"], codes={1})
    assert "it holds demo.hdf5: demoplan import RECORDING -o FOLDER" in answer.stderr, answer
