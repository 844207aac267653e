"""The lean ``demoplan perceive`` path (demoplan.cli.perceiving) against the typer command.

For every command line both must print the same stdout and stderr, exit with
the same code and write the same files; whatever the lean parser does not
accept must be left to typer.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import typer.main
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.cli.perceiving import (
    PERCEIVE_OPTIONS,
    PerceiveOptions,
    parse_perceive_options,
    run_perceive,
)
from demoplan.commands.perception import calibrate
from demoplan.perception.camera import Camera, save_image
from demoplan.perception.pinhole import render_table
from demoplan.perception.synthetic import SyntheticBlock, render_blocks
from tests.perception.test_calibration import BLOCKS, MARKER_SIDE, MARKERS, markers_file
from tests.perception.test_calibration import camera as oblique

PHOTOS = Path(__file__).resolve().parents[1] / "data" / "photos"


def outcome(folder: Path) -> dict[str, bytes]:
    """The files a command left in ``folder`` (its inputs among them)."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def through_typer(args: list[str]) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, ["perceive", *args])
    return result.exit_code, result.stdout, result.stderr


def through_lean_path(
    args: list[str], capsys: pytest.CaptureFixture[str]
) -> tuple[int, str, str] | None:
    """What the launcher runs for a pipe, or None where it leaves ``args`` to typer."""
    options = parse_perceive_options(args)
    if options is None:
        return None
    capsys.readouterr()
    code = run_perceive(options)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture(scope="module")
