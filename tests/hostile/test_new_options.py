"""Hostile input to the recently added CLI surface, hand-written as
test_options.py: ``show SCENE`` (``--model``, ``--plot``), ``run --video``
(and Ctrl-C while it records), ``run --clutter`` with hostile extra objects,
``experiments --out`` and ``--open``.

Every case: an exit code of docs/cli.md; when it is not 0, exactly one stderr
line ``demoplan: error: …`` naming the file or the option, no traceback or
warning text, and no file in the working folder new or changed (the outputs
are written all or none). The defects this pass found (ffmpeg's own lines
and a blamed standard output for an unwritable --video, a folder or a link to
a device taken for --video, an escape sequence in an object name sent to the
terminal, show's "size unknown" without what was expected) are fixed; their
cases stay as regression tests.
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

from tests.hostile.harness import (
    DEMOPLAN,
    ERROR_PREFIX,
    HANG_SECONDS,
    NOT_SEEN,
    Answer,
    check_clean,
    check_refused,
    fingerprint,
    private_device,
    run,
)
from tests.support.helpers import EXAMPLES, ONE_MOVE_SCENE
from tests.support.shared_experiments import ExperimentsRun

HAVE_VIDEO = all(importlib.util.find_spec(m) for m in ("mujoco", "imageio_ffmpeg"))
needs_video = pytest.mark.skipif(not HAVE_VIDEO, reason="MuJoCo or imageio-ffmpeg not installed")
MUJOCO = ["--sim", "mujoco"]
RUN = ["run", "model.json", "scene.json"]
ONE_MOVE = ["run", "model.json", "one-move.json"]
"""A run of one move, for the videos that are made: where a video goes and how
it ends is the same for any run, and a frame per step makes it short."""
ESCAPE = "\x1b[31mESC"  # a terminal escape sequence as an object name


def _scene(**extra: dict[str, Any]) -> dict[str, Any]:
    """The Fig. 4 scene with ``extra`` objects added (or replaced)."""
    scene = json.loads((EXAMPLES / "scenes" / "pyramid-fig4.json").read_text())
    scene["objects"].update(extra)
    return scene


def _without_sizes() -> dict[str, Any]:
    scene = _scene()
    for obj in scene["objects"].values():
        del obj["size"]
    return scene


IN_THE_WAY = [0.34, 0.0, 0.0]  # a spot the first plan's moves pass: clutter there is moved
CUBE = [0.04, 0.04, 0.04]
SCENES: dict[str, dict[str, Any]] = {
    # show SCENE
    "far.json": _scene(wood={"position": [1e308, 0.04, 0.0], "size": CUBE}),
    "hugesize.json": _scene(wood={"position": [0.3, 0.04, 0.0], "size": [1e308, 0.04, 0.04]}),
    "hugeyaw.json": _scene(wood={"position": [0.3, 0.04, 0.0], "yaw": 1e300, "size": CUBE}),
    "nosize.json": _without_sizes(),
    "extra-nosize.json": _scene(blue={"position": [0.6, 0.4, 0.0]}),
    "extra.json": _scene(blue={"position": [0.6, 0.4, 0.0], "size": CUBE}),
    # run --clutter
    "c-loc3.json": _scene(loc3={"position": [0.6, 0.4, 0.0], "size": CUBE}),
    "c-freespace1.json": _scene(freespace1={"position": [0.6, 0.4, 0.0], "size": CUBE}),
    "c-grasp2.json": _scene(grasp2={"position": [0.6, 0.4, 0.0], "size": CUBE}),
    "c-space.json": _scene(**{"blue box": {"position": [0.6, 0.4, 0.0], "size": CUBE}}),
    "c-newline.json": _scene(**{"blue\nbox": {"position": [0.6, 0.4, 0.0], "size": CUBE}}),
    "c-empty-name.json": _scene(**{"": {"position": [0.6, 0.4, 0.0], "size": CUBE}}),
    "c-nosize.json": _scene(blue={"position": IN_THE_WAY}),
    "c-null-size.json": _scene(blue={"position": IN_THE_WAY, "size": None}),
    "c-loc3-nosize.json": _scene(loc3={"position": [0.6, 0.4, 0.0]}),
    "c-upper-loc3.json": _scene(LOC3={"position": [0.6, 0.4, 0.0], "size": CUBE}),
    "c-overlap.json": _scene(blue={"position": [0.31, 0.04, 0.0], "size": CUBE}),
    "c-in-the-way.json": _scene(blue={"position": IN_THE_WAY, "size": CUBE}),
    "c-escape.json": _scene(**{ESCAPE: {"position": IN_THE_WAY, "size": CUBE}}),
    "c-escape-nosize.json": _scene(**{ESCAPE: {"position": IN_THE_WAY}}),
}


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("new-options")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", folder / "scene.json")
    shutil.copy(ONE_MOVE_SCENE, folder / "one-move.json")
    assert run(["learn", "demos.json", "--paper", "-o", "model.json"], folder).code == 0
    model = (folder / "model.json").read_text()
    (folder / "oak-model.json").write_text(model.replace('"wood"', '"oak"'))  # no wood in it
    shutil.copy(folder / "model.json", folder / "model.mp4")  # an input named like a video
    for name, scene in SCENES.items():
        (folder / name).write_text(json.dumps(scene))
    text = (folder / "scene.json").read_text()
    (folder / "nan.json").write_text(text.replace("[0.300, 0.040", "[NaN, 0.040"))
    (folder / "overflow.json").write_text(text.replace("[0.300, 0.040", "[1e999, 0.040"))
    tiny = _scene(wood={"position": [0.3, 0.04, 0.0], "size": [0.0001, 0.0001, 0.0001]})
    (folder / "tiny-scene.json").write_text(json.dumps(tiny))  # MuJoCo's gripper cannot take it
    (folder / "empty.json").write_text("{}\n")
    for name in ("folder", "folder.png", "vid.mp4", "others", "old-report"):
        (folder / name).mkdir()
    (folder / "others" / "thesis.tex").write_text("\\documentclass{article}\n")
    (folder / "old-report" / "report.md").write_text("# an earlier report\n")
    (folder / "old-report" / "notes.txt").write_text("mine, not the report's\n")
    (folder / "link.mp4").symlink_to("scene.json")  # a link to an input, named like a video
    return folder


def _case(workspace: Path, tmp_path: Path) -> Path:
    folder = tmp_path / "case"
    shutil.copytree(workspace, folder, symlinks=True)
    return folder


def _changed(before: dict[str, str], after: dict[str, str]) -> set[str]:
    """Top-level names new, gone or changed."""
    names = set(before) ^ set(after)
    names |= {p for p in after if p in before and after[p] != before[p]}
    return {p.split("/")[0] for p in names}


def check_answer(
    answer: Answer,
    before: dict[str, str],
    after: dict[str, str],
    names: list[str],
    codes: set[int],
    outputs: tuple[str, ...] = (),
) -> None:
    """docs/cli.md for one case: an exit code from ``codes``; refused in one line
    naming one of ``names`` (not a temporary file beside it) with nothing
    changed, or done with only ``outputs`` changed."""
    assert answer.code in codes, f"exit code not in {sorted(codes)}: {answer}"
    if answer.code == 0:
        check_clean(answer)
        assert _changed(before, after) <= set(outputs), f"files changed: {answer}"
    else:
        check_refused(answer, names, codes=codes - {0})
        for temporary in (".part.", ".tmp"):  # the output as the user named it
            assert temporary not in answer.stderr, f"names a temporary file: {answer}"
        assert after == before, f"files changed: {_changed(before, after)}: {answer}"


# ---------------------------------------------------------------------------------------
# show SCENE
# (arguments, names one of which the error line must contain, exit codes, outputs on 0)

SHOW: list[object] = [
    pytest.param(["show", "nan.json"], ["nan.json"], {1}, (), id="show-nan"),
    pytest.param(["show", "overflow.json"], ["overflow.json"], {1}, (), id="show-1e999"),
    pytest.param(["show", "far.json"], ["far.json"], {1}, (), id="show-1e308-position"),
    pytest.param(["show", "hugesize.json"], ["hugesize.json"], {1}, (), id="show-1e308-size"),
    pytest.param(["show", "hugeyaw.json"], ["hugeyaw.json"], {0, 1}, (), id="show-1e300-yaw"),
    pytest.param(["show", "nosize.json"], ["nosize.json"], {1}, (), id="show-no-sizes"),
    pytest.param(["show", "folder"], ["folder"], {1}, (), id="show-a-folder"),
    pytest.param(["show", "/dev/null"], ["/dev/null"], {1}, (), id="show-dev-null"),
    pytest.param(
        ["show", "nosize.json", "--model", "demos.json"],
        ["demos.json"],
        {1},
        (),
        id="show-model-is-demonstrations",
    ),
    pytest.param(
        ["show", "nosize.json", "--model", "scene.json"],
        ["scene.json"],
        {1},
        (),
        id="show-model-is-a-scene",
    ),
    pytest.param(
        ["show", "nosize.json", "--model", "empty.json"],
        ["empty.json"],
        {1},
        (),
        id="show-model-empty-document",
    ),
    pytest.param(
        ["show", "nosize.json", "--model", "folder"], ["folder"], {1}, (), id="show-model-folder"
    ),
    pytest.param(
        ["show", "nosize.json", "--model", "/dev/null"],
        ["/dev/null"],
        {1},
        (),
        id="show-model-dev-null",
    ),
    pytest.param(
        ["show", "nosize.json", "--model", "oak-model.json"],
        ["nosize.json"],
        {1},
        (),
        id="show-model-lacks-an-object",
    ),
    pytest.param(
        ["show", "extra-nosize.json", "--model", "model.json"],
        ["extra-nosize.json"],
        {1},
        (),
        id="show-model-lacks-an-unsized-object",
    ),
    pytest.param(
        ["show", "extra.json", "--model", "model.json"],
        ["extra.json"],
        {0, 1},
        (),
        id="show-model-lacks-a-sized-object",
    ),
    pytest.param(  # a model's plot: its demonstrations and states
        ["show", "model.json", "--plot", "p.png"], [], {0}, ("p.png",), id="show-plot-of-a-model"
    ),
    pytest.param(
        ["show", "model.json", "--model", "model.json"],
        ["--model"],
        {1, 2},
        (),
        id="show-model-of-a-model",
    ),
    pytest.param(
        ["show", "scene.json", "--plot", "bad.xyz"], ["--plot"], {1, 2}, (), id="show-plot-bad-ext"
    ),
    pytest.param(
        ["show", "scene.json", "--plot", "folder.png"],
        ["folder.png"],
        {1, 2},
        (),
        id="show-plot-a-folder",
    ),
    pytest.param(
        ["show", "scene.json", "--plot", "scene.json"],
        ["scene.json"],
        {1, 2},
        (),
        id="show-plot-over-the-input",
    ),
    pytest.param(
        ["show", "scene.json", "--plot", "/proc/no/x.png"],
        ["/proc/no/x.png"],
        {1},
        (),
        id="show-plot-no-such-place",
    ),
    pytest.param(
        ["show", "scene.json", "--plot", "/sys/x.png"],
        ["/sys/x.png"],
        {1},
        (),
        id="show-plot-unwritable",
    ),
    pytest.param(
        ["show", "scene.json", "--plot", "scene.json/x.png"],
        ["scene.json/x.png"],
        {1},
        (),
        id="show-plot-under-a-file",
    ),
    pytest.param(
        ["show", "nan.json", "--plot", "p.png"], ["nan.json"], {1}, (), id="show-plot-bad-scene"
    ),
    pytest.param(  # the control: sizes from the model, the plot written
        ["show", "nosize.json", "--model", "model.json", "--plot", "p.png"],
        [],
        {0},
        ("p.png",),
        id="show-model-and-plot-work",
    ),
]


@pytest.mark.parametrize(("args", "names", "codes", "outputs"), SHOW)
def test_show_a_hostile_scene(
    workspace: Path,
    tmp_path: Path,
    args: list[str],
    names: list[str],
    codes: set[int],
    outputs: tuple[str, ...],
) -> None:
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run(args, folder, timeout=60)
    check_answer(answer, before, fingerprint(folder), names, codes, outputs)
    for output in outputs:
        assert (folder / output).stat().st_size > 0


def test_show_a_scene_without_sizes_says_what_was_expected(workspace: Path, tmp_path: Path) -> None:
    answer = run(["show", "nosize.json"], _case(workspace, tmp_path))
    check_refused(answer, ["nosize.json"], codes={1})
    assert "expected" in answer.stderr, answer


# ---------------------------------------------------------------------------------------
# run --video

VIDEO: list[object] = [
    pytest.param([*RUN, *MUJOCO, "--video", "run.avi"], ["--video"], {2}, id="run-video-avi"),
    pytest.param([*RUN, "--video", "run.mp4"], ["--video"], {2}, id="run-video-without-mujoco"),
    pytest.param(
        [*RUN, *MUJOCO, "--video", "scene.json"], ["--video"], {1, 2}, id="run-video-over-the-scene"
    ),
    pytest.param(
        ["run", "model.mp4", "scene.json", *MUJOCO, "--video", "model.mp4"],
        ["model.mp4"],
        {1, 2},
        id="run-video-over-the-model",
    ),
    pytest.param(  # link.mp4 -> scene.json
        [*RUN, *MUJOCO, "--video", "link.mp4"], ["link.mp4"], {1, 2}, id="run-video-over-a-link"
    ),
    pytest.param(
        [*RUN, *MUJOCO, "--video", "folder"], ["folder", "--video"], {1, 2}, id="run-video-folder"
    ),
    pytest.param(  # refused before the first motion: no video either
        ["run", "model.json", "tiny-scene.json", *MUJOCO, "--video", "v.mp4"],
        ["objects.wood.size"],
        {1},
        marks=needs_video,
        id="run-video-ungraspable-scene",
    ),
]


@pytest.mark.parametrize(("args", "names", "codes"), VIDEO)
def test_run_a_hostile_video(
    workspace: Path, tmp_path: Path, args: list[str], names: list[str], codes: set[int]
) -> None:
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run(args, folder, timeout=60)
    check_answer(answer, before, fingerprint(folder), names, codes)


@needs_video
@pytest.mark.parametrize(
    "path",
    [
        pytest.param(path, id=name)
        for path, name in [
            ("/proc/no/run.mp4", "run-video-no-such-place"),
            ("/sys/run.mp4", "run-video-unwritable-folder"),
            ("scene.json/run.mp4", "run-video-under-a-file"),
            ("missing/run.mp4", "run-video-missing-folder"),  # --plot and -o make it
        ]
    ],
)
def test_run_a_video_where_it_cannot_be_written(workspace: Path, tmp_path: Path, path: str) -> None:
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run([*ONE_MOVE, *MUJOCO, "--video", path], folder, timeout=60)
    after = fingerprint(folder)
    if path == "missing/run.mp4":  # made like the folder of any other output, or refused
        check_answer(answer, before, after, [path], {0, 1}, outputs=("missing",))
    else:
        check_answer(answer, before, after, [path], {1})


@pytest.mark.slow
@needs_video
def test_run_a_video_into_a_folder_named_like_one(workspace: Path, tmp_path: Path) -> None:
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run([*ONE_MOVE, *MUJOCO, "--video", "vid.mp4"], folder, timeout=60)
    check_answer(answer, before, fingerprint(folder), ["vid.mp4"], {1, 2})


@pytest.mark.slow
@needs_video
def test_run_a_video_into_a_link_to_dev_full(workspace: Path, tmp_path: Path) -> None:
    folder = _case(workspace, tmp_path)
    (folder / "full.mp4").symlink_to(private_device(tmp_path / "full", "full"))
    before = fingerprint(folder)
    answer = run([*ONE_MOVE, *MUJOCO, "--video", "full.mp4"], folder, timeout=60)
    assert (folder / "full.mp4").is_symlink(), f"the link was replaced: {answer}"
    check_answer(answer, before, fingerprint(folder), ["full.mp4"], {1})


def _complete_mp4(path: Path) -> bool:
    """An MP4 as ffmpeg finishes it: its index (moov) written after the frames."""
    data = path.read_bytes()
    return data[4:8] == b"ftyp" and b"moov" in data and b"mdat" in data


@pytest.mark.slow
@needs_video
def test_run_a_video_works(workspace: Path, tmp_path: Path) -> None:
    """The control for the cases above: one complete MP4 and nothing else."""
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run([*ONE_MOVE, *MUJOCO, "--video", "run.mp4"], folder, timeout=60)
    check_answer(answer, before, fingerprint(folder), [], {0}, outputs=("run.mp4",))
    assert _complete_mp4(folder / "run.mp4")


@needs_video
@pytest.mark.parametrize(
    ("group", "delay"),
    [
        pytest.param(False, 0.0, id="run-video-ctrl-c-as-recording-starts"),
        pytest.param(True, 0.5, id="run-video-ctrl-c-to-the-group"),  # ffmpeg gets it too
    ],
)
def test_ctrl_c_while_recording_a_video(
    workspace: Path, tmp_path: Path, group: bool, delay: float
) -> None:
    """Ctrl-C once ffmpeg has started writing: exit 130 (at once; only a hang
    is timed, HANG_SECONDS), the one line ``demoplan: interrupted``, no video,
    partial or temporary. ``group``: as a terminal sends it, to ffmpeg as well
    (its own process group)."""
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    process = subprocess.Popen(
        [DEMOPLAN, *RUN, *MUJOCO, "--video", "run.mp4"],
        cwd=folder,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=group,
    )
    began = time.monotonic()
    while time.monotonic() - began < HANG_SECONDS and process.poll() is None:
        if any("run.mp4" in p.name for p in folder.iterdir()):  # ffmpeg is writing
            break
        time.sleep(0.01)
    time.sleep(delay)
    sent = time.monotonic()
    if group:
        os.killpg(process.pid, signal.SIGINT)
    else:
        process.send_signal(signal.SIGINT)
    try:
        _, err = process.communicate(timeout=2 * HANG_SECONDS)
    except subprocess.TimeoutExpired:
        if group:
            os.killpg(process.pid, signal.SIGKILL)
        else:
            process.kill()
        raise AssertionError(f"still running {2 * HANG_SECONDS:g} s after Ctrl-C") from None
    seconds = time.monotonic() - sent
    for text in NOT_SEEN:
        assert text not in err, err
    if process.returncode == 0:  # finished before the signal: the whole video
        assert _changed(before, fingerprint(folder)) == {"run.mp4"}
        assert _complete_mp4(folder / "run.mp4")
        return
    assert process.returncode == 130, f"exit {process.returncode}: {err}"
    assert err.splitlines() == ["demoplan: interrupted"], err
    assert seconds < HANG_SECONDS, f"{seconds:.2f} s after Ctrl-C"
    assert fingerprint(folder) == before, f"left: {_changed(before, fingerprint(folder))}"


# ---------------------------------------------------------------------------------------
# run --clutter

CLUTTER: list[object] = [
    pytest.param("c-loc3.json", "objects.loc3", {1}, id="run-clutter-loc3"),
    pytest.param("c-freespace1.json", "objects.freespace1", {1}, id="run-clutter-freespace1"),
    pytest.param("c-grasp2.json", "objects.grasp2", {1}, id="run-clutter-grasp2"),
    pytest.param("c-space.json", "objects['blue box']", {1}, id="run-clutter-a-space"),
    pytest.param("c-newline.json", "objects['blue\\nbox']", {1}, id="run-clutter-a-newline"),
    pytest.param("c-empty-name.json", "objects", {1}, id="run-clutter-an-empty-name"),
    pytest.param("c-nosize.json", "objects.blue", {1}, id="run-clutter-no-size"),
    pytest.param("c-null-size.json", "objects.blue", {1}, id="run-clutter-size-null"),
    pytest.param("c-loc3-nosize.json", "objects.loc3", {1}, id="run-clutter-loc3-no-size"),
    pytest.param("c-overlap.json", "objects.blue", {1}, id="run-clutter-overlaps-wood"),
    pytest.param("c-upper-loc3.json", "LOC3", {0, 1}, id="run-clutter-LOC3"),
    pytest.param("c-in-the-way.json", "", {0}, id="run-clutter-in-the-way-works"),  # the control
]


@pytest.mark.parametrize(("scene", "field", "codes"), CLUTTER)
def test_run_with_hostile_clutter(
    workspace: Path, tmp_path: Path, scene: str, field: str, codes: set[int]
) -> None:
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run(["run", "model.json", scene, "--clutter"], folder, timeout=60)
    check_answer(answer, before, fingerprint(folder), [scene], codes)
    if answer.code:
        assert field in answer.stderr, f"does not name {field}: {answer}"


@pytest.mark.parametrize(
    "scene",
    [
        pytest.param("c-escape.json", id="run-clutter-escape-moved"),
        pytest.param("c-escape-nosize.json", id="run-clutter-escape-no-size"),
    ],
)
def test_run_with_clutter_named_by_an_escape_sequence(
    workspace: Path, tmp_path: Path, scene: str
) -> None:
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run(["run", "model.json", scene, "--clutter"], folder, timeout=60)
    check_answer(answer, before, fingerprint(folder), [scene], {0, 1})
    assert ESCAPE not in answer.stdout + answer.stderr, f"raw escape printed: {answer}"


# ---------------------------------------------------------------------------------------
# experiments --out, --open

EXPERIMENTS: list[object] = [
    pytest.param("scene.json", id="experiments-out-a-file"),
    pytest.param("others", id="experiments-out-a-folder-of-other-files"),
    pytest.param("old-report", id="experiments-out-an-old-report-and-other-files"),
    pytest.param("/proc/no/report", id="experiments-out-no-such-place"),
    pytest.param("/sys/report", id="experiments-out-unwritable"),
    pytest.param("scene.json/report", id="experiments-out-under-a-file"),
    pytest.param("", id="experiments-out-empty-name"),  # the working folder itself
]


@pytest.mark.parametrize("out", EXPERIMENTS)
def test_experiments_into_a_hostile_place(workspace: Path, tmp_path: Path, out: str) -> None:
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run(["experiments", "--out", out], folder, timeout=60)
    check_answer(answer, before, fingerprint(folder), [out or "."], {1, 2})


@pytest.mark.slow
def test_experiments_open_without_a_browser(experiments_run: ExperimentsRun) -> None:
    """No display, no terminal browser, no $BROWSER: the report is written, exit
    0, and one note on stderr saying to open the page by hand. (The session's
    run of ``experiments --out report --open``, in a process of its own without
    those variables: tests/support/shared_experiments.py.)"""
    answer = experiments_run
    assert answer.exit_code == 0, answer.stderr
    for text in NOT_SEEN:
        assert text not in answer.stderr, answer.stderr
    lines = answer.stderr.splitlines()
    assert len(lines) == 1, answer.stderr
    assert lines[0].startswith("demoplan: note:") and not lines[0].startswith(ERROR_PREFIX)
    assert "report/report.html" in lines[0] and "browser" in lines[0], answer.stderr
    assert (answer.report / "report.html").stat().st_size > 0
    assert "Report page: report/report.html" in answer.output
