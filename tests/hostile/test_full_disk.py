"""A disk that fills up while a command writes its outputs: one line naming
the output, exit 1, and nothing half written or left behind — no partial
file or folder, no temporary one, no folder made for it, and earlier outputs
as they were (issues 14 and 27). Needs a small tmpfs, so it runs where the
tests may mount one (root in CI's VM); a private ``/dev/full`` node stands
for a full device."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.hostile.harness import check_clean, check_refused, fingerprint, private_device, run
from tests.segmentation.test_import import box_states, write_recording
from tests.support.helpers import EXAMPLES

RUN = ["run", "model.json", "scene.json"]
HAVE_VIDEO = all(importlib.util.find_spec(m) for m in ("mujoco", "imageio_ffmpeg"))


def _mount(where: Path, size: str) -> None:
    where.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
        capture_output=True,
        check=False,
    )
    if mounted.returncode:
        pytest.skip(f"cannot mount a small tmpfs here: {mounted.stderr.decode().strip()}")


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 200 KB tmpfs: enough for a demonstration, not for a storyboard."""
    where = tmp_path / "small"
    _mount(where, "200k")
    try:
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=False)


def _fill(disk: Path, free_kb: int) -> None:
    """Fill ``disk`` with one file until ``free_kb`` KB are left (a tmpfs
    counts whole 4 KB pages)."""
    filler = disk / "filler"
    filler.unlink(missing_ok=True)
    with filler.open("wb", buffering=0) as handle:
        try:
            while True:
                handle.write(b"\0" * 4096)
        except OSError:  # full
            pass
    usage = shutil.disk_usage(disk)
    size = filler.stat().st_size
    filler.unlink()
    filler.write_bytes(b"\0" * max(0, size + usage.free - free_kb * 1024))


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("disk")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", folder / "scene.json")
    shutil.copy(EXAMPLES / "planning" / "paper-example.xml", folder / "problem.xml")
    shutil.copy(EXAMPLES / "streams" / "set-table-1.csv", folder / "stream.csv")
    write_recording(folder / "toy.hdf5", box_states())
    assert run(["learn", "demos.json", "--paper", "-o", "model.json"], folder).code == 0
    return folder


@pytest.mark.parametrize(
    ("args", "output"),
    [
        (["run", "model.json", "scene.json", "--frames", "SMALL/frames"], "frames"),
        (["run", "model.json", "scene.json", "--frames", "SMALL/new/deeper/fr"], "fr"),
        (["experiments", "--out", "SMALL/report"], "report"),
    ],
    ids=["run-frames", "run-frames-in-new-folders", "experiments"],
)
def test_a_disk_that_fills_up_leaves_nothing(
    workspace: Path, small_disk: Path, args: list[str], output: str
) -> None:
    answer = run([a.replace("SMALL", str(small_disk)) for a in args], workspace)
    check_refused(answer, [output], codes={1})
    assert "no space left" in answer.stderr
    assert ".tmp" not in answer.stderr  # the output as the user named it
    assert list(small_disk.iterdir()) == []


# Commands whose outputs are a few KB: (arguments, the outputs, an earlier
# version of them to keep when the command fails). SMALL is the small disk.
FILES: dict[str, tuple[list[str], list[str]]] = {
    "segment": (
        ["segment", "stream.csv", "-o", "SMALL/d.json", "--plot", "SMALL/d.png"],
        ["d.json", "d.png"],
    ),
    "pddl": (["pddl", "problem.xml", "-o", "SMALL/pd"], ["pd/domain.pddl", "pd/problem.pddl"]),
    "pddl-new-folders": (["pddl", "problem.xml", "-o", "SMALL/a/b/pd"], []),
    "problem-pddl": (
        ["problem", "model.json", "scene.json", "--pddl", "-o", "SMALL/p.pddl"],
        ["p.pddl", "p-domain.pddl"],
    ),
    "import": (["import", "toy.hdf5", "-o", "SMALL/out"], ["out/toy-demo_1.json"]),
}


