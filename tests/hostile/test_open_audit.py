"""What demoplan opens: ``import``, ``segment``, ``learn``, ``plan``,
``run --video --frames`` and ``experiments`` run under a file-access monitor
(``strace -f``: tests/hostile/file_audit.py, where the rule and every
allowance are listed) on hostile inputs; any open, creation, rename, link or
removal outside the named inputs and outputs (and Python's, the libraries'
and the system's own files) fails the test.

The inputs lie beside "secrets" — files a careless or hostile input could
lead to: a valid recording and a model beside the recording, a CSV stream
and a bag's ``metadata.yaml`` beside the stream, a demonstration beside the
demonstrations, a hidden file in a folder of them, a link planted where the
video's part file could go. A secret is never touched, not even attempted.
File names come from hypothesis (odd characters: spaces, quotes, escapes,
``..``, a right-to-left mark), derandomized and few: each example is a whole
command under ``strace``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import h5py
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from tests.hostile.file_audit import (
    Allowed,
    Audit,
    audit_environment,
    audited,
    check_accesses,
    parse_log,
    skip_without_strace,
    violations,
)
from tests.hostile.harness import Answer, check_clean, check_refused, run
from tests.hostile.test_recordings import valid_recording
from tests.segmentation.test_import import MODEL, box_states, write_recording
from tests.support.helpers import ONE_MOVE_SCENE
from tests.support.shared_experiments import USERS_NOTES, ExperimentsRun

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES, SRC, TESTS = ROOT / "examples", ROOT / "src", ROOT / "tests"

FEW = settings(
    max_examples=4,
    deadline=None,
    derandomize=True,
    phases=[Phase.explicit, Phase.generate],  # no shrinking: each example is a traced command
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
NAME_PARTS = st.sampled_from(  # the first is the first example's whole name
    [
        "é $'\n\x1b[2J-",
        "a",
        "Z",
        "_",
        "-",
        ".",
        "..",
        " ",
        "é",
        "$",
        "'",
        '"',
        "\\",
        "\n",
        "\x1b[2J",
        "*",
        "#",
    ]
    + ["%", "~", "\u202e"]
)
NAMES = (
    st.lists(NAME_PARTS, min_size=1, max_size=6)
    .map("".join)
    .filter(lambda n: n not in {".", ".."} and len(n.encode()) < 100)
)


@pytest.fixture(scope="session")
def caches(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The libraries' caches for every audited command (matplotlib's font list once)."""
    return tmp_path_factory.mktemp("library-caches")


@contextmanager
def folder() -> Iterator[Path]:
    """A fresh root per example: ``work`` (the command's working folder),
    ``home`` and ``tmp`` (its HOME and TMPDIR), the inputs and the secrets."""
    with tempfile.TemporaryDirectory(prefix="open-audit-") as name:
        root = Path(name).resolve()
        (root / "work").mkdir()
        yield root


def allowed(root: Path, caches: Path, inputs: list[Path], outputs: list[Path]) -> Allowed:
    return Allowed(tuple(inputs), tuple(outputs), audit_environment(root, caches))


# --------------------------------------------------------------------------- import

ONE_NAME_EACH = settings(FEW, max_examples=1)
MODEL_FILES = {  # the model_file attribute, and what models/ holds
    "xml text": MODEL,
    "models/ file": "model_1.xml",
    "models/ link to a secret beside": "model_1.xml",
    "../secret.xml": "../secret.xml",
    "a secret beside": "secret.xml",
}
LINKS = {  # an external link data/demo_2 -> this file's data/demo_1
    "beside": "secret.h5",
    "through ..": "../outside/secret.h5",
    "absolute": "ABSOLUTE",
}
CASES = [(model, None) for model in MODEL_FILES] + [("xml text", link) for link in LINKS]


@pytest.mark.parametrize(("model", "link"), CASES, ids=[f"import {m} {x}" for m, x in CASES])
@given(name=NAMES)
@ONE_NAME_EACH
def test_import_opens_the_recording_and_its_model_only(
    model: str, link: str | None, name: str, caches: Path
) -> None:
    with folder() as root:
        recordings, outside = root / "in", root / "outside"
        (recordings / "models").mkdir(parents=True)
        outside.mkdir()
        secrets = [
            valid_recording(recordings / "secret.h5"),
            valid_recording(outside / "secret.h5"),
            recordings / "secret.xml",
            root / "secret.xml",
        ]
        for xml in secrets[2:]:
            xml.write_text(MODEL)
        if model == "models/ file":
            (recordings / "models" / "model_1.xml").write_text(MODEL)
        elif model == "models/ link to a secret beside":
            (recordings / "models" / "model_1.xml").symlink_to(recordings / "secret.xml")
        recording = write_recording(recordings / f"{name}.hdf5", box_states(), MODEL_FILES[model])
        if link is not None:
            target = str(outside / "secret.h5") if LINKS[link] == "ABSOLUTE" else LINKS[link]
            with h5py.File(recording, "a") as handle:
                handle["data/demo_2"] = h5py.ExternalLink(target, "/data/demo_1")
        out = root / "work" / "out" / name
        rule = allowed(root, caches, [recording, recordings / "models"], [out])
        audit = audited(["import", recording, "-o", out], root / "work", rule, never=secrets)
        if model in {"xml text", "models/ file"} and link is None:
            assert audit.answer.code == 0, audit.answer
            assert len(list(out.iterdir())) == 1, audit.answer
        else:
            check_refused(audit.answer, [f"{recordings}/"], codes={1})  # the name: escaped
            assert not out.exists()


