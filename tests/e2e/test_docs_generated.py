"""docs/formats.md and docs/cli.md are what docs/generate.py writes from the code
now (a changed option, schema or output fails here), their examples load with
demoplan's own readers, and every command of the CLI is documented."""

from __future__ import annotations

import importlib.util
import json
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import h5py
import numpy as np
import pytest
import typer.core
import typer.main
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.documents.demonstrations import demonstrations_from_document, load_object_geometry
from demoplan.learning.modelfile import model_from_dict
from demoplan.model import TaskModel
from demoplan.planning.xml import problem_from_xml
from demoplan.scenes.scene import Scene, scene_from_document
from demoplan.segmentation.readers.csv import load_csv

ROOT = Path(__file__).resolve().parents[2]
FENCE = re.compile(r"^```(\w*)\n(.*?)^```$", re.S | re.M)


def generator() -> ModuleType:
    """docs/generate.py as a module (docs/ is no package)."""
    name = "demoplan_docs_generate"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, ROOT / "docs" / "generate.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while it loads
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def pages() -> dict[str, str]:
    texts: dict[str, str] = generator().pages()
    return texts


def fenced(page: str, language: str) -> list[str]:
    text = (ROOT / "docs" / page).read_text(encoding="utf-8")
    return [body for kind, body in FENCE.findall(text) if kind == language]


def test_committed_pages_are_what_the_generator_writes(pages: dict[str, str]) -> None:
    assert set(pages) == {"formats.md", "cli.md"}
    for name, text in pages.items():
        committed = (ROOT / "docs" / name).read_text(encoding="utf-8")
        assert committed == text, f"docs/{name} is out of date: run python docs/generate.py"


def test_check_names_the_page_that_is_out_of_date(pages: dict[str, str], tmp_path: Path) -> None:
    for name, text in pages.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    assert generator().stale(tmp_path, pages) == []
    (tmp_path / "cli.md").write_text(pages["cli.md"].replace("--json", "--jsn", 1))
    (tmp_path / "formats.md").unlink()
    assert generator().stale(tmp_path, pages) == ["formats.md", "cli.md"]


def test_check_passes_on_the_committed_pages(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, str(ROOT / "docs" / "generate.py"), "--check"],
        capture_output=True,
        text=True,
        env={"HOME": str(tmp_path), "COLUMNS": "20", "PYTHONHASHSEED": "1"},
        cwd="/",
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr


def test_pages_do_not_depend_on_the_terminal_width(
    pages: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "40")
    monkeypatch.setenv("LINES", "10")
    assert generator().pages() == pages


def load(document: dict[str, Any], tmp_path: Path) -> object:
    """A JSON example read as demoplan reads a file of its kind."""
    kind = str(document.get("format", "")).removeprefix("demoplan/").rsplit("-", 1)[0]
    if kind in ("demonstration", "demonstrations"):
        return demonstrations_from_document(document, "example")
    if kind == "scene":
        return scene_from_document(document, "example")
    if kind == "model":
        return model_from_dict(document, "example")
    if kind == "objects":  # the studio's objects file
        from demoplan.commands.objects import objects_from_document

        return objects_from_document(document, "example")
    if kind == "markers":  # calibrate --markers, perceive --markers
        from demoplan.perception.calibration import markers_from_document

        return markers_from_document(document, "example")
    if "final_scene" in document:  # run --json
        return scene_from_document(document["final_scene"], "example: final_scene")
    if "actions" in document:  # solve --json, plan --json
        for action in document["actions"]:
            assert action[0] in ("GRASP", "PUT_DOWN") and len(action) == 4
        return document["actions"]
    if set(document) == {"landmarks"}:  # a landmark entry, as in any file
        from demoplan.documents.poses import LandmarkSchema

        return {n: LandmarkSchema.model_validate(e) for n, e in document["landmarks"].items()}
    if document and all(isinstance(v, list) and len(v) == 3 for v in document.values()):
        from demoplan.perception.colours import load_palette  # perceive --colours

        palette = tmp_path / "colours.json"
        palette.write_text(json.dumps(document), encoding="utf-8")
        return load_palette(palette)
    path = tmp_path / "objects.json"  # segment --objects-file
    path.write_text(json.dumps(document), encoding="utf-8")
    return load_object_geometry(path)


def test_every_json_example_loads(tmp_path: Path) -> None:
    examples = fenced("formats.md", "json")
    assert len(examples) >= 8
    kinds = set()
    for body in examples:
        loaded = load(json.loads(body), tmp_path)
        kinds.add(type(loaded).__name__)
    assert {"list", "Scene", "TaskModel", "dict"} <= kinds