@settings(
    max_examples=15,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(name=st.sampled_from(sorted(FILES)), free_kb=st.sampled_from([0, 4, 8, 12]))
def test_a_full_disk_under_file_outputs(
    workspace: Path, tmp_path_factory: pytest.TempPathFactory, name: str, free_kb: int
) -> None:
    """``segment``, ``pddl``, ``problem --pddl``, ``import`` onto a disk with
    ``free_kb`` KB left, where an earlier run's outputs stand (an "old"
    text): done (every output whole), or refused in one line with exit 1
    and the disk as it was — the earlier outputs kept, never the first file
    of two written alone, no folder made."""
    disk = tmp_path_factory.mktemp("full") / "small"
    _mount(disk, "64k")
    try:
        args, outputs = FILES[name]
        for output in outputs:
            (disk / output).parent.mkdir(parents=True, exist_ok=True)
            (disk / output).write_text("old\n")
        _fill(disk, free_kb)
        before = fingerprint(disk)
        answer = run([a.replace("SMALL", str(disk)) for a in args], workspace)
        after = fingerprint(disk)
        if answer.code == 0:
            check_clean(answer)
            for output in outputs:
                assert (disk / output).read_text() != "old\n", f"{output} not written: {answer}"
        else:
            check_refused(answer, [str(disk)], codes={1})
            assert "no space left" in answer.stderr, answer
            assert after == before, f"the disk changed: {answer}"
    finally:
        subprocess.run(["umount", str(disk)], check=False)


@pytest.mark.parametrize(
    "args",
    [
        ["segment", "stream.csv", "-o", "FULL"],
        ["segment", "stream.csv", "-o", "d.json", "--plot", "FULL.png"],
        ["learn", "demos.json", "--paper", "-o", "FULL"],
        ["export", "bt", "model.json", "scene.json", "-o", "t.xml", "--plot", "FULL.png"],
    ],
    ids=["segment-o", "segment-plot", "learn-o", "export-plot"],
)
def test_a_full_device_is_an_error(workspace: Path, tmp_path: Path, args: list[str]) -> None:
    """A private ``/dev/full`` as an output: one line, exit 1, and the other
    output of the command not written."""
    folder = tmp_path / "case"
    shutil.copytree(workspace, folder)
    full = "FULL.png" if "FULL.png" in args else "FULL"
    private_device(folder / full, "full")
    before = fingerprint(folder)
    answer = run(args, folder)
    check_refused(answer, [full], codes={1})
    assert "no space left" in answer.stderr, answer
    assert fingerprint(folder) == before, answer


@pytest.fixture
def read_only_disk(tmp_path: Path) -> Iterator[Path]:
    """A read-only tmpfs (mounted ``ro``: a read-only folder stops root too)."""
    where = tmp_path / "ro"
    _mount(where, "64k,ro")
    try:
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=False)


@pytest.mark.parametrize(
    "args",
    [
        ["plan", "model.json", "scene.json", "--plot", "RO/p.png"],
        ["show", "model.json", "--plot", "RO/p.png"],
        ["show", "scene.json", "--plot", "RO/p.png"],
        ["export", "bt", "model.json", "scene.json", "-o", "t.xml", "--plot", "RO/p.png"],
        ["segment", "stream.csv", "-o", "d.json", "--plot", "RO/p.png"],
        ["learn", "demos.json", "--paper", "-o", "RO/m.json"],
    ],
    ids=["plan-plot", "show-model-plot", "show-scene-plot", "export-plot", "segment-plot", "learn"],
)
def test_a_read_only_folder_is_one_plain_line_and_nothing_written(
    workspace: Path, tmp_path: Path, read_only_disk: Path, args: list[str]
) -> None:
    """An output in a read-only folder: ``FILE: cannot write (read-only file
    system)``, the file named once (a figure said ``cannot write the plot
    (FILE: cannot write (…))`` before), exit 1, and the command's other
    output not written (``export -o t.xml`` was, before its drawing failed)."""
    folder = tmp_path / "case"
    shutil.copytree(workspace, folder)
    before = fingerprint(folder)
    answer = run([a.replace("RO", str(read_only_disk)) for a in args], folder)
    check_refused(answer, [str(read_only_disk)], codes={1})
    assert "cannot write (read-only file system)" in answer.stderr, answer
    assert answer.stderr.count(str(read_only_disk)) == 1, answer
    assert fingerprint(folder) == before, answer


@pytest.mark.slow
@pytest.mark.skipif(not HAVE_VIDEO, reason="MuJoCo or imageio-ffmpeg not installed")
@pytest.mark.parametrize("free_kb", [0, 32])
def test_a_video_onto_a_full_disk_is_an_error(
    workspace: Path, small_disk: Path, free_kb: int
) -> None:
    """``run --video`` where the video does not fit (ffmpeg's exit status is
    checked, and the MP4 checked whole): one line, exit 1, nothing left."""
    (small_disk / "new").mkdir()
    _fill(small_disk, free_kb)
    before = fingerprint(small_disk)
    video = small_disk / "new" / "v.mp4"
    answer = run([*RUN, "--sim", "mujoco", "--video", str(video)], workspace)
    check_refused(answer, ["v.mp4"], codes={1})
    assert "no space left" in answer.stderr and ".part" not in answer.stderr, answer
    assert fingerprint(small_disk) == before, answer
