"""Units and physical sanity of demonstrations and scenes (docs/formats.md
"Conventions" and "Demonstration", docs/limits.md "Numbers that no tabletop
holds" and "Warnings about a file's contents").

Families of tabletop tasks drawn in metres and written in m, cm or mm: with the
right ``units`` every one is read; with the unit left out (read as metres) a
millimetre file is always refused and a centimetre one whenever the documented
rule sees it, in one line naming ``units``. Angles written in radians where
degrees are read are warned about; ordinary degree files are not. Towers built
bottom-up are accepted without a word; a block released before the block under
it is there is warned about, naming the demonstration, the step and the step
where its support arrives.
"""

from __future__ import annotations

import json
import logging
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.documents.demonstrations import (
    demonstrations_from_document,
    demonstrations_from_path,
)
from demoplan.documents.releases import unsupported_releases
from demoplan.documents.units import MAX_CARRIED_M, MAX_SPREAD_M
from demoplan.errors import InputError
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.rotations import quat_from_yaw, rpy_from_quat
from demoplan.scenes.scene import scene_from_document
from tests.support.helpers import EXAMPLES

SCALE = {"m": 1.0, "cm": 0.01, "mm": 0.001}
FAMILY = settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
WARNINGS = "demoplan"


# --------------------------------------------------------------------------- families


@st.composite
def tabletops(draw: st.DrawFn) -> dict[str, Any]:
    """A tabletop task in metres: 1–4 objects of 5 mm – 30 cm, standing on a
    1.6 m table, each moved once (one of them at least 2 cm); sizes given or not."""
    n = draw(st.integers(1, 4))
    coordinate = st.floats(-0.8, 0.8, allow_nan=False).map(lambda v: round(v, 4))
    extent = st.floats(0.005, 0.3, allow_nan=False).map(lambda v: round(v, 4))
    names = [f"o{i}" for i in range(n)]
    initial = {name: [draw(coordinate), draw(coordinate), 0.0] for name in names}
    steps = [
        {"object": name, "position": [draw(coordinate), draw(coordinate), 0.0]} for name in names
    ]
    assume(max(math.dist(initial[s["object"]][:2], s["position"][:2]) for s in steps) >= 0.02)
    document: dict[str, Any] = {
        "format": "demoplan/demonstration-1",
        "initial": {name: {"position": xyz} for name, xyz in initial.items()},
        "steps": steps,
    }
    if draw(st.booleans()):
        document["objects"] = {
            name: {
                "shape": draw(st.sampled_from(["box", "cylinder"])),
                "size": [draw(extent) for _ in range(3)],
            }
            for name in names
        }
    return document


def written_in(document: dict[str, Any], unit: str, declare: bool = True) -> dict[str, Any]:
    """``document`` (metres) with every length in ``unit``; ``declare``: with ``units``."""
    factor = 1 / SCALE[unit]

    def convert(value: Any, key: str = "") -> Any:
        if isinstance(value, dict):
            return {k: convert(v, k) for k, v in value.items()}
        if isinstance(value, list) and key in ("position", "size"):
            return [round(v * factor, 6) for v in value]
        if isinstance(value, list):
            return [convert(v) for v in value]
        return value

    out = convert(document)
    if declare:
        out["units"] = {"length": unit}
    return out


def spread(document: dict[str, Any]) -> float:
    """How far the positions of a (metres) document spread along an axis."""
    points = [p["position"] for p in document["initial"].values()] + [
        s["position"] for s in document["steps"]
    ]
    return max(max(p[a] for p in points) - min(p[a] for p in points) for a in range(3))


def largest(document: dict[str, Any]) -> float:
    return max((max(o["size"]) for o in document.get("objects", {}).values()), default=0.0)


def refusal(document: dict[str, Any]) -> InputError | None:
    try:
        demonstrations_from_document(document, "demo.json")
    except InputError as exc:
        return exc
    return None


# --------------------------------------------------------------------------- lengths


@FAMILY
@given(task=tabletops(), unit=st.sampled_from(["m", "cm", "mm"]))
def test_a_tabletop_in_its_declared_unit_is_read(task: dict[str, Any], unit: str) -> None:
    (demo,) = demonstrations_from_document(written_in(task, unit), "demo.json")
    assert demo.steps[0].pose.position == pytest.approx(tuple(task["steps"][0]["position"]))


