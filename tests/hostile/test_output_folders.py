"""Output folders and files as a user's disk holds them (issue 27): demoplan
never removes a file it cannot prove it wrote, leaves nothing behind, and
writes nothing half.

A folder output (``run --frames``, ``experiments --out``) is replaced only
where its ``.demoplan-manifest.json`` lists every file in it, unchanged
(docs/limits.md, "Outputs"); a refused or failed command leaves every file
outside its outputs — and the outputs themselves — as they were, and makes
no folder. Each refusal is one line on stderr with the exit code of
docs/limits.md (1: a file that cannot be written or replaced).

The regression cases of the issue: a user's ``experiment1-notes.txt`` in a
report folder, a user's folder named like a frame, an earlier import's file
replaced by an import that then failed (the destroyed files); a link to an
output folder leaving ``.NAME.old-….tmp``, a refused ``run --video new/v.mp4``
leaving ``new/``, a planted ``.v.mp4.part.mp4`` link whose target ffmpeg
truncated (the leftovers and the victim).
"""

from __future__ import annotations

import importlib.util
import json
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import h5py
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.fileio import MANIFEST
from tests.hostile.harness import check_refused, fingerprint, run
from tests.segmentation.test_import import MODEL, box_states
from tests.support.helpers import EXAMPLES, ONE_MOVE_SCENE

HAVE_VIDEO = all(importlib.util.find_spec(m) for m in ("mujoco", "imageio_ffmpeg"))
needs_video = pytest.mark.skipif(not HAVE_VIDEO, reason="MuJoCo or imageio-ffmpeg not installed")
RUN = ["run", "model.json", "scene.json"]


