"""Every output option of every writing command, pointed at a special file:
a private character device (the same device as ``/dev/full``), a FIFO and a
socket, each made in the test's own folder — never the machine's ``/dev``.

The rule (docs/limits.md, "Outputs"): a special file is never renamed over,
removed or truncated. A file output (``-o``, ``--plot``, ``problem --pddl``)
is written straight into a character device or a pipe — into ``/dev/full``
that is "no space left on the device", exit 1 — and refuses a socket; a
folder output (``import``, ``pddl``, ``--frames``, ``experiments --out``)
and ``--video`` (an MP4 is finished by seeking back) refuse all three, exit 1.
Either way the node is afterwards the node it was, and no other file in the
folder is new or changed.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import socket
import stat
import tempfile
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.hostile.harness import check_refused, fingerprint, run
from tests.segmentation.test_import import box_states, write_recording
from tests.support.helpers import EXAMPLES

HAVE_MUJOCO = all(importlib.util.find_spec(m) for m in ("mujoco", "imageio_ffmpeg"))
FULL = os.makedev(1, 7)  # the kernel's "always full" device


def _device(path: Path) -> None:
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, FULL)
    except PermissionError:
        pytest.skip("making a device node is not permitted here")


def _socket(path: Path) -> None:
    # A socket's path is limited to ~107 bytes: bound in a short folder, then moved.
    with tempfile.TemporaryDirectory(prefix="s") as short:
        server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            server.bind(str(Path(short) / "s"))
            (Path(short) / "s").rename(path)
        finally:
            server.close()


NODES: dict[str, tuple[Callable[[Path], None], Callable[[int], bool]]] = {
    "device": (_device, stat.S_ISCHR),
    "fifo": (os.mkfifo, stat.S_ISFIFO),
    "socket": (_socket, stat.S_ISSOCK),
}


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("special-outputs")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", folder / "scene.json")
    shutil.copy(EXAMPLES / "planning" / "paper-example.xml", folder / "problem.xml")
    shutil.copy(EXAMPLES / "streams" / "set-table-1.csv", folder / "stream.csv")
    shutil.copy(EXAMPLES / "perception" / "blocks-top.png", folder / "top.png")
    write_recording(folder / "toy.hdf5", box_states())
    assert run(["learn", "demos.json", "--paper", "-o", "model.json"], folder).code == 0
    return folder


# (arguments with NODE where the special file goes, the node's name, whether the
# output is one file that may be streamed into a device or a pipe)
CASES: list[object] = [
    pytest.param(["learn", "demos.json", "--paper", "-o", "NODE"], "m.json", True, id="learn-o"),
    pytest.param(["segment", "stream.csv", "-o", "NODE"], "d.json", True, id="segment-o"),
    pytest.param(
        ["segment", "stream.csv", "-o", "d.json", "--plot", "NODE"],
        "d.png",
        True,
        id="segment-plot",
    ),
    pytest.param(["show", "scene.json", "--plot", "NODE"], "s.png", True, id="show-plot"),
    pytest.param(
        # no time limit: the default 2 s counts from the process start, and a
        # loaded machine may spend them before the plan that is to be drawn
        ["plan", "model.json", "scene.json", "--timeout", "inf", "--plot", "NODE"],
        "p.png",
        True,
        id="plan-plot",
    ),
    pytest.param(
        ["problem", "model.json", "scene.json", "-o", "NODE"], "p.xml", True, id="problem-o"
    ),
    pytest.param(
        ["problem", "model.json", "scene.json", "--pddl", "-o", "NODE"],
        "p.pddl",
        True,
        id="problem-pddl",
    ),
    pytest.param(  # the domain written beside the problem
        ["problem", "model.json", "scene.json", "--pddl", "-o", "p.pddl"],
        "p-domain.pddl",
        True,
        id="problem-pddl-domain",
    ),
    pytest.param(
        ["perceive", "top.png", "--px-per-m", "1000", "--origin", "0.05", "-0.21", "-o", "NODE"],
        "scene-out.json",
        True,
        id="perceive-o",
    ),
    pytest.param(
        [
            "perceive",
            "top.png",
            "--px-per-m",
            "1000",
            "--origin",
            "0.05",
            "-0.21",
            "--plot",
            "NODE",
        ],
        "overlay.png",
        True,
        id="perceive-plot",
    ),
    pytest.param(["pddl", "problem.xml", "-o", "NODE"], "pddl-out", False, id="pddl-o-folder"),
    pytest.param(["import", "toy.hdf5", "-o", "NODE"], "imported", False, id="import-o"),
    pytest.param(
        ["run", "model.json", "scene.json", "--frames", "NODE"], "frames", False, id="run-frames"
    ),
    pytest.param(["experiments", "--out", "NODE"], "report", False, id="experiments-out"),
    pytest.param(
        ["run", "model.json", "scene.json", "--sim", "mujoco", "--video", "NODE"],
        "v.mp4",
        False,
        marks=pytest.mark.skipif(not HAVE_MUJOCO, reason="MuJoCo or imageio-ffmpeg missing"),
        id="run-video",
    ),
]


def _drain(fifo: Path) -> tuple[threading.Thread, list[bytes]]:
    """A reader of ``fifo`` in a thread (a pipe's writer waits for one)."""
    received: list[bytes] = []

    def read() -> None:
        with fifo.open("rb") as handle:
            received.append(handle.read())

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    return reader, received


def _release(fifo: Path, reader: threading.Thread) -> None:
    """End a reader still waiting for a writer that never came."""
    if reader.is_alive():
        fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
        os.close(fd)
    reader.join(timeout=30)


@pytest.mark.parametrize("kind", sorted(NODES))
@pytest.mark.parametrize(("args", "name", "streamed"), CASES)
def test_an_output_naming_a_special_file_leaves_it_as_it_was(
    workspace: Path, tmp_path: Path, args: list[str], name: str, streamed: bool, kind: str
) -> None:
    folder = tmp_path / "case"
    shutil.copytree(workspace, folder)
    make, is_kind = NODES[kind]
    node = folder / name
    make(node)
    before = fingerprint(folder)
    reader, received = _drain(node) if kind == "fifo" else (None, [])
    try:
        answer = run([node.name if a == "NODE" else a for a in args], folder, timeout=120)
    finally:
        if reader is not None:
            _release(node, reader)
    assert is_kind(node.lstat().st_mode), f"{name} is no longer a {kind}: {answer}"
    if streamed and kind == "fifo":
        assert answer.code == 0, f"not written into the pipe: {answer}"
        assert received and received[0], f"nothing came through the pipe: {answer}"
        return
    check_refused(answer, [name], codes={1}, max_seconds=float("inf"))
    if streamed and kind == "device":
        assert "no space left on the device" in answer.stderr, answer
    else:
        assert "not a regular file" in answer.stderr or "not a folder" in answer.stderr, answer
    assert fingerprint(folder) == before, f"files changed: {answer}"