@FAMILY
@given(task=tabletops())
def test_millimetres_read_as_metres_are_refused_naming_units(task: dict[str, Any]) -> None:
    exc = refusal(written_in(task, "mm", declare=False))
    assert exc is not None and exc.field == "units"
    assert str(exc).startswith("demo.json: units: lengths read in metres (the default")
    assert '"units": {"length": "mm"}' in str(exc) or '"length": "cm"' in str(exc)


@FAMILY
@given(task=tabletops())
def test_centimetres_read_as_metres_are_refused_where_the_rule_sees_them(
    task: dict[str, Any],
) -> None:
    """Read as metres, a centimetre file is 100 times too large: refused when its
    positions then spread more than 10 m or an object it moves is over 2 m (the
    rule of docs/limits.md); a file that moves only objects under 2 cm within
    10 cm is not seen — the documented blind spot."""
    assume(abs(spread(task) * 100 - MAX_SPREAD_M) > 1e-6)  # not on the bound itself
    assume(abs(largest(task) * 100 - MAX_CARRIED_M) > 1e-6)
    exc = refusal(written_in(task, "cm", declare=False))
    seen = spread(task) * 100 > MAX_SPREAD_M or largest(task) * 100 > MAX_CARRIED_M
    assert (exc is not None) == seen
    if exc is not None:
        assert exc.field == "units" and "\n" not in str(exc)


@FAMILY
@given(task=tabletops())
def test_sizes_in_metres_among_millimetre_positions_are_refused(task: dict[str, Any]) -> None:
    """Sizes written in metres in a millimetre file: refused when the positions
    then spread more than 1000 times the largest object (here: whenever the task
    spreads wider than its largest object)."""
    assume("objects" in task and spread(task) > largest(task) * 1.001)
    mixed = written_in(task, "mm")
    mixed["objects"] = task["objects"]  # left in metres
    exc = refusal(mixed)
    assert exc is not None and exc.field == "units"
    assert "sizes and positions in different units" in str(exc)


@st.composite
def warehouses(draw: st.DrawFn) -> tuple[list[dict[str, Any]], float]:
    """Two demonstrations of a warehouse task in metres: a pallet put down near
    the dock, a crate put down 11–200 m away along a random axis (0.5 m crates,
    well within 1000 of their size), each to within a centimetre."""
    far = draw(st.floats(11.0, 200.0))
    axis = draw(st.integers(0, 1))
    documents = []
    for _ in range(2):
        jitter = draw(st.floats(-0.01, 0.01))
        crate = [1.0 + jitter, 1.0, 0.0]
        crate[axis] += far
        documents.append(
            {
                "format": "demoplan/demonstration-1",
                "objects": {
                    "pallet": {"shape": "box", "size": [1.2, 0.8, 0.15]},
                    "crate": {"shape": "box", "size": [0.5, 0.5, 0.5]},
                },
                "steps": [
                    {"object": "pallet", "position": [1.0, 1.0 + jitter, 0.0]},
                    {"object": "crate", "position": crate},
                ],
            }
        )
    return documents, far


@settings(max_examples=20, deadline=None)
@given(task=warehouses())
def test_a_workspace_wider_than_a_tabletop_is_learned_where_the_file_declares_its_unit(
    task: tuple[list[dict[str, Any]], float], tmp_path_factory: pytest.TempPathFactory
) -> None:
    """A warehouse's positions spread 11–200 m: with ``"units": {"length": "m"}``
    the user's word stands — one warning per file naming units, and learned;
    without units, refused as a tabletop file read in the wrong unit (exit 1)."""
    documents, far = task
    folder = tmp_path_factory.mktemp("warehouse")
    for k, document in enumerate(documents):
        (folder / f"declared-{k}.json").write_text(json.dumps(written_in(document, "m")))
        (folder / f"silent-{k}.json").write_text(json.dumps(document))
    declared = [str(folder / f"declared-{k}.json") for k in range(2)]
    result = CliRunner().invoke(app, ["learn", *declared, "--json"])
    assert result.exit_code == 0, result.stderr
    warnings = [line for line in result.stderr.splitlines() if "wider than a tabletop" in line]
    assert len(warnings) == 2
    assert all(": units: its positions spread" in line for line in warnings)
    crate = next(s for s in json.loads(result.stdout)["states"] if s["object"] == "crate")
    assert max(abs(v) for v in crate["position"]["value"]) >= far - 0.02
    silent = [str(folder / f"silent-{k}.json") for k in range(2)]
    result = CliRunner().invoke(app, ["learn", *silent, "--json"])
    assert result.exit_code == 1
    (line,) = result.stderr.strip().splitlines()
    assert 'units: lengths read in metres (the default: it gives no "units")' in line