# --------------------------------------------------------------------------- segment


@pytest.mark.slow  # a few commands under strace: handed out early
@given(name=NAMES, output=NAMES)
@FEW
def test_segment_opens_the_stream_only(name: str, output: str, caches: Path) -> None:
    with folder() as root:
        streams = root / "streams"
        streams.mkdir()
        stream = streams / f"{name}.csv"
        shutil.copy(EXAMPLES / "streams" / "set-table-1.csv", stream)
        secrets = [streams / "secret.csv", streams / "metadata.yaml", streams / "secret.db3"]
        for secret in secrets:
            shutil.copy(EXAMPLES / "streams" / "set-table-1.csv", secret)
        # outputs named relative to the working folder
        demo, plot = Path("out") / f"{output}.json", Path("out") / f"{output}.png"
        work = root / "work"
        rule = allowed(root, caches, [stream], [work / demo, work / plot])
        args = ["segment", stream, "-o", demo, "--plot", plot]
        audit = audited(args, work, rule, never=secrets)
        assert audit.answer.code == 0, audit.answer
        assert (work / demo).is_file() and (work / plot).is_file()


@pytest.mark.parametrize("linked", [False, True], ids=["segment bag", "segment bag linking out"])
def test_segment_opens_the_bag_folder_only(linked: bool, caches: Path, tmp_path: Path) -> None:
    """A ROS 2 bag is a folder: its metadata.yaml and the storage files it
    lists. Another bag beside it is never opened, nor a storage file linked
    out of the folder (refused)."""
    from demoplan.segmentation.readers.csv import load_csv
    from demoplan.segmentation.writers import write_bag

    root = tmp_path
    (root / "work").mkdir()
    stream = load_csv(EXAMPLES / "streams" / "set-table-1.csv")
    bag, other = root / "bags" / "bag 1", root / "bags" / "secret"
    for folder in (bag, other):
        write_bag(stream, folder, kind="pose")
    storage = next(bag.glob("*.db3"))
    if linked:
        storage.unlink()
        storage.symlink_to(next(other.glob("*.db3")))
    secrets = [other / "metadata.yaml", next(other.glob("*.db3"))]
    out = root / "work" / "demo.json"
    rule = allowed(root, caches, [bag], [out])
    audit = audited(["segment", bag, "-o", out], root / "work", rule, never=secrets)
    if linked:
        check_refused(audit.answer, [str(storage)], codes={1})
        assert not out.exists()
    else:
        assert audit.answer.code == 0, audit.answer
        assert out.is_file()


# --------------------------------------------------------------------------- learn


@pytest.mark.parametrize(
    "what", ["folder", "file", "folder with a link leading out"], ids=lambda w: f"learn {w}"
)
def test_learn_opens_the_demonstrations_only(what: str, caches: Path, tmp_path: Path) -> None:
    root = tmp_path
    (root / "work").mkdir()
    demos = root / "demos"
    if what == "file":
        demos.mkdir()
        named = demos / "demonstrations.json"
        shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", named)
        secrets = [demos / "secret.json", demos / "demonstrations.yaml"]
    else:  # hidden files and other kinds beside the demonstrations
        shutil.copytree(EXAMPLES / "set_table", demos)
        named = demos
        secrets = [demos / ".secret.json", demos / "notes.txt", demos / "secret.json~"]
    if what == "folder with a link leading out":  # an unpacked archive's link
        secrets.append(root / "secret.json")
        (demos / "demonstration-4.json").symlink_to(root / "secret.json")
    for secret in secrets:
        shutil.copy(EXAMPLES / "set_table" / "demonstration-1.json", secret)
    out = root / "work" / "model.json"
    rule = allowed(root, caches, [named], [out])
    audit = audited(["learn", named, "-o", out, "--paper"], root / "work", rule, never=secrets)
    if what == "folder with a link leading out":
        check_refused(audit.answer, [str(demos / "demonstration-4.json")], codes={1})
        assert not out.exists()
    else:
        assert audit.answer.code == 0, audit.answer
        assert out.is_file()