def test_the_model_example_is_the_blocks_model() -> None:
    (model,) = [
        m
        for m in (json.loads(body) for body in fenced("formats.md", "json"))
        if m.get("format") == "demoplan/model-1"
    ]
    loaded = model_from_dict(model, "example")
    assert isinstance(loaded, TaskModel)
    assert [s.object for s in loaded.states] == ["wood", "green", "red", "green"]
    assert len(loaded.constraints) == 5


def test_the_run_example_ends_in_a_scene() -> None:
    (report,) = [
        r for r in (json.loads(body) for body in fenced("formats.md", "json")) if "final_scene" in r
    ]
    scene = scene_from_document(report["final_scene"], "example")
    assert isinstance(scene, Scene) and report["success"]
    assert [f["kind"] for f in report["failures"]] and report["replans"] == len(report["failures"])


def test_csv_and_xml_examples_load(tmp_path: Path) -> None:
    stream, in_millimetres = fenced("formats.md", "csv")
    path = tmp_path / "stream.csv"
    path.write_text(stream, encoding="utf-8")
    assert len(load_csv(path).tracks) == 7
    path.write_text(in_millimetres, encoding="utf-8")
    plate = load_csv(path).track("plate")
    assert plate.positions[0].tolist() == pytest.approx([0.1489, 0.2012, 0.0007])
    # the other XML block is an excerpt of a behaviour tree (tests/execution/test_behaviour_tree.py)
    (problem,) = [text for text in fenced("formats.md", "xml") if "BTCPP_format" not in text]
    assert len(problem_from_xml(problem).objects) == 4


def test_every_command_and_option_is_in_cli_md() -> None:
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    root = typer.main.get_command(app)
    assert isinstance(root, typer.core.TyperGroup)
    context = root.context_class(root, info_name="demoplan")
    names = root.list_commands(context)
    assert len(names) >= 11
    for name in names:
        command = root.get_command(context, name)
        assert command is not None
        assert f"\n## `demoplan {name}`\n" in text, name
        section = text.split(f"\n## `demoplan {name}`\n", 1)[1].split("\n## ", 1)[0]
        for param in command.params:
            for opt in (*param.opts, *param.secondary_opts):
                argument = str(param.metavar or opt.upper()).replace("|", "\\|")
                shown = f"`{opt}`" if opt.startswith("-") else f"`{argument}"
                assert shown in section, (name, opt)
    assert "## Exit codes" in text
    for code in ("| 0 |", "| 1 |", "| 2 |", "| 3 |", "| 4 |", "| 130 |", "| 143 |"):
        assert code in text


RECORDING_MODEL = """<mujoco>
  <worldbody>
    <body name="table" pos="0 0 0.4"><geom type="box" size="0.5 0.5 0.4"/></body>
    <body name="box0" pos="0.1 0.2 0.85"><freejoint/><geom type="box" size="0.05 0.05 0.05"/></body>
  </worldbody>
</mujoco>"""


def write_recording(path: Path) -> Path:
    """A robosuite-like recording: the box rests, is carried 0.3 m in x, rests (100 Hz)."""
    t = np.arange(1, 401) * 0.01
    carried = np.clip(t - 1.0, 0.0, 1.0)
    states = np.zeros((t.size, 1 + 7 + 6))  # time, the free joint's qpos and qvel
    states[:, 0] = t
    states[:, 1] = 0.1 + 0.3 * carried
    states[:, 2] = 0.2
    states[:, 3] = 0.85 + 0.1 * np.sin(np.pi * carried)
    states[:, 4] = 1.0  # quaternion w
    with h5py.File(path, "w") as handle:
        data = handle.create_group("data")
        data.attrs["env"] = "Toy"
        demo = data.create_group("demo_1")
        demo.create_dataset("states", data=states)
        demo.attrs["model_file"] = RECORDING_MODEL
    return path


def test_import_json_has_the_documented_fields(tmp_path: Path) -> None:
    recording = write_recording(tmp_path / "toy.hdf5")
    result = CliRunner().invoke(
        app, ["import", str(recording), "-o", str(tmp_path / "out"), "--json"]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    docs = generator()
    assert list(summary) == list(docs.IMPORT_JSON.fields)
    (entry,) = summary["demonstrations"]
    documented = set(docs.IMPORTED_JSON.fields)
    assert set(entry) == documented - set(docs.IMPORTED_JSON.optional)