def material(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A top view of three blocks, two of one colour (a type column), 1 px = 1 mm; a
    bare table; a file that is no image; an oblique view of markers, its markers
    file and the camera file calibrated from it."""
    folder = tmp_path_factory.mktemp("material")
    blocks = [
        SyntheticBlock("red", 0.10, 0.10, 0.0, 0.04),
        SyntheticBlock("red", 0.20, 0.12, 20.0, 0.04),
        SyntheticBlock("blue", 0.15, 0.22, 5.0, 0.04),
    ]
    image = render_blocks(blocks, Camera(1000.0, (0.0, 0.0)), width=320, height=300, rng=3)
    save_image(image, folder / "table.png")
    save_image(image * 0 + 200, folder / "empty.png")  # a bare grey table
    (folder / "junk.png").write_bytes(b"not an image")
    view = render_table(oblique(20.0), BLOCKS, MARKERS, marker_side=MARKER_SIDE)
    save_image(view, folder / "view.png")
    calibrate(folder / "view.png", markers_file(folder), output=folder / "camera.json")
    return folder


@pytest.fixture
def table(material: Path, tmp_path: Path) -> Path:
    """A fresh copy of :func:`material` for one command line."""
    for name, content in outcome(material).items():
        (tmp_path / name).write_bytes(content)
    return tmp_path


LEAN = [
    ["table.png", "--px-per-m", "1000", "--origin", "0", "0"],
    ["table.png", "--px-per-m=1000", "--origin", "-0.1", "0.2", "--json", "-o", "scene.json"],
    ["table.png", "--side", "0.04", "--plot", "overlay.png", "-o", "scene.json"],
    ["table.png", "--side", "0.04", "--px-per-m", "1000", "--origin", "0", "0", "--timeout", "inf"],
    ["missing.png", "--px-per-m", "1000", "--origin", "0", "0"],  # no such file
    ["junk.png", "--side", "0.04"],  # not an image
    ["empty.png", "--px-per-m", "1000", "--origin", "0", "0"],  # no blocks: exit 1
    ["table.png", "--px-per-m", "1000"],  # no origin: how pixels map
    ["table.png", "--px-per-m", "1000", "--origin", "nan", "0"],  # not finite
    ["table.png", "--px-per-m", "1000", "--origin", "0", "0", "--camera", "c.json"],
    ["table.png", "--camera", "missing.json"],
    ["view.png", "--markers", "markers.json", "--side", "0.04", "--plot", "overlay.png"],
    ["view.png", "--camera", "camera.json", "--json"],
    ["view.png", "--camera", "markers.json"],  # not a camera file
    ["table.png", "--side", "0.04", "-o", "table.png"],  # would overwrite its input
    ["table.png", "--side", "0.04", "-o", "same.png", "--plot", "same.png"],
    ["table.png", "--side", "0.04", "--timeout", "0"],  # out of time: exit 4
    ["table.png", "--side", "0.04", "--side", "0.03", "--px-per-m", "1000", "--origin", "0", "0"],
    ["table.png", "--side", "0.04", "--side", "0.03"],  # one size for the scale: exit 2
]
"""Command lines the lean path runs: successes and errors of perception itself."""

DECLINED = [
    ["--help"],
    ["table.png", "--side", "0.04", "--help"],
    ["table.png", "--side", "abc"],  # a bad number
    ["table.png", "--px-per-m", "0", "--origin", "0", "0"],  # out of typer's range
    ["table.png", "--px-per-m", "nan", "--origin", "0", "0"],
    ["table.png", "--side", "-0.04"],
    ["table.png", "--side", "0.04", "--side", "-0.03", "--px-per-m", "1000", "--origin", "0", "0"],
    ["table.png", "--side", "0.04", "--timeout", "-1"],
    ["table.png", "--origin", "0"],  # one number of two
    ["table.png", "table.png", "--side", "0.04"],  # two images
    ["table.png", "--side", "0.04", "--sequence"],
    ["table.png", "--side", "0.04", "--before", "table.png"],
    ["table.png", "--side", "0.04", "--colours", "p.yaml"],
    ["table.png", "--side", "0.04", "--unknown"],
    ["table.png", "--sid", "0.04"],  # an abbreviation
    ["--", "table.png", "--side", "0.04"],
]
"""Command lines left to typer: its help and usage errors."""


@pytest.mark.parametrize("args", LEAN, ids=" ".join)
def test_same_output_exit_code_and_files(
    args: list[str],
    table: Path,
    tmp_path_factory: pytest.TempPathFactory,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Relative paths in a folder each: the lines name the same files."""
    other = tmp_path_factory.mktemp("typer")
    for name, content in outcome(table).items():
        (other / name).write_bytes(content)
    monkeypatch.chdir(table)
    lean = through_lean_path(args, capsys)
    assert lean is not None, args
    monkeypatch.chdir(other)
    assert through_typer(args) == lean
    assert outcome(other) == outcome(table)


def test_the_cases_cover_success_and_each_kind_of_error(
    table: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Not a list of one outcome: tables, JSON, the rejections line and exit codes 1, 2, 4."""
    monkeypatch.chdir(table)
    results = [through_lean_path(args, capsys) for args in LEAN]
    codes = {r[0] for r in results if r is not None}
    assert codes == {0, 1, 2, 4}
    outputs = "".join(r[1] for r in results if r is not None)
    assert "┃ name ┃ type" in outputs and '"format": "demoplan/scene-1"' in outputs
    assert "rejected" in outputs and "(drawn in overlay.png)" in outputs


@pytest.mark.parametrize("args", DECLINED, ids=" ".join)
def test_everything_else_is_left_to_typer(args: list[str]) -> None:
    assert parse_perceive_options(args) is None


def test_parsed_options() -> None:
    options = parse_perceive_options(
        ["--origin", "0.5", "-1", "a.png", "--px-per-m=800", "--json", "-o", "s.json"]
    )
    assert options == PerceiveOptions(
        Path("a.png"), 800.0, (0.5, -1.0), json_output=True, output=Path("s.json")
    )
    several = parse_perceive_options(["a.png", "--side", "0.038", "--side=0.025"])
    assert several == PerceiveOptions(Path("a.png"), side=(0.038, 0.025))


def test_the_lean_parser_knows_every_option_it_claims_and_declines_the_rest() -> None:
    command = typer.main.get_command(app)
    perceive = command.commands["perceive"]  # type: ignore[attr-defined]
    typer_options = {name for p in perceive.params for name in p.opts if name.startswith("--")}
    assert set(PERCEIVE_OPTIONS) <= typer_options
    for option in sorted(typer_options - set(PERCEIVE_OPTIONS)):
        assert parse_perceive_options(["a.png", "--side", "0.04", option]) is None, option


def test_a_real_photograph_through_the_executable(tmp_path: Path) -> None:
    """``python -m demoplan perceive`` on a photograph with ``--side``, stdout piped:
    neither typer, click nor pydantic is imported, and stdout, stderr, exit code
    and the scene file are typer's."""
    photo = str(PHOTOS / "mrhan_touching.png")
    probe = (
        "import runpy, sys\n"
        "if sys.argv[1] == 'typer':  # the lean parser declines everything\n"
        "    import demoplan.cli.perceiving as lean\n"
        "    lean.parse_perceive_options = lambda args: None\n"
        "sys.argv = ['demoplan', 'perceive', *sys.argv[2:]]\n"
        "try:\n    runpy.run_module('demoplan', run_name='__main__')\n"
        "finally:\n    heavy = {m.split('.')[0] for m in sys.modules}\n"
        "    heavy &= {'typer', 'click', 'pydantic'}\n"
        "    print(sorted(heavy), file=sys.stderr)\n"
    )
    runs = {}
    for path in ("lean", "typer"):
        folder = tmp_path / path
        folder.mkdir()
        runs[path] = subprocess.run(
            [sys.executable, "-c", probe, path, photo, "--side", "0.025", "-o", "scene.json"],
            capture_output=True,
            text=True,
            cwd=folder,
            check=False,
        )
    lean, typer_run = runs["lean"], runs["typer"]
    assert lean.returncode == typer_run.returncode == 0, lean.stderr
    assert lean.stdout == typer_run.stdout and "Blocks in mrhan_touching.png" in lean.stdout
    assert lean.stderr == "[]\n"
    assert "'pydantic', 'typer'" in typer_run.stderr  # click: typer's own copy, or not
    assert outcome(tmp_path / "lean") == outcome(tmp_path / "typer")