def _recording(path: Path, shift: float) -> Path:
    """A toy robosuite recording of two demonstrations (``demo_1``, ``demo_2``),
    the box carried ``shift`` m further in each."""
    with h5py.File(path, "w") as handle:
        data = handle.create_group("data")
        data.attrs["env"] = "Toy"
        for k in (1, 2):
            states = box_states()
            states[:, 5] += shift * k
            demo = data.create_group(f"demo_{k}")
            demo.create_dataset("states", data=states)
            demo.attrs["model_file"] = MODEL
    return path


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A learned model and its scene, and ``frames/``: a frames folder this
    demoplan wrote (with its manifest)."""
    folder = tmp_path_factory.mktemp("output-folders")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(ONE_MOVE_SCENE, folder / "scene.json")  # a frame per step: the fewer the cheaper
    assert run(["learn", "demos.json", "--paper", "-o", "model.json"], folder).code == 0
    answer = run([*RUN, "--frames", "frames"], folder)
    assert answer.code == 0, answer
    return folder


def _case(workspace: Path, tmp_path: Path) -> Path:
    folder = tmp_path / "case"
    shutil.copytree(workspace, folder, symlinks=True)
    return folder


def _names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def _refused_and_unchanged(
    answer: object, names: list[str], before: dict[str, str], after: dict[str, str]
) -> None:
    """One line naming one of ``names``, exit 1, never a temporary file's
    name, and every file as it was (nothing made, changed or removed)."""
    check_refused(answer, names, codes={1})  # type: ignore[arg-type]
    stderr = answer.stderr  # type: ignore[attr-defined]
    assert ".tmp" not in stderr and ".part" not in stderr, answer
    changed = sorted(k for k in before.keys() | after.keys() if before.get(k) != after.get(k))
    assert not changed, f"changed: {changed}: {answer}"


# ---------------------------------------------------------------------------------------
# A folder demoplan wrote is replaced; anything else in it is refused, never removed


def test_an_earlier_frames_folder_is_replaced_and_nothing_is_left(
    workspace: Path, tmp_path: Path
) -> None:
    """The control: a second run replaces the frames this demoplan wrote; the
    new folder's manifest lists exactly its files with their SHA-256, and no
    temporary or set-aside folder is left anywhere."""
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run([*RUN, "--frames", "frames", "--seed", "3"], folder)
    assert answer.code == 0, answer
    after = fingerprint(folder)
    changed = {k for k in before.keys() | after.keys() if before.get(k) != after.get(k)}
    assert all(k.startswith("frames/") for k in changed), changed
    assert _names(folder) == _names(workspace)
    manifest = json.loads((folder / "frames" / MANIFEST).read_text())
    listed = set(manifest["files"])
    assert listed == {p.name for p in (folder / "frames").iterdir()} - {MANIFEST}
    assert "storyboard.png" in listed
    import hashlib

    for name, digest in manifest["files"].items():
        assert hashlib.sha256((folder / "frames" / name).read_bytes()).hexdigest() == digest


USER_NAMES = st.one_of(
    st.sampled_from(
        [
            "frame-0099.png",  # named like a frame: the case
            "frame-0001.png",  # the name of a frame demoplan wrote, now the user's
            "storyboard.png",
            "experiment1-notes.txt",
            "report.md",
            MANIFEST,  # the user's own manifest
            "notes.txt",
            ".hidden",
        ]
    ),
    st.text(
        st.characters(codec="utf-8", exclude_characters="/\x00", exclude_categories=["Cs"]),
        min_size=1,
        max_size=40,
    ).filter(lambda n: n not in {".", ".."}),
)


@settings(
    max_examples=12,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(name=USER_NAMES, as_folder=st.booleans())
def test_a_users_file_in_a_frames_folder_is_never_removed(
    workspace: Path, tmp_path_factory: pytest.TempPathFactory, name: str, as_folder: bool
) -> None:
    """A file or folder of the user's in a frames folder demoplan wrote —
    whatever its name, a frame's own included (then the user's content
    replaces demoplan's) — makes ``run --frames`` refuse in one line and
    leave everything as it was."""
    folder = _case(workspace, tmp_path_factory.mktemp("user"))
    mine = folder / "frames" / name
    if mine.exists():
        mine.unlink()
    if as_folder:
        mine.mkdir()
        (mine / "mine.txt").write_text("the user's\n")
    else:
        mine.write_bytes(b"the user's own file\n")
    before = fingerprint(folder)
    answer = run([*RUN, "--frames", "frames"], folder)
    _refused_and_unchanged(answer, ["frames"], before, fingerprint(folder))


def test_a_users_notes_in_a_report_folder_are_kept(workspace: Path, tmp_path: Path) -> None:
    """The issue's case: ``experiments --out rep`` where ``rep`` holds an
    earlier report and the user's ``experiment1-notes.txt``: refused before
    any work, the notes kept. (An earlier report written by this demoplan is
    a folder with a manifest: the frames folder stands in for it, the
    experiments take minutes.)"""
    folder = _case(workspace, tmp_path)
    (folder / "frames" / "experiment1-notes.txt").write_text("my notes\n")
    before = fingerprint(folder)
    answer = run(["experiments", "--out", "frames"], folder, timeout=60)
    _refused_and_unchanged(answer, ["frames"], before, fingerprint(folder))
    assert "experiment1-notes.txt" in answer.stderr


def test_a_report_of_an_older_demoplan_is_refused_with_what_to_do(tmp_path: Path) -> None:
    """A report folder without a manifest (written by a demoplan before 1.x's
    manifests, or by hand) is not proof: refused, saying to remove it or
    choose another name (docs/limits.md, "Outputs")."""
    old = tmp_path / "rep"
    old.mkdir()
    for name in ("report.md", "report.html", "summary.json"):
        (old / name).write_text("an old report\n")
    before = fingerprint(tmp_path)
    answer = run(["experiments", "--out", "rep"], tmp_path, timeout=60)
    _refused_and_unchanged(answer, ["rep"], before, fingerprint(tmp_path))
    assert MANIFEST in answer.stderr and "remove" in answer.stderr, answer


def test_a_manifest_that_lies_about_a_file_is_refused(workspace: Path, tmp_path: Path) -> None:
    """A listed file whose content is not what the manifest says is the
    user's: refused, kept."""
    folder = _case(workspace, tmp_path)
    board = folder / "frames" / "storyboard.png"
    board.write_bytes(board.read_bytes() + b"edited")
    before = fingerprint(folder)
    answer = run([*RUN, "--frames", "frames"], folder)
    _refused_and_unchanged(answer, ["frames"], before, fingerprint(folder))
    assert "storyboard.png" in answer.stderr


def test_a_link_to_an_output_folder_stays_and_leaves_nothing(
    workspace: Path, tmp_path: Path
) -> None:
    """``--frames link`` where ``link`` names a frames folder elsewhere: the
    folder it names is replaced, the link stays, and no ``.link.old-….tmp``
    (nor any other new name) is left beside either."""
    folder = _case(workspace, tmp_path)
    (folder / "elsewhere").mkdir()
    (folder / "frames").rename(folder / "elsewhere" / "real")
    (folder / "link").symlink_to("elsewhere/real")
    names = _names(folder), _names(folder / "elsewhere")
    answer = run([*RUN, "--frames", "link", "--seed", "2"], folder)
    assert answer.code == 0, answer
    assert (folder / "link").is_symlink() and (folder / "link").readlink() == Path("elsewhere/real")
    assert (_names(folder), _names(folder / "elsewhere")) == names
    assert (folder / "elsewhere" / "real" / MANIFEST).is_file()


# ---------------------------------------------------------------------------------------
# import -o: an earlier import's files are as they were when a later one fails


@pytest.fixture
def immutable() -> Iterator[list[Path]]:
    """Files made immutable (``chattr +i``: a rename over them fails, even
    for root) for one test, made mutable again after it."""
    files: list[Path] = []
    yield files
    for path in files:
        subprocess.run(["chattr", "-i", str(path)], check=False, capture_output=True)