def test_a_collection_names_the_demonstration_whose_units_are_wrong() -> None:
    good = written_in(_tower_document(), "m", declare=False)
    bad = written_in(_tower_document(), "mm", declare=False)
    document = {"format": "demoplan/demonstrations-1", "demonstrations": [good, bad]}
    exc = refusal(document)
    assert exc is not None and exc.field == "demonstrations[1].units"


@FAMILY
@given(task=tabletops(), unit=st.sampled_from(["cm", "mm"]))
def test_a_scene_in_the_wrong_unit_is_refused_and_in_the_right_one_read(
    task: dict[str, Any], unit: str
) -> None:
    assume("objects" in task)
    objects = {
        name: {**task["objects"][name], "position": step["position"]}
        for name, step in zip(task["objects"], task["steps"], strict=True)
    }
    scene = written_in({"format": "demoplan/scene-1", "objects": objects}, unit)
    read = scene_from_document(scene, "scene.json")
    assert read.objects[0].pose.position == pytest.approx(tuple(task["steps"][0]["position"]))
    del scene["units"]
    positions = [o["position"] for o in objects.values()]
    wide = max(max(p[a] for p in positions) - min(p[a] for p in positions) for a in range(3))
    factor = 1 / SCALE[unit]
    assume(abs(wide * factor - MAX_SPREAD_M) > 1e-6)
    assume(abs(largest(task) * factor - MAX_CARRIED_M) > 1e-6)
    if wide * factor > MAX_SPREAD_M or largest(task) * factor > MAX_CARRIED_M:
        with pytest.raises(InputError, match=r"^scene\.json: units: lengths read in metres"):
            scene_from_document(scene, "scene.json")
    else:
        scene_from_document(scene, "scene.json")


def test_the_user_report_millimetres_without_units(tmp_path: Path) -> None:
    """The issue's file: a demonstration in millimetres without ``units`` learned
    "Precision: 224312.1 mm"; now one line naming units, exit 1, nothing written."""
    path = tmp_path / "mm.json"
    document = written_in(
        json.loads((EXAMPLES / "set_table" / "demonstration-1.json").read_text()),
        "mm",
        declare=False,
    )
    path.write_text(json.dumps(document))
    result = CliRunner().invoke(app, ["learn", str(path), "-o", str(tmp_path / "model.json")])
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"demoplan: error: {path}: units: ")
    assert '"units": {"length": "mm"}' in lines[0]
    assert not (tmp_path / "model.json").exists()


# --------------------------------------------------------------------------- real files


def _real_documents() -> list[Path]:
    """The examples' demonstrations and scenes (a markers file of the
    calibration and a palette file have no positions of objects to weigh)."""
    return sorted(
        p
        for p in EXAMPLES.rglob("*.json")
        if any(
            kind in json.loads(p.read_text()).get("format", "")
            for kind in ("demoplan/demonstration", "demoplan/scene")
        )
    )