def test_learn_update_opens_the_model_and_the_demonstrations_only(
    caches: Path, tmp_path: Path
) -> None:
    """``--update`` locks the model's folder while it reads and writes the
    model back; a model beside it is never opened."""
    root = tmp_path
    (root / "work").mkdir()
    models = root / "work" / "models"
    models.mkdir()
    first, second = (EXAMPLES / "set_table" / f"demonstration-{i}.json" for i in (1, 2))
    model = models / "model 'é'.json"
    assert run(["learn", first, "-o", model], root / "work").code == 0
    secret = models / "model.json"
    shutil.copy(model, secret)
    rule = allowed(root, caches, [second, model], [model])
    audit = audited(["learn", "--update", model, second], root / "work", rule, never=[secret])
    assert audit.answer.code == 0, audit.answer
    assert model.read_bytes() != secret.read_bytes()  # written back, with the new one


# --------------------------------------------------------------------------- plan and run


@pytest.fixture(scope="session")
def blocks_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Experiment 2's model, learned once (not audited)."""
    folder = tmp_path_factory.mktemp("blocks-model")
    model = folder / "model.json"
    answer = run(
        ["learn", EXAMPLES / "blocks" / "demonstrations.json", "--paper", "-o", model], folder
    )
    assert answer.code == 0, answer
    return model


@pytest.mark.slow  # a few commands under strace: handed out early
@given(name=NAMES, plot=NAMES)
@FEW
def test_plan_opens_the_model_and_the_scene_only(
    name: str, plot: str, caches: Path, blocks_model: Path
) -> None:
    with folder() as root:
        scenes = root / "scenes"
        scenes.mkdir()
        scene = scenes / f"{name}.json"
        shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", scene)
        secrets = [scenes / "secret.json", scenes / "set-table-cluttered.json"]
        for secret in secrets:
            shutil.copy(EXAMPLES / "scenes" / "set-table-cluttered.json", secret)
        image = root / "work" / "plots" / f"{plot}.png"
        rule = allowed(root, caches, [blocks_model, scene], [image])
        # No time limit: the default 2 s counts from the process start, which
        # strace and a loaded machine slow many times; the plan must come.
        args = ["plan", blocks_model, scene, "--timeout", "inf", "--plot", image]
        audit = audited(args, root / "work", rule, never=secrets)
        assert audit.answer.code == 0, audit.answer
        assert image.is_file()


@given(name=NAMES)
@settings(FEW, max_examples=2)
def test_run_kinematic_with_frames_opens_its_inputs_only(
    name: str, caches: Path, blocks_model: Path
) -> None:
    """The kinematic simulation draws its frames with matplotlib; the frames
    folder is named with odd characters and a user's folder stands beside it.
    One move (a frame per step): the files opened are those of any run."""
    with folder() as root:
        scene = root / "scene.json"
        shutil.copy(ONE_MOVE_SCENE, scene)
        beside = root / "work" / f"{name}-notes"
        beside.mkdir()
        (beside / "frame-001.png").write_bytes(b"the user's")
        frames = root / "work" / name
        rule = allowed(root, caches, [blocks_model, scene], [frames])
        args = ["run", blocks_model, scene, "--frames", frames]
        audit = audited(args, root / "work", rule, never=[beside / "frame-001.png"])
        assert audit.answer.code == 0, audit.answer
        assert any(frames.iterdir())


@pytest.mark.slow
def test_run_with_video_and_frames_opens_its_inputs_only(
    caches: Path, blocks_model: Path, tmp_path: Path
) -> None:
    """MuJoCo (the video records the physics simulation), rendered with EGL;
    a link planted beside the video where a careless part file would go.
    One move: the files opened are those of any run."""
    root = tmp_path
    (root / "work").mkdir()
    scene = root / "scene 'é'.json"
    shutil.copy(ONE_MOVE_SCENE, scene)
    victim = root / "victim.txt"
    victim.write_text("the user's file")
    out = root / "work" / "out $x"
    out.mkdir()
    video, frames = out / "run\u202e.mp4", out / "frames 1"
    (out / f".{video.name}.part.mp4").symlink_to(victim)
    rule = Allowed(
        (blocks_model, scene),
        (video, frames),
        dict(audit_environment(root, caches), MUJOCO_GL="egl"),
        renders=True,
    )
    args = ["run", blocks_model, scene, "--sim", "mujoco", "--video", video, "--frames", frames]
    audit = audited(args, root / "work", rule, never=[victim])
    check_clean(audit.answer, max_seconds=600)
    assert audit.answer.code == 0, audit.answer
    assert video.stat().st_size > 0 and any(frames.iterdir())
    assert victim.read_text() == "the user's file"


