"""`demoplan import`: robosuite / robomimic HDF5 recordings → demonstration files.

The real data are robosuite's human demonstrations from its 0.3.0 and 1.0.0
source distributions (:mod:`tests.support.robosuite_data`); the bad inputs are made
here with h5py.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.errors import InputError
from demoplan.segmentation import import_recording
from demoplan.segmentation.readers.hdf5 import model_layout, read_recording
from tests.support.cli import invoke
from tests.support.robosuite_data import RobosuiteDataError, robosuite_demonstrations, skip_or_fail

OBJECTS = {
    "SawyerPickPlace": ["Milk", "Bread", "Cereal", "Can"],
    "PickPlace": ["Milk", "Bread", "Cereal", "Can"],
    "SawyerNutAssembly": ["SquareNut", "RoundNut"],
    "NutAssembly": ["SquareNut", "RoundNut"],
    "SawyerStack": ["cubeA", "cubeB"],
    "Stack": ["cubeA", "cubeB"],
}
LANDMARKS = {
    "SawyerPickPlace": ["bin1", "bin2"],
    "PickPlace": ["bin1", "bin2"],
    "SawyerNutAssembly": ["peg1", "peg2"],
    "NutAssembly": ["peg1", "peg2"],
    "SawyerStack": [],
    "Stack": [],
}
DEMOS = {"SawyerPickPlace": 2, "SawyerNutAssembly": 2, "SawyerStack": 2}


@pytest.fixture(scope="session")
def recordings() -> dict[str, Path]:
    try:
        return robosuite_demonstrations()
    except RobosuiteDataError as exc:
        skip_or_fail(exc)


def model_xml(path: Path, key: str = "demo_1") -> str:
    with h5py.File(path) as handle:
        name = handle["data"][key].attrs["model_file"]
    return (path.parent / "models" / name).read_text()


# --------------------------------------------------------------------------- real data


@pytest.mark.parametrize("name", list(OBJECTS))
def test_reads_objects_landmarks_and_provenance(recordings: dict[str, Path], name: str) -> None:
    demos = read_recording(recordings[name])
    assert len(demos) == DEMOS.get(name, 1)
    for demo in demos:
        assert list(demo.stream.objects) == OBJECTS[name]
        assert [n for n, _ in demo.landmarks] == LANDMARKS[name]
        provenance = dict(demo.provenance)
        assert provenance["source"] == str(recordings[name])
        assert provenance["demonstration"] == demo.key
        assert provenance["samples"] == demo.samples > 100
        assert provenance["env"] in {name, name.removeprefix("Sawyer")}
        # Objects rest on the table (or bin floor) before they are touched: z = 0.
        for track in demo.stream:
            assert abs(track.positions[-1, 2]) < 0.2
            settled = track.positions[len(track) // 50 : len(track) // 50 + 5, 2]
            if name not in {"SawyerNutAssembly", "NutAssembly"}:  # the nuts fall first
                assert np.all(np.abs(settled) < 0.006), (track.name, settled)


@pytest.mark.parametrize("name", ["SawyerStack", "Stack"])
def test_cubes_rest_at_z_zero_and_stack(recordings: dict[str, Path], name: str) -> None:
    path = recordings[name]
    layout = model_layout(model_xml(path), "model")
    xml_z = {layout.bodies[i].name: float(layout.bodies[i].pos[2]) for i in layout.free_bodies}
    table_top = 0.8
    demo = read_recording(path)[0]
    assert dict(demo.provenance)["table_top_z"] == pytest.approx(table_top)
    geometry = dict(demo.geometry)
    assert geometry["cubeA"].size == pytest.approx((0.04, 0.04, 0.04))
    assert geometry["cubeB"].size == pytest.approx((0.05, 0.05, 0.05))
    cube_a, cube_b = demo.stream.track("cubeA"), demo.stream.track("cubeB")
    # The first sample is the model's placement height, shifted to the resting point.
    for track, half in ((cube_a, 0.02), (cube_b, 0.025)):
        assert track.positions[0, 2] == pytest.approx(
            xml_z[track.name] - table_top - half, abs=3e-3
        )
    assert abs(cube_b.positions[0, 2]) < 0.003
    # At the end cubeA sits on cubeB (5 cm), centred within a few cm.
    assert cube_a.positions[-1, 2] == pytest.approx(0.05, abs=0.005)
    assert np.linalg.norm(cube_a.positions[-1, :2] - cube_b.positions[-1, :2]) < 0.03


def test_mesh_objects_rest_on_the_bin_floor(recordings: dict[str, Path]) -> None:
    demo = read_recording(recordings["PickPlace"])[0]
    landmarks = dict(demo.landmarks)
    assert landmarks["bin1"].position == pytest.approx((0.1, -0.25, -0.04))
    assert "Milk" not in dict(demo.geometry)  # mesh: only its height is known
    assert dict(demo.geometry)["bin1"].size == pytest.approx((0.42, 0.52, 0.12))
    for track in demo.stream:
        assert abs(track.positions[0, 2]) < 0.003
        assert track.orientations is not None
        assert np.allclose(np.linalg.norm(track.orientations, axis=1), 1.0)


def test_import_recording_names_and_provenance(recordings: dict[str, Path]) -> None:
    demos = import_recording(recordings["SawyerNutAssembly"])
    assert [d.name for d in demos] == ["SawyerNutAssembly-demo_1", "SawyerNutAssembly-demo_2"]
    for demo in demos:
        assert dict(demo.provenance)["demonstration"] == demo.name.split("-")[-1]
        assert [n for n, _ in demo.landmarks] == ["peg1", "peg2"]
        assert set(demo.geometry()) == {"SquareNut", "RoundNut", "peg1", "peg2"}
        assert demo.geometry()["peg2"].shape == "cylinder"


def test_cli_writes_one_file_per_demonstration(recordings: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "demos"
    result = invoke("import", recordings["SawyerNutAssembly"], "-o", out, "--json")
    assert result.exit_code == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["source"] == str(recordings["SawyerNutAssembly"])
    files = sorted(out.iterdir())
    assert [f.name for f in files] == [
        "SawyerNutAssembly-demo_1.json",
        "SawyerNutAssembly-demo_2.json",
    ]
    assert [d["file"] for d in summary["demonstrations"]] == [str(f) for f in files]
    assert [d["samples"] for d in summary["demonstrations"]] == [3318, 2430]
    for file in files:
        document = json.loads(file.read_text())
        assert document["provenance"]["source"] == str(recordings["SawyerNutAssembly"])
        assert document["provenance"]["samples"] in {3318, 2430}
    demos = load_demonstrations([out])  # the files read back, provenance kept
    assert dict(demos[0].provenance)["demonstration"] == "demo_1"
    # Without --json: a table per demonstration; a name prefix.
    result = invoke("import", recordings["Stack"], "-o", out, "--name-prefix", "stack")
    assert result.exit_code == 0, result.stderr
    assert "demo_1" in result.stdout and (out / "stack-demo_1.json").is_file()


# --------------------------------------------------------------------------- synthetic


MODEL = """<mujoco>
  <compiler angle="radian"/>
  <default><default class="ball"><joint type="ball"/></default></default>
  <worldbody>
    <body name="table" pos="0 0 0.4"><geom type="box" size="0.5 0.5 0.4"/></body>
    <body name="arm" childclass="ball" pos="0 0 1.5"><joint name="shoulder"/>
      <geom type="sphere" size="0.05" contype="0" conaffinity="0"/></body>
    <body name="box0" pos="0.1 0.2 0.85"><freejoint/><geom type="box" size="0.05 0.05 0.05"/></body>
    <body name="post" pos="0.3 -0.3 0.9" axisangle="0 0 1 0.5">
      <geom type="cylinder" size="0.02 0.1"/></body>
  </worldbody>