@pytest.mark.parametrize("path", _real_documents(), ids=lambda p: str(p.relative_to(EXAMPLES)))
def test_every_example_is_read_without_a_units_complaint_or_warning(
    path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    document = json.loads(path.read_text())
    with caplog.at_level(logging.WARNING, logger=WARNINGS):
        if "scene" in document["format"]:
            scene_from_document(document, str(path))
        else:
            demonstrations_from_path(path)
    assert [r.getMessage() for r in caplog.records] == []


def test_robosuite_recordings_imported_are_read_without_complaint(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """The nine demonstrations of robosuite's recordings (metres, quaternions,
    stacked cubes, nuts on pegs, objects in bins), written and read back."""
    from demoplan.documents.demonstrations import demonstration_to_dict
    from demoplan.segmentation import import_recording
    from tests.support.robosuite_data import (
        RobosuiteDataError,
        robosuite_demonstrations,
        skip_or_fail,
    )

    try:
        recordings = robosuite_demonstrations()
    except RobosuiteDataError as exc:
        skip_or_fail(exc)
    paths = []
    for recording in recordings.values():
        for demo in import_recording(recording):
            path = tmp_path / f"{demo.name}.json"
            path.write_text(json.dumps(demonstration_to_dict(demo)))
            paths.append(path)
    assert len(paths) == 9
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger=WARNINGS):
        for path in paths:
            demonstrations_from_path(path)
    assert [r.getMessage() for r in caplog.records] == []


# --------------------------------------------------------------------------- angles


def _scene_with_yaws(yaws: list[float], angle: str | None = None) -> dict[str, Any]:
    objects = {
        f"o{i}": {"position": [0.1 * i, 0.2, 0.0], "yaw": yaw, "size": [0.04, 0.04, 0.04]}
        for i, yaw in enumerate(yaws)
    }
    scene: dict[str, Any] = {"format": "demoplan/scene-1", "objects": objects}
    if angle is not None:
        scene["units"] = {"angle": angle}
    return scene


def _warnings(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]


turns = st.floats(-359.0, 359.0, allow_nan=False).map(lambda v: round(v, 1))


@FAMILY
@given(
    yaws=st.lists(turns, min_size=2, max_size=6).filter(
        lambda ys: sum(abs(y) >= 45.1 for y in ys) >= 2
    ),
    decimals=st.integers(3, 6),
)
def test_radians_read_as_degrees_are_warned_about(
    yaws: list[float], decimals: int, caplog: pytest.LogCaptureFixture
) -> None:
    """Objects turned (two at least by 45° or more) written in radians, read in
    degrees: one warning naming the file and the largest angle's field."""
    written = [round(math.radians(y), decimals) for y in yaws]
    assume(not all(float(w).is_integer() for w in written if w))  # whole numbers read as degrees
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger=WARNINGS):
        scene_from_document(_scene_with_yaws(written), "scene.json")
    (line,) = _warnings(caplog)
    biggest = max(range(len(written)), key=lambda i: abs(written[i]))
    assert line.startswith(f"scene.json: objects.o{biggest}.yaw: every angle of the file")
    assert '"units": {"angle": "rad"}' in line
    # Declared, the same file is read without a word, the turns as meant.
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger=WARNINGS):
        scene = scene_from_document(_scene_with_yaws(written, "rad"), "scene.json")
    assert _warnings(caplog) == []
    for obj, yaw in zip(scene.objects, yaws, strict=True):
        turned = rpy_from_quat(obj.pose.orientation or (0, 0, 0, 1))[2]
        assert math.remainder(turned - yaw, 360) == pytest.approx(0, abs=0.03)  # 3 decimals


@FAMILY
@given(
    common=st.lists(st.integers(-12, 12), min_size=2, max_size=6),
    noise=st.lists(
        st.floats(-3, 3, allow_nan=False).map(lambda v: round(v, 1)), min_size=6, max_size=6
    ),
)
def test_ordinary_degree_files_are_not_warned_about(
    common: list[int], noise: list[float], caplog: pytest.LogCaptureFixture
) -> None:
    """Hand-placed objects at multiples of 15° with a few degrees of scatter,
    one turned at least 15°: no warning."""
    yaws = [15 * c + e for c, e in zip(common, noise, strict=False)]
    assume(any(c != 0 for c in common))
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger=WARNINGS):
        scene_from_document(_scene_with_yaws(yaws), "scene.json")
    assert _warnings(caplog) == []


@pytest.mark.parametrize(
    "yaws",
    [
        [0, 2, 0],
        [0, 1, -3, 5],
        [-0.5, -0.99, -0.4],
        [0.49, 0.5, 0.55],
        [-0.2, -0.2, 1.0, 0.2, 0.5],
    ],
)
def test_small_degree_turns_are_not_warned_about(
    yaws: list[float], caplog: pytest.LogCaptureFixture
) -> None:
    """Whole degrees (pyramid-fig4's 2°), and placements within a degree of the
    axes, at most one beyond π/4 (the placements of the blocks and kitting
    examples without their initial poses): degrees are the likelier reading."""
    with caplog.at_level(logging.WARNING, logger=WARNINGS):
        scene_from_document(_scene_with_yaws(yaws), "scene.json")
    assert _warnings(caplog) == []