# --------------------------------------------------------------------------- experiments


def test_experiments_opens_its_package_data_only(experiments_run: ExperimentsRun) -> None:
    """The experiments read the shipped examples (the checkout's examples/,
    or the package's in a wheel: their named input) and write the report
    folder only; the user's file beside it is never touched. Audited on the
    session's shared run (tests/support/shared_experiments.py: ``experiments --out
    report --open`` without a browser, under strace in tests/support/background.py's
    job), whose harness is Python too: it reads the tests' modules and
    writes the command's captured stdout and stderr and its result pickle."""
    job = experiments_run.job
    trace = job.traced()
    if trace is None:
        skip_without_strace()
        return
    report, work = experiments_run.report, job.work
    rule = Allowed(
        (EXAMPLES, SRC, TESTS),  # the harness imports tests/'s modules
        (report, *experiments_run.harness_writes),
        experiments_run.environment,
        renders=True,
    )
    answer = Answer(
        ("experiments", "--out", "report", "--open"),
        experiments_run.exit_code,
        experiments_run.output,
        experiments_run.stderr,
        0.0,
    )
    audit = Audit(answer, tuple(parse_log(trace.read_bytes().decode("ascii"), ROOT)))
    existed = [work, *work.parents]  # the job's folders, made before the run
    check_accesses(audit, rule, existed=existed, never=[experiments_run.users_file])
    assert audit.answer.code == 0, audit.answer
    assert (report / "report.html").is_file()
    assert experiments_run.users_file.read_text() == USERS_NOTES


# --------------------------------------------------------------------------- the monitor


def _hex(text: str) -> str:
    return "".join(f"\\x{byte:02x}" for byte in os.fsencode(text))


def test_the_monitor_reads_every_kind_of_call_and_fails_what_the_rule_does_not_allow() -> None:
    """The log parser and the rule, on an ``strace -f -y -xx`` log written by
    hand: paths from a dirfd, the working folder, a call interrupted by
    another process's, failed calls, names with a newline; the rule allows
    the input and the output and nothing else here."""
    h = _hex
    odd = "in/a\nb.csv"  # a newline in the name
    log = "\n".join(
        [
            f'100 openat(AT_FDCWD<{h("/w")}>, "{h(odd)}", O_RDONLY|O_CLOEXEC)'
            f" = 3<{h('/w/' + odd)}>",
            f'100 openat(3<{h("/w/out")}>, "{h("../x")}", O_WRONLY|O_CREAT|O_TRUNC, 0666'
            " <unfinished ...>",
            f'101 mkdir("{h("d")}", 0777) = -1 EEXIST (File exists)',
            f"100 <... openat resumed>) = 4<{h('/w/x')}>",
            f'100 rename("{h("/w/.t.tmp")}", "{h("t")}") = 0',
            f'100 symlinkat("{h("/etc/passwd")}", AT_FDCWD<{h("/w")}>, "{h("l")}") = 0',
            f'100 openat(AT_FDCWD<{h("/w")}>, "{h("/s/secret")}", O_RDONLY) = -1 ENOENT (No such)',
            "100 --- SIGCHLD {si_signo=SIGCHLD, si_code=CLD_EXITED} ---",
            "100 +++ exited with 0 +++",
        ]
    )
    accesses = parse_log(log, Path("/c"))
    seen = [(a.pid, a.call, a.path, a.writes, a.real) for a in accesses]
    assert seen == [
        (100, "openat", "/w/in/a\nb.csv", False, "/w/in/a\nb.csv"),
        (101, "mkdir", "/c/d", True, None),  # pid 101's folder: the command's
        (100, "openat", "/w/x", True, "/w/x"),
        (100, "rename", "/w/.t.tmp", True, None),
        (100, "rename", "/w/t", True, None),  # pid 100 was last seen in /w
        (100, "symlinkat", "/w/l", True, None),  # the link's text is no access
        (100, "openat", "/s/secret", False, None),  # attempted: counted
    ]
    env = {"HOME": "/h", "TMPDIR": "/t", "MPLCONFIGDIR": "/m", "XDG_CACHE_HOME": "/x"}
    rule = Allowed((Path("/w/in/a\nb.csv"),), (Path("/w/x"),), env)
    answer = Answer(("segment",), 0, "", "", 0.0)
    found = violations(Audit(answer, tuple(accesses)), rule, existed=[Path("/w"), Path("/")])
    assert [line.split(" (process")[0] for line in found] == [
        "read openat '/s/secret'",
        "write mkdir '/c/d'",
        "write rename '/w/.t.tmp'",
        "write rename '/w/t'",
        "write symlinkat '/w/l'",
    ]
