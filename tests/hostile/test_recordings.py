"""Hostile HDF5 recordings for ``demoplan import`` (docs/limits.md "Recordings").

Each case is a recording that is valid but for one hostile part, made here
with h5py: a container pointing elsewhere (an external link, external raw
storage, a virtual dataset — the file it points to exists and holds a valid
recording, so following it would succeed), names that would be paths, a
model XML with numbers no model holds, a dataset declaring more than the file
holds. Every refusal is one line and exit 1, nothing is written, and — for the
containers — the command is run under ``strace`` and never opens the file
pointed to.
"""

from __future__ import annotations

import json
import re
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.segmentation.types import ObjectTrack, PoseStream
from demoplan.segmentation.writers import write_bag, write_csv
from demoplan.wording import printable
from tests.hostile import file_audit
from tests.hostile.harness import Answer, check_refused, fingerprint, run
from tests.segmentation.test_import import MODEL, box_states, write_recording
from tests.support.helpers import EXAMPLES

GENERATED = settings(
    max_examples=12,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@contextmanager
def folder() -> Iterator[Path]:
    """A fresh folder per generated example (tmp_path is one per test)."""
    with tempfile.TemporaryDirectory(prefix="hostile-recording-") as name:
        yield Path(name).resolve()


def import_refused(recording: Path, cwd: Path, *names: str) -> Answer:
    """``import RECORDING -o out``: one error line naming the recording (and
    ``names``), exit 1, no output folder, no file changed or made under ``cwd``."""
    out = cwd / "out"
    before = fingerprint(cwd)
    answer = run(["import", recording, "-o", out], cwd)
    check_refused(answer, [str(recording)], codes={1})
    for name in names:
        assert name in answer.stderr, f"{name!r} not named: {answer}"
    assert not out.exists(), answer
    assert fingerprint(cwd) == before, answer
    return answer


# --------------------------------------------------------------------------- containers


def run_audited(args: list[str | Path], cwd: Path) -> tuple[Answer, set[Path]]:
    """Run ``demoplan ARGS`` under ``strace -f`` (tests/hostile/file_audit.py):
    its answer and every path it (or a thread or child of it) tried to open,
    as named and as opened (links followed)."""
    audit = file_audit.run_audited(args, cwd)
    return audit.answer, {Path(path) for path in audit.touched()}


def valid_recording(path: Path) -> Path:
    """A recording of two demonstrations, each a box carried 0.3 m."""
    write_recording(path, box_states())
    with h5py.File(path, "a") as handle:
        handle.copy(handle["data/demo_1"], "data/demo_2")
    return path


TARGETS: dict[str, Callable[[Path], tuple[Path, str]]] = {  # (file, the name written)
    "beside": lambda root: (root / "in" / "secret.h5", "secret.h5"),
    "outside": lambda root: (root / "outside" / "secret.h5", "../outside/secret.h5"),
    "absolute": lambda root: (
        root / "elsewhere" / "secret.h5",
        str(root / "elsewhere" / "secret.h5"),
    ),
}
PLACES = ["data/demo_1", "data/demo_2/states", "data/demo_3", "extra"]


def point_elsewhere(recording: Path, kind: str, place: str, written: str) -> str:
    """Put ``kind`` at ``place`` of ``recording``, pointing to ``written``
    (the name as the file records it); returns the object named in the refusal."""
    with h5py.File(recording, "a") as handle:
        if place in handle:
            del handle[place]
        if kind == "external link":
            inside = "/data/demo_1/states" if place.endswith("states") else "/data/demo_1"
            handle[place] = h5py.ExternalLink(written, inside)
            return place
        group_name, _, _ = place.rpartition("/") if place.endswith("states") else (place, "", "")
        group = handle.require_group(group_name)
        states = box_states()
        if kind == "external storage":
            group.create_dataset(
                "states", shape=states.shape, dtype="f8", external=[(written, 0, states.nbytes)]
            )
        else:
            layout = h5py.VirtualLayout(shape=states.shape, dtype="f8")
            layout[:] = h5py.VirtualSource(written, "data/demo_1/states", shape=states.shape)
            group.create_virtual_dataset("states", layout)
        if "model_file" not in group.attrs:
            group.attrs["model_file"] = MODEL
        return f"{group_name}/states"


@given(
    kind=st.sampled_from(["external link", "external storage", "virtual dataset"]),
    where=st.sampled_from(list(TARGETS)),
    place=st.sampled_from(PLACES),
)
@GENERATED
def test_a_recording_pointing_to_another_file_is_refused_and_that_file_never_opened(
    kind: str, where: str, place: str
) -> None:
    with folder() as root:
        (root / "in").mkdir()
        target, written = TARGETS[where](root)
        target.parent.mkdir(exist_ok=True)
        valid_recording(target)  # what a follower would read, as a recording
        if kind == "external storage":  # raw bytes: a valid states table
            target.write_bytes(box_states().tobytes())
        recording = valid_recording(root / "in" / "toy.hdf5")
        named = point_elsewhere(recording, kind, place, written)
        answer, opened = run_audited(["import", recording, "-o", root / "out"], root)
        check_refused(answer, [str(recording)], codes={1})
        line = answer.stderr.strip()
        assert f": {named}: " in line and written in line, answer
        assert recording in opened, "the audit saw no open of the recording itself"
        assert target.resolve() not in opened, f"{target} opened: {answer}"
        assert not (root / "out").exists()


def test_a_model_file_beside_the_recording_that_links_elsewhere_is_refused(tmp_path: Path) -> None:
    secret = tmp_path / "secret.xml"
    secret.write_text(MODEL)
    (tmp_path / "rec" / "models").mkdir(parents=True)
    (tmp_path / "rec" / "models" / "model_1.xml").symlink_to(secret)
    recording = write_recording(tmp_path / "rec" / "toy.hdf5", box_states(), "model_1.xml")
    answer = import_refused(recording, tmp_path, "model_file", "outside the recording's models/")
    assert str(secret) in answer.stderr


@pytest.mark.parametrize(
    ("model_file", "linked"),
    [("secret.xml", False), ("../secret.xml", False), ("model_1.xml", True)],
    ids=["a file beside", "a name with ..", "a link in models/ to a file beside"],
)
def test_a_model_file_is_read_from_models_only(
    model_file: str, linked: bool, tmp_path: Path
) -> None:
    """Only models/ beside the recording holds its model: not the recording's
    other neighbours (a user's download folder), by name or through a link."""
    (tmp_path / "rec" / "models").mkdir(parents=True)
    secret = tmp_path / "rec" / "secret.xml"
    secret.write_text(MODEL)  # a valid model: reading it would succeed
    if linked:
        (tmp_path / "rec" / "models" / model_file).symlink_to(secret)
    recording = write_recording(tmp_path / "rec" / "toy.hdf5", box_states(), model_file)
    answer = import_refused(recording, tmp_path, "model_file")
    assert str(tmp_path / "rec" / "models") in answer.stderr, answer


# --------------------------------------------------------------------------- names

NAME_PARTS = st.sampled_from(
    ["a", "Z", "_", "-", ".", "..", "../", "/", "/etc/", "\\", " ", "\x1b[2J", "\n", "\x07"]
    + ["\u202e", "$", "é"]
)
NAMES = st.lists(NAME_PARTS, min_size=1, max_size=10).map("".join)
KEYS = NAMES.map(lambda n: n.replace("/", "|")).filter(lambda k: k not in {".", ""})


def named_recording(path: Path, env: str, keys: list[str], robomimic: bool) -> None:
    with h5py.File(path, "w") as handle:
        data = handle.create_group("data")
        if robomimic:
            data.attrs["env_args"] = json.dumps({"env_name": env})
        else:
            data.attrs["env"] = env
        for key in keys:
            group = data.create_group(key)
            group.create_dataset("states", data=box_states())
            group.attrs["model_file"] = MODEL


@given(
    env=NAMES,
    keys=st.lists(KEYS, min_size=1, max_size=3, unique=True),
    robomimic=st.booleans(),
)
@GENERATED
def test_names_in_a_recording_become_safe_file_names_inside_the_output_folder(
    env: str, keys: list[str], robomimic: bool
) -> None:
    with folder() as root:
        (root / "in").mkdir()
        recording = root / "in" / "demo.hdf5"  # a generic stem: the names come from env
        named_recording(recording, env, keys, robomimic)
        before = fingerprint(root)
        answer = run(["import", recording, "-o", root / "out" / "demos"], root)
        assert answer.code == 0, answer
        after = fingerprint(root)
        created = {Path(name) for name in set(after) - set(before)}
        out = Path("out") / "demos"
        assert created - {Path("out"), out} == {out / f.name for f in (root / out).iterdir()}
        files = sorted(f.name for f in (root / out).iterdir())
        assert len(files) == len(keys), (files, answer)  # one per demonstration: none lost
        for name in files:
            assert re.fullmatch(r"[^\W.-][\w.+-]*\.json", name) and ".." not in name, name
            assert len(name.encode()) <= 125, name
        written = {json.loads((root / out / f).read_text())["name"] for f in files}
        assert written == {f"{env}-{key}" for key in keys}  # the names themselves kept
        shown = answer.stdout + answer.stderr
        controls = {c for c in shown if not c.isprintable() and c != "\n"}
        assert not controls, f"{controls} reached the terminal: {answer}"


def test_names_reduced_to_one_file_name_are_all_written(tmp_path: Path) -> None:
    recording = tmp_path / "demo.hdf5"
    named_recording(recording, "Toy", ["a/b".replace("/", "\x1b"), "a\nb", "a b"], False)
    answer = run(["import", recording, "-o", tmp_path / "out"], tmp_path)
    assert answer.code == 0, answer
    assert sorted(f.name for f in (tmp_path / "out").iterdir()) == [
        "Toy-a_b-2.json",
        "Toy-a_b-3.json",
        "Toy-a_b.json",
    ]


# --------------------------------------------------------------------------- model XML

ORIENTATIONS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")
WIDTH = {"pos": 3, "quat": 4, "axisangle": 4, "euler": 3, "xyaxes": 6, "zaxis": 3}
ELEMENTS = {  # the model's parts that become what import writes
    "object body": ".//body[@name='box0']",
    "object geom": ".//body[@name='box0']/geom",
    "landmark body": ".//body[@name='post']",
    "landmark geom": ".//body[@name='post']/geom",
    "table geom": ".//body[@name='table']/geom",
}


def model_with(element: str, attribute: str, value: str) -> str:
    root = ET.fromstring(MODEL)
    node = root.find(ELEMENTS[element])
    assert node is not None
    if attribute in ORIENTATIONS:
        for other in ORIENTATIONS:
            node.attrib.pop(other, None)
    node.set(attribute, value)
    return ET.tostring(root, encoding="unicode")


@st.composite
def bad_numbers(draw: st.DrawFn) -> tuple[str, str, str]:
    """(element, attribute, value): a non-finite or huge component, or an
    orientation with a zero or degenerate axis."""
    element = draw(st.sampled_from(list(ELEMENTS)))
    choices = ["pos", *ORIENTATIONS, *(["size"] if "geom" in element else [])]
    attribute = draw(st.sampled_from(choices))
    width = 3 if attribute == "size" and "object" in element else WIDTH.get(attribute, 2)
    if attribute == "size" and "landmark" in element:
        width = 2
    values = ["0.05"] * width if attribute == "size" else ["0.5"] * width
    if attribute in {"quat", "xyaxes", "zaxis"} and draw(st.booleans()):
        zero = {"quat": "0 0 0 0", "zaxis": "0 0 0", "xyaxes": draw(
            st.sampled_from(["0 0 0 0 1 0", "1 0 0 0 0 0", "1 0 0 2 0 0"]))}  # fmt: skip
        return element, attribute, zero[attribute]
    index = draw(st.integers(0, width - 1))
    values[index] = draw(st.sampled_from(["nan", "NaN", "inf", "-inf", "1e200", "-1e200"]))
    return element, attribute, " ".join(values)


@given(case=bad_numbers())
@GENERATED
def test_non_finite_huge_and_degenerate_model_numbers_are_refused(
    case: tuple[str, str, str],
) -> None:
    attribute = case[1]
    with folder() as root:
        recording = write_recording(root / "toy.hdf5", box_states(), model_with(*case))
        answer = import_refused(recording, root)
        assert attribute in answer.stderr or "xyaxes" in answer.stderr, answer


@given(depth=st.integers(101, 3000), kind=st.sampled_from(["body", "default"]))
@settings(max_examples=6, deadline=None, derandomize=True)
def test_deeply_nested_models_are_refused_without_recursion(depth: int, kind: str) -> None:
    if kind == "body":
        nested = "<body>" * depth + "</body>" * depth
        model = MODEL.replace("</worldbody>", nested + "</worldbody>")
    else:
        nested = "".join(f'<default class="c{i}">' for i in range(depth)) + "</default>" * depth
        model = MODEL.replace("<default>", "<default>" + nested, 1)
    with folder() as root:
        recording = write_recording(root / "toy.hdf5", box_states(), model)
        answer = import_refused(recording, root, "nested")
        assert "RecursionError" not in answer.stderr


def model_replaced(old: str, new: str) -> Callable[[Path], Path]:
    assert old in MODEL
    return lambda path: write_recording(path, box_states(), MODEL.replace(old, new))


def states_with(column: int, value: float, dtype: type = np.float64) -> Callable[[Path], Path]:
    def make(path: Path) -> Path:
        states = box_states()
        states[:, column] = value
        return write_recording(path, states.astype(dtype))

    return make


ACTUATOR = '<actuator><general joint="shoulder" dyntype="filter" actdim="inf"/></actuator>'
OUT_OF_RANGE: dict[str, tuple[Callable[[Path], Path], tuple[str, ...]]] = {
    "an object 40 m wide": (
        model_replaced('size="0.05 0.05 0.05"', 'size="20 20 20"'),
        ("objects.box", "0.1 mm – 10 m"),
    ),
    "an object 1 µm wide": (
        model_replaced('size="0.05 0.05 0.05"', 'size="5e-7 5e-7 5e-7"'),
        ("objects.box", "0.1 mm – 10 m"),
    ),
    "a landmark 5 km away": (
        model_replaced('pos="0.3 -0.3 0.9"', 'pos="5000 -0.3 0.9"'),
        ("landmarks.post", "1 km"),
    ),
    "positions 5 km from the origin": (states_with(5, 5000.0), ("'box'", "1 km")),
    "quaternion components of 1e200": (states_with(8, 1e200), ("states", "unit quaternion")),
    "a zero quaternion": (states_with(8, 0.0), ("states", "unit quaternion")),
    "NaN states": (states_with(6, np.nan), ("states", "NaN")),
    "complex states": (states_with(0, 0.01, np.complex128), ("states", "complex128")),
    "integer states": (states_with(0, 1.0, np.int64), ("states", "int64")),
    "actdim inf": (model_replaced("</mujoco>", ACTUATOR + "</mujoco>"), ("actdim",)),
    "a negative size": (model_replaced('size="0.02 0.1"', 'size="-0.02 0.1"'), ("size",)),
}


@pytest.mark.parametrize("case", list(OUT_OF_RANGE), ids=[f"import {c}" for c in OUT_OF_RANGE])
def test_numbers_beyond_the_documented_limits_are_refused(case: str, tmp_path: Path) -> None:
    make, names = OUT_OF_RANGE[case]
    recording = make(tmp_path / "toy.hdf5")
    import_refused(recording, tmp_path, *names)


# --------------------------------------------------------------------------- what datasets declare


@given(rows=st.integers(10**6, 10**10), chunked=st.booleans())
@settings(max_examples=6, deadline=None, derandomize=True)
def test_a_dataset_declaring_more_than_the_file_holds_is_refused_before_reading(
    rows: int, chunked: bool
) -> None:
    with folder() as root:
        recording = write_recording(root / "toy.hdf5", None)
        with h5py.File(recording, "a") as handle:
            handle["data/demo_1"].create_dataset(
                "states", shape=(rows, 21), dtype="f8", chunks=(1000, 21) if chunked else None
            )
        import_refused(recording, root, "states", "declares")


def test_a_dataset_cut_short_is_refused(tmp_path: Path) -> None:
    recording = write_recording(tmp_path / "toy.hdf5", None)
    states = box_states()
    with h5py.File(recording, "a") as handle:
        dataset = handle["data/demo_1"].create_dataset(
            "states", shape=states.shape, dtype="f8", chunks=(10, 21)
        )
        dataset[:100] = states[:100]  # 300 of the 400 rows never written
    import_refused(recording, tmp_path, "states", "never written, or cut short")


@pytest.mark.parametrize(
    "attribute", ["model_file", "env"], ids=["import model_file", "import env"]
)
def test_text_that_is_not_utf8_is_refused(attribute: str, tmp_path: Path) -> None:
    recording = write_recording(tmp_path / "toy.hdf5", box_states())
    with h5py.File(recording, "a") as handle:
        group = handle["data/demo_1"] if attribute == "model_file" else handle["data"]
        group.attrs[attribute] = np.bytes_(b"<mujoco>\xff\xfe</mujoco>")
    import_refused(recording, tmp_path, attribute, "not UTF-8")


# --------------------------------------------------------------------------- text is text


def _two_carried(names: list[str]) -> str:
    """A CSV stream of two objects named ``names``, carried in opposite directions."""
    lines = ["t,object,x,y,z"]
    for i in range(400):
        t = i * 0.01
        x = 0.3 * min(max(t - 1.0, 0.0), 1.0)
        z = 0.1 * np.sin(np.pi * min(max(t - 1.0, 0.0), 1.0))
        lines.append(f'{t:.2f},"{names[0]}",{x:.4f},0.2,{z:.4f}')
        lines.append(f'{t:.2f},"{names[1]}",{0.6 - x:.4f},0.5,{z:.4f}')
    return "\n".join(lines) + "\n"


def test_names_with_tex_are_drawn_and_printed_literally(tmp_path: Path) -> None:
    """A segmentation figure of objects named ``$\\sqrt{$`` and ``$x$``:
    drawn (not parsed as TeX), and the table on stdout shows them as written."""
    stream = tmp_path / "stream.csv"
    stream.write_text(_two_carried(["$\\sqrt{$", "$x$"]))
    answer = run(["segment", stream, "-o", "demo.json", "--plot", "speeds.png"], tmp_path)
    assert answer.code == 0, answer
    assert (tmp_path / "speeds.png").stat().st_size > 0
    assert "$\\sqrt{$" in answer.stdout and "$x$" in answer.stdout, answer


@pytest.mark.parametrize(
    "name", ["$x$ \x1b[31mred", "cup\x1b[2J\x07\u202efake", "green apple", "loc3", "cup\tb"]
)
def test_a_stream_object_a_plan_cannot_name_is_refused_in_one_escaped_line(
    name: str, tmp_path: Path
) -> None:
    """A CSV object named with an escape sequence, a space or a location's name
    (docs/formats.md "Object names"): ``segment`` and ``learn`` of the stream
    refuse it in one line naming the file and the object, escaped; nothing is
    written. Before, ``segment`` wrote a demonstration ``learn`` then took (or,
    now, would refuse) and printed the name escaped."""
    stream = tmp_path / "stream.csv"
    stream.write_text(_two_carried(["plate", name]))
    for command in (["segment", stream, "-o", "demo.json"], ["learn", stream, "-o", "m.json"]):
        answer = run(command, tmp_path)
        check_refused(answer, [str(stream)], codes={1})
        assert f"object {printable(repr(name))}" in answer.stderr, answer
        assert not {c for c in answer.stderr + answer.stdout if not c.isprintable() and c != "\n"}
    assert sorted(f.name for f in tmp_path.iterdir()) == ["stream.csv"]


def test_figure_texts_are_literal_but_tick_labels_keep_their_notation() -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from demoplan.plotting.labels import add_label, literal_texts

    figure = Figure()
    ax = figure.subplots()
    ax.set_yscale("log")
    ax.plot([1, 2], [1, 1000], label="$x$")
    ax.set_title("$\\sqrt{$")
    label = add_label(ax, "$y$", (1.5, 10))
    ax.legend()
    literal_texts(figure)
    figure.canvas.draw()  # a parse of "$\sqrt{$" would raise here
    assert not ax.title.get_parse_math() and not label.get_parse_math()
    assert not ax.get_legend().get_texts()[0].get_parse_math()
    ticks = [t for t in ax.yaxis.get_ticklabels() if t.get_text()]
    assert ticks and all(t.get_parse_math() for t in ticks)


# --------------------------------------------------------------------------- TF trees


def carried_track(name: str, offset: float = 0.0) -> ObjectTrack:
    """4 s at 100 Hz: rests, carried 0.3 m along x during 1-2 s, rests."""
    t = np.arange(400) * 0.01
    s = np.clip(t - 1.0, 0.0, 1.0)
    positions = np.column_stack((offset + 0.3 * s, np.full_like(t, 0.2), 0.1 * np.sin(np.pi * s)))
    return ObjectTrack(name, t, positions)


def still_track(name: str, x: float) -> ObjectTrack:
    t = np.arange(400) * 0.01
    return ObjectTrack(name, t, np.column_stack((np.full_like(t, x), np.zeros_like(t), t * 0)))


CONTROLS = st.sampled_from(["\x1b[2J", "\x1b]0;title\x07", "\x07", "\u202e", "\n", "\r"])
FRAME_NAMES = st.tuples(CONTROLS, NAMES).map(lambda p: "cup" + p[0] + p[1] + "x")


@given(name=FRAME_NAMES.filter(lambda n: "/" not in n))
@settings(max_examples=6, deadline=None, derandomize=True)
def test_tf_frame_names_with_escapes_are_refused_in_one_escaped_line(name: str) -> None:
    """A TF frame followed as an object, named with control characters: refused
    where the bag is read, one line, no control character reaching the
    terminal, nothing written (docs/formats.md "Object names")."""
    with folder() as root:
        write_bag(PoseStream((carried_track(name),)), root / "bag", kind="tf")
        answer = run(["segment", root / "bag", "-o", root / "demo.json"], root)
        check_refused(answer, [str(root / "bag")], codes={1})
        assert "object name" in answer.stderr, answer
        controls = {c for c in answer.stdout + answer.stderr if not c.isprintable() and c != "\n"}
        assert not controls, f"{controls} reached the terminal: {answer}"
        assert not (root / "demo.json").exists()


@pytest.mark.parametrize("kilometres", [5.0, 50.0])
def test_a_tf_tree_placing_an_object_kilometres_away_is_refused(
    kilometres: float, tmp_path: Path
) -> None:
    """A cup 0.3 m from its parent frame ``base``, which is ``kilometres`` from
    the world: composed, the cup is that far from the origin."""
    stream = PoseStream((still_track("base", kilometres * 1000.0), carried_track("cup")))
    write_bag(stream, tmp_path / "bag", kind="tf", parents={"base": "world", "cup": "base"})
    answer = run(["segment", tmp_path / "bag", "-o", tmp_path / "demo.json"], tmp_path)
    check_refused(answer, [str(tmp_path / "bag")], codes={1})
    assert "1 km" in answer.stderr and "'cup'" in answer.stderr, answer
    assert not (tmp_path / "demo.json").exists()


def test_a_warning_naming_an_object_names_it_on_one_line(tmp_path: Path) -> None:
    """An object still moving when the stream ends is warned about by name,
    one line a warning."""
    name = "cup$x$"
    track = carried_track(name)
    moving = ObjectTrack(name, track.times[:150], track.positions[:150])  # cut mid-carry
    stream = PoseStream((carried_track("plate", 1.0), moving))
    path = tmp_path / "stream.csv"
    write_csv(stream, path)
    answer = run(["segment", path, "-o", tmp_path / "demo.json"], tmp_path)
    assert answer.code == 0, answer
    warnings = [line for line in answer.stderr.splitlines() if "WARNING" in line]
    assert warnings and all(name in line for line in warnings), answer


@pytest.mark.parametrize("planted", ["../victim.txt", "/nonexistent-demoplan/x.json", "loop"])
def test_a_link_planted_in_the_output_folder_is_not_written_through(
    planted: str, tmp_path: Path
) -> None:
    """``out/toy-demo_1.json`` is a link leading out of ``out``: refused, the
    file it names untouched (a link to nowhere or a loop of links alike)."""
    recording = write_recording(tmp_path / "toy.hdf5", box_states())
    victim = tmp_path / "victim.txt"
    victim.write_text("victim")
    (tmp_path / "out").mkdir()
    link = tmp_path / "out" / "toy-demo_1.json"
    link.symlink_to(link if planted == "loop" else Path(planted))
    before = fingerprint(tmp_path)
    answer = run(["import", recording, "-o", tmp_path / "out"], tmp_path)
    check_refused(answer, [str(link)], codes={1})
    assert "outside the folder" in answer.stderr, answer
    assert fingerprint(tmp_path) == before and victim.read_text() == "victim"


# --------------------------------------------------------------------------- another kind


def _other_kind(kind: str, root: Path) -> Path:
    """A file (or bag folder) of ``kind`` that demoplan reads with another command."""
    stream = PoseStream((carried_track("cup"),))
    if kind in {"bag-folder", "metadata", "db3", "mcap"}:
        write_bag(stream, root / "bag", kind="tf", storage="mcap" if kind == "mcap" else "sqlite3")
        return {
            "bag-folder": root / "bag",
            "metadata": root / "bag" / "metadata.yaml",
            "db3": root / "bag" / "bag.db3",
            "mcap": root / "bag" / "bag.mcap",
        }[kind]
    if kind == "csv":
        write_csv(stream, root / "stream.csv")
        return root / "stream.csv"
    if kind == "json":
        (root / "demo.json").write_text((EXAMPLES / "blocks" / "demonstrations.json").read_text())
        return root / "demo.json"
    (root / "table.png").write_bytes((EXAMPLES / "perception" / "blocks-top.png").read_bytes())
    return root / "table.png"


OTHER_KINDS = {
    # kind: what the one line must point to
    "bag-folder": "demoplan segment",
    "metadata": "demoplan segment",
    "db3": "demoplan segment",
    "mcap": "demoplan segment",
    "csv": "demoplan segment",
    "json": "demoplan learn",
    "png": "demoplan perceive",
}


@pytest.mark.parametrize("kind", OTHER_KINDS)
def test_import_of_a_file_another_command_reads_names_that_command(
    kind: str, tmp_path: Path
) -> None:
    """``import`` given a bag (its folder, metadata.yaml or storage), a CSV pose
    stream, a demonstration or a photograph: one line saying what it is and
    which command reads it; nothing written. Before, h5py's "Unable to
    synchronously open file (file signature not found)" or "is a folder"."""
    path = _other_kind(kind, tmp_path)
    answer = run(["import", path, "-o", tmp_path / "out"], tmp_path)
    check_refused(answer, [str(path)], codes={1})
    assert OTHER_KINDS[kind] in answer.stderr, answer
    assert "signature" not in answer.stderr, answer
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("content", "said"),
    [(b"", "an empty file"), (b"hello\n", "no HDF5 signature"), (bytes(range(256)), "signature")],
)
def test_import_of_a_file_that_is_no_hdf5_says_so_in_its_own_words(
    content: bytes, said: str, tmp_path: Path
) -> None:
    """An empty file or one without HDF5's signature: one line in demoplan's
    words, not h5py's "Unable to synchronously open file (file signature not
    found)"."""
    path = tmp_path / "demo.hdf5"
    path.write_bytes(content)
    answer = run(["import", path, "-o", tmp_path / "out"], tmp_path)
    check_refused(answer, [str(path)], codes={1})
    assert said in answer.stderr and "synchronously" not in answer.stderr, answer
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bag_with_a_name_that_is_not_utf8_is_one_plain_line(storage: str, tmp_path: Path) -> None:
    """A damaged bag whose message type reads ``tf2\\xffmsgs/…``: one line in
    demoplan's words, not Python's "'utf-8' codec can't decode byte 0xff in
    position 3: invalid start byte"; nothing written."""
    write_bag(PoseStream((carried_track("cup"),)), tmp_path / "bag", kind="tf", storage=storage)
    for part in (tmp_path / "bag").iterdir():
        if part.suffix in {".mcap", ".db3"}:
            part.write_bytes(part.read_bytes().replace(b"tf2_msgs", b"tf2\xffmsgs"))
    answer = run(["segment", tmp_path / "bag", "-o", tmp_path / "demo.json"], tmp_path)
    check_refused(answer, [str(tmp_path / "bag")], codes={1})
    assert "codec" not in answer.stderr, answer
    assert not (tmp_path / "demo.json").exists()