# --------------------------------------------------------------------------- releases


def _block(z: float, xy: tuple[float, float] = (0.5, 0.3), yaw: float = 0.0) -> Pose:
    return Pose((xy[0], xy[1], z), quat_from_yaw(yaw))


@st.composite
def towers(draw: st.DrawFn) -> tuple[Demonstration, list[float]]:
    """A tower of 2–5 blocks built bottom-up, each a little off the centre of the
    one under it (well within it) and turned; the blocks start far apart."""
    n = draw(st.integers(2, 5))
    side = st.floats(0.03, 0.08, allow_nan=False)
    sizes = [
        (draw(side), draw(side), draw(st.floats(0.015, 0.06, allow_nan=False))) for _ in range(n)
    ]
    offset = st.floats(-0.004, 0.004, allow_nan=False)
    steps, bottoms, z = [], [], 0.0
    for i in range(n):
        bottoms.append(z)
        xy = (0.5 + draw(offset), 0.3 + draw(offset))
        steps.append(Step(f"b{i}", _block(z, xy, draw(st.floats(-20, 20)))))
        z += sizes[i][2]
    demo = Demonstration(
        name="tower",
        steps=tuple(steps),
        objects=tuple((f"b{i}", ObjectGeometry("box", sizes[i])) for i in range(n)),
        initial=tuple((f"b{i}", _block(0.0, (0.1 * i - 0.5, -0.4))) for i in range(n)),
    )
    return demo, bottoms


@FAMILY
@given(tower=towers())
def test_a_tower_built_bottom_up_has_no_unsupported_release(
    tower: tuple[Demonstration, list[float]],
) -> None:
    demo, _ = tower
    assert unsupported_releases(demo) == []


@FAMILY
@given(tower=towers(), data=st.data())
def test_a_block_released_before_its_support_is_named_with_the_step_it_arrives(
    tower: tuple[Demonstration, list[float]], data: st.DataObject
) -> None:
    """Block i put first, before block i − 1 under it: a warning for step 1,
    block i at its height above the table, block i − 1 arriving at step i."""
    demo, bottoms = tower
    i = data.draw(st.integers(1, len(demo.steps) - 1))
    steps = (demo.steps[i], *demo.steps[:i], *demo.steps[i + 1 :])
    (release,) = unsupported_releases(
        Demonstration("d2", steps, demo.objects, initial=demo.initial)
    )
    assert (release.demonstration, release.step, release.object) == ("d2", 1, f"b{i}")
    assert release.height == pytest.approx(bottoms[i])
    assert release.above is None and release.arrives == (f"b{i - 1}", i + 1)
    assert release.describe().startswith(f"demonstration 'd2' step 1: b{i} released ")


@FAMILY
@given(height=st.floats(0.0, 0.5, allow_nan=False), carried=st.booleans())
def test_a_release_in_the_air_is_named_and_one_on_the_table_is_not(
    height: float, carried: bool
) -> None:
    """One cube, nothing else: released more than 1 cm above the table it is
    named; a point it is carried through (followed by its own next step) never."""
    geometry = (("cube", ObjectGeometry("box", (0.04, 0.04, 0.04))),)
    steps = [Step("cube", _block(height))]
    if carried:
        steps.append(Step("cube", _block(0.0, (0.6, 0.3))))
    found = unsupported_releases(Demonstration("d", tuple(steps), geometry))
    assert [r.step for r in found] == ([1] if height > 0.01 and not carried else [])


@FAMILY
@given(gap=st.floats(0.0, 0.2, allow_nan=False), base=st.floats(0.01, 0.1, allow_nan=False))
def test_a_release_above_a_block_names_the_gap_to_its_top(gap: float, base: float) -> None:
    """A cube released over a block: resting on it up to 1 cm above its top;
    higher, named with its height above the block's top."""
    geometry = (
        ("block", ObjectGeometry("box", (0.1, 0.1, base))),
        ("cube", ObjectGeometry("box", (0.04, 0.04, 0.04))),
    )
    steps = (Step("block", _block(0.0)), Step("cube", _block(base + gap, (0.51, 0.3))))
    found = unsupported_releases(Demonstration("d", steps, geometry))
    if gap <= 0.01 - 1e-9:
        assert found == []
    elif gap > 0.01 + 1e-9:
        (release,) = found
        assert release.above == "block" and release.height == pytest.approx(gap)
        assert "above the top of the block, resting on nothing" in release.describe()