def test_an_import_that_fails_half_way_restores_the_earlier_import(
    tmp_path: Path, immutable: list[Path]
) -> None:
    """``import -o out`` over an earlier import whose second file cannot be
    replaced (immutable): the first file, already renamed into place when the
    second rename fails, is put back — the earlier import is as it was, and
    no temporary or kept-aside file is left."""
    _recording(tmp_path / "first.hdf5", 0.0)
    _recording(tmp_path / "toy.hdf5", 0.05)  # the same names, other content
    first = run(["import", "first.hdf5", "-o", "out", "--name-prefix", "toy"], tmp_path)
    assert first.code == 0, first
    assert _names(tmp_path / "out") == ["toy-demo_1.json", "toy-demo_2.json"]
    _make_immutable(tmp_path / "out" / "toy-demo_2.json", immutable)
    before = fingerprint(tmp_path)
    answer = run(["import", "toy.hdf5", "-o", "out", "--name-prefix", "toy"], tmp_path)
    _refused_and_unchanged(answer, ["out"], before, fingerprint(tmp_path))


def _make_immutable(path: Path, immutable: list[Path]) -> None:
    made = subprocess.run(["chattr", "+i", str(path)], check=False, capture_output=True)
    if made.returncode:
        pytest.skip(f"chattr +i is not supported here: {made.stderr.decode().strip()}")
    immutable.append(path)


@pytest.mark.parametrize(
    ("args", "second"),
    [
        (["pddl", "problem.xml", "-o", "pd"], "pd/problem.pddl"),
        (["problem", "model.json", "scene.json", "--pddl", "-o", "p.pddl"], "p.pddl"),
    ],
    ids=["pddl", "problem-pddl"],
)
def test_a_pddl_pair_that_fails_half_way_keeps_the_earlier_pair(
    workspace: Path, tmp_path: Path, immutable: list[Path], args: list[str], second: str
) -> None:
    """The domain and the problem over an earlier pair whose second file (the
    problem, renamed after the domain) cannot be replaced: the domain is put
    back, never left new beside the old problem."""
    folder = _case(workspace, tmp_path)
    shutil.copy(EXAMPLES / "planning" / "paper-example.xml", folder / "problem.xml")
    earlier = run(args, folder)
    assert earlier.code == 0, earlier
    for path in (folder / second).parent.iterdir():
        if path.suffix == ".pddl":
            path.write_text(f"; an earlier {path.name}\n")  # so that the new one differs
    _make_immutable(folder / second, immutable)
    before = fingerprint(folder)
    answer = run(args, folder)
    _refused_and_unchanged(answer, [second], before, fingerprint(folder))


@pytest.mark.parametrize("link", ["loop", "loop/s.json", "a"])
def test_an_output_through_a_loop_of_links_is_refused(
    workspace: Path, tmp_path: Path, link: str
) -> None:
    """``perceive -o`` (and any file output) through a link to itself or a
    loop of two: one line, nothing written anywhere."""
    folder = _case(workspace, tmp_path)
    shutil.copy(EXAMPLES / "perception" / "blocks-top.png", folder / "top.png")
    (folder / "loop").symlink_to("loop")
    (folder / "a").symlink_to("b")
    (folder / "b").symlink_to("a")
    before = fingerprint(folder)
    answer = run(
        ["perceive", "top.png", "--px-per-m", "1000", "--origin", "0.05", "-0.21", "-o", link],
        folder,
    )
    _refused_and_unchanged(answer, [link], before, fingerprint(folder))


# ---------------------------------------------------------------------------------------
# run --video


def test_a_refused_video_run_makes_no_folder(workspace: Path, tmp_path: Path) -> None:
    """``--video new/deeper/v.mp4`` with a scene the model cannot use: the
    video's place is checked before the work (a private folder made there
    and removed at once), then the run is refused: ``new`` is not left."""
    folder = _case(workspace, tmp_path)
    before = fingerprint(folder)
    answer = run(
        ["run", "model.json", "demos.json", "--sim", "mujoco", "--video", "new/deeper/v.mp4"],
        folder,
    )
    _refused_and_unchanged(answer, ["demos.json"], before, fingerprint(folder))


@pytest.mark.slow
@needs_video
def test_a_planted_part_file_link_is_never_followed(workspace: Path, tmp_path: Path) -> None:
    """A link named as the old partial file (``.v.mp4.part.mp4``) planted
    beside the video, pointing at a user's file: the file and the link are
    untouched, the video is complete and nothing else is new."""
    folder = _case(workspace, tmp_path)
    (folder / "victim.txt").write_text("a user's file\n")
    (folder / ".v.mp4.part.mp4").symlink_to("victim.txt")
    before = fingerprint(folder)
    answer = run([*RUN, "--sim", "mujoco", "--video", "v.mp4"], folder, timeout=120)
    assert answer.code == 0, answer
    after = fingerprint(folder)
    assert {k for k in before.keys() | after.keys() if before.get(k) != after.get(k)} == {"v.mp4"}
    data = (folder / "v.mp4").read_bytes()
    assert data[4:8] == b"ftyp" and b"moov" in data