</mujoco>"""


def box_states(width: int = 1 + 11 + 9, moved: bool = True) -> np.ndarray:
    """4 s at 100 Hz: the box rests, is carried 0.3 m in x during 1–2 s, rests."""
    t = np.arange(1, 401) * 0.01
    states = np.zeros((t.size, width))
    states[:, 0] = t
    states[:, 1] = 1.0  # the ball joint's quaternion (w first)
    x = 0.1 + 0.3 * np.clip(t - 1.0, 0.0, 1.0) * moved
    lift = 0.1 * np.sin(np.pi * np.clip(t - 1.0, 0.0, 1.0))
    states[:, 5], states[:, 6], states[:, 7] = x, 0.2, 0.85 + lift
    states[:, 8] = 1.0  # the box's quaternion w
    return states


def write_recording(path: Path, states: np.ndarray | None, model: str | None = MODEL) -> Path:
    with h5py.File(path, "w") as handle:
        data = handle.create_group("data")
        data.attrs["env"] = "Toy"
        demo = data.create_group("demo_1")
        if states is not None:
            demo.create_dataset("states", data=states)
        if model is not None:
            demo.attrs["model_file"] = model
    return path


def test_layout_follows_mujoco_order() -> None:
    layout = model_layout(MODEL, "toy")
    assert (layout.nq, layout.nv, layout.na) == (11, 9, 0)
    assert [layout.bodies[i].name for i in layout.free_bodies] == ["box0"]
    assert layout.qpos_address == (4,)


def test_synthetic_recording(tmp_path: Path) -> None:
    path = write_recording(tmp_path / "toy.hdf5", box_states())
    (demo,) = read_recording(path)
    track = demo.stream.track("box")
    assert track.positions[0] == pytest.approx((0.1, 0.2, 0.0))
    assert dict(demo.landmarks)["post"].position == pytest.approx((0.3, -0.3, 0.0))
    assert dict(demo.geometry)["post"].shape == "cylinder"
    (imported,) = import_recording(path)
    assert imported.name == "toy-demo_1"
    assert [s.object for s in imported.steps] == ["box"]
    assert imported.steps[0].pose.position == pytest.approx((0.4, 0.2, 0.0), abs=1e-3)


def h5_without_data(path: Path) -> Path:
    with h5py.File(path, "w") as handle:
        handle.create_group("other")
    return path


BAD = {
    "truncated": None,  # made from a real file in the test
    "text": None,
    "no data": lambda p: h5_without_data(p),
    "no states": lambda p: write_recording(p, None),
    "no model": lambda p: write_recording(p, box_states(), None),
    "malformed model": lambda p: write_recording(p, box_states(), "<mujoco><worldbody>"),
    "missing model file": lambda p: write_recording(p, box_states(), "model_9.xml"),
    "no free body": lambda p: write_recording(p, box_states(), MODEL.replace("<freejoint/>", "")),
    "width": lambda p: write_recording(p, box_states(width=30)),
}
MESSAGES = {
    "truncated": "HDF5",
    "text": "HDF5",
    "no data": "'data'",
    "no states": "'states'",
    "no model": "model_file",
    "malformed model": "malformed model XML",
    "missing model file": "model_9.xml",
    "no free body": "no free-jointed body",
    "width": "30 columns",
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_input_exits_1_and_writes_nothing(
    case: str, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    path = tmp_path / "bad.hdf5"
    if case == "truncated":
        data = request.getfixturevalue("recordings")["SawyerStack"].read_bytes()
        path.write_bytes(data[: len(data) * 2 // 3])
    elif case == "text":
        path.write_text("time,x\n0,1\n")
    else:
        BAD[case](path)  # type: ignore[misc]
    out = tmp_path / "out"
    result = invoke("import", path, "-o", out)
    assert result.exit_code == 1, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("demoplan: error: ")
    assert str(path) in lines[0] and MESSAGES[case] in lines[0], lines[0]
    assert not out.exists()
    with pytest.raises(InputError):
        import_recording(path)