def test_a_tilted_knife_on_its_edge_rests_on_the_table() -> None:
    """A knife pitched 90° (the cucumber example) rests on its edge: its resting
    point stands half its width above the table, its lowest corner on it."""
    geometry = (("knife", ObjectGeometry("box", (0.02, 0.25, 0.04))),)
    pitched = Pose((0.4, 0.1, 0.0103), (0.0, math.sqrt(0.5), 0.0, math.sqrt(0.5)))
    assert unsupported_releases(Demonstration("d", (Step("knife", pitched),), geometry)) == []
    raised = Pose((0.4, 0.1, 0.05), pitched.orientation)
    (release,) = unsupported_releases(Demonstration("d", (Step("knife", raised),), geometry))
    assert release.height == pytest.approx(0.04)


def test_a_block_on_two_bridging_blocks_is_held_up() -> None:
    """The blocks example's top block rests on two blocks with a gap between:
    its centre is over the gap, its footprint on both."""
    cube = ObjectGeometry("box", (0.04, 0.04, 0.04))
    demo = Demonstration(
        "bridge",
        (
            Step("wood", _block(0.0, (0.335, 0.04))),
            Step("green", _block(0.0, (0.391, 0.036))),
            Step("red", _block(0.04, (0.3655, 0.0402))),
        ),
        (("wood", cube), ("green", cube), ("red", cube)),
    )
    assert unsupported_releases(demo) == []


def test_the_user_report_bowl_released_before_the_plate(tmp_path: Path) -> None:
    """The issue's demonstration: `learn` succeeds and says, in one warning line,
    which step of which demonstration releases the bowl on nothing."""
    objects = {
        "plate": {"shape": "cylinder", "size": [0.24, 0.24, 0.02]},
        "bowl": {"shape": "cylinder", "size": [0.14, 0.14, 0.06]},
        "cup": {"shape": "cylinder", "size": [0.08, 0.08, 0.1]},
    }
    initial = {n: {"position": [0.1, 0.2 + 0.3 * i]} for i, n in enumerate(objects)}
    good = [
        {"object": "plate", "position": [0.5, 0.3, 0]},
        {"object": "cup", "position": [0.7, 0.45, 0]},
        {"object": "bowl", "position": [0.5, 0.3, 0.02]},
    ]
    wrong = [
        {"object": "cup", "position": [0.71, 0.45, 0]},
        {"object": "cup", "position": [0.7, 0.45, 0]},
        {"object": "cup", "position": [0.7, 0.46, 0]},
        {"object": "bowl", "position": [0.5, 0.31, 0.02]},
        {"object": "plate", "position": [0.5, 0.3, 0]},
    ]
    demos = [
        {"name": "d1", "objects": objects, "initial": initial, "steps": good},
        {"name": "d2", "initial": initial, "steps": wrong},
    ]
    path = tmp_path / "dinner.json"
    path.write_text(json.dumps({"format": "demoplan/demonstrations-1", "demonstrations": demos}))
    result = CliRunner().invoke(app, ["learn", str(path), "-o", str(tmp_path / "model.json")])
    assert result.exit_code == 0, result.stderr
    warnings = [line for line in result.stderr.splitlines() if "released" in line]
    assert warnings == [
        f"demoplan: WARNING: {path}: demonstrations[1]: demonstration 'd2' step 4: bowl "
        "released 2 cm above the table with nothing under it (the plate arrives at step 5)"
    ]


def _tower_document() -> dict[str, Any]:
    """A two-block tower in metres (a plain document for the collection test)."""
    return {
        "format": "demoplan/demonstration-1",
        "objects": {"a": {"size": [0.04, 0.04, 0.04]}, "b": {"size": [0.04, 0.04, 0.04]}},
        "initial": {"a": {"position": [0.1, 0.1]}, "b": {"position": [0.2, 0.1]}},
        "steps": [
            {"object": "a", "position": [0.5, 0.3, 0.0]},
            {"object": "b", "position": [0.5, 0.3, 0.04]},
        ],
    }
