"""The front ends — the command line, the studio, the library (api.py) — only
parse their input and render what the command layer (demoplan.commands)
returns: no call from one of their modules into a pipeline stage (learning,
planning, scenes, execution, segmentation, perception, experiments) other
than the renderers and parsers named here, one list for all three."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

CLI = Path(__file__).resolve().parents[1] / "src" / "demoplan" / "cli"
STAGES = (
    "demoplan.learning",
    "demoplan.planning",
    "demoplan.scenes",
    "demoplan.execution",
    "demoplan.segmentation",
    "demoplan.perception",
    "demoplan.experiments",
)
RENDERING_AND_PARSING = {
    # tables and JSON of values the command layer returned
    "demoplan.learning.tables",
    "demoplan.learning.modelfile.model_to_dict",
    "demoplan.planning.problem.format_plan",
    "demoplan.planning.problem.optimality_line",
    "demoplan.planning.problem.plan_to_json",
    # options parsed into the values the command layer takes
    "demoplan.execution.faults.parse_faults",
    "demoplan.segmentation.types.parse_object_patterns",
    "demoplan.segmentation.settings.settings_help",
    "demoplan.scenes.geometry.GeometrySettings",
    "demoplan.segmentation.streams.StreamOptions",
    "demoplan.budget.Budget",
    "demoplan.execution.executor.ExecutionSettings",
    # a scene document parsed as `plan` parses it (the studio's requests)
    "demoplan.scenes.scene.scene_from_document",
    # the constraint graph as the report draws it
    "demoplan.learning.constraints.goal_order",
    "demoplan.learning.constraints.visit_sequence",
}


def _stage_calls(path: Path, allowed: set[str] = RENDERING_AND_PARSING) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    origin: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            for alias in node.names:
                origin[alias.asname or alias.name] = f"{node.module}.{alias.name}"
        elif isinstance(node, ast.Import):
            for alias in node.names:
                origin[alias.asname or alias.name.split(".")[0]] = alias.name
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        while isinstance(func, ast.Attribute):
            func = func.value
        if not isinstance(func, ast.Name) or func.id not in origin:
            continue
        target = origin[func.id]
        if not target.startswith(STAGES):
            continue
        if any(target == name or target.startswith(name + ".") for name in allowed):
            continue
        found.append(f"{path.name}:{node.lineno}: {target}")
    return found


STUDIO = CLI.parent / "studio"
FRONT_END_MODULES = {
    "cli": sorted(CLI.rglob("*.py")),
    "studio": sorted(STUDIO.rglob("*.py")),  # its routes included
    "api": [CLI.parent / "api.py", CLI.parent / "__main__.py"],
}


@pytest.mark.parametrize("front_end", sorted(FRONT_END_MODULES))
def test_a_front_end_calls_the_command_layer_not_the_stages(front_end: str) -> None:
    """No front end holds a second copy of learning, planning or execution:
    each calls the command layer (the studio's targets in a scene and what a
    picked-up object carries included: demoplan.commands.scenes) and only the
    renderers and parsers of :data:`RENDERING_AND_PARSING`."""
    modules = FRONT_END_MODULES[front_end]
    assert len(modules) >= 2 and all(path.is_file() for path in modules)
    calls = [call for path in modules for call in _stage_calls(path)]
    assert not calls, f"work inside {front_end}:\n" + "\n".join(calls)


def test_the_check_sees_a_call_into_a_stage(tmp_path: Path) -> None:
    module = tmp_path / "command.py"
    module.write_text(
        "from demoplan.scenes.plan import plan_in_scene\n"
        "from demoplan.learning import tables\n"
        "def plan(m, s):\n"
        "    tables.state_rows(m)\n"
        "    return plan_in_scene(m, s)\n"
    )
    assert _stage_calls(module) == ["command.py:5: demoplan.scenes.plan.plan_in_scene"]


# --- floors: every import, function-level ones included, goes down or level ---

SRC = CLI.parents[1]
FLOORS = {
    # the shared floor: the package root's modules (model, poses… errors, fileio,
    # budget, graphs) and what the files say (documents/)
    "documents": 0,
    # the paper's stages, which know nothing of each other's insides but values
    "learning": 1,
    "planning": 1,
    "segmentation": 1,
    "perception": 1,
    # a learned task in a scene: goals, locations, problems (uses learning and planning)
    "scenes": 2,
    "plotting": 3,
    "execution": 4,
    "experiments": 5,
    "commands": 6,
    # many runs of the command layer's ``run`` (``evaluate``): beside the commands
    "evaluation": 6,
    "cli": 7,
    # the studio's web application: a front end over the command layer, as the CLI
    "studio": 7,
    # what the front ends share (Ctrl-C and SIGTERM handling)
    "frontends": 7,
}
FRONT_ENDS = {"api": 7, "__main__": 7, "launcher": 7}
VALUE_MODULES = {
    # The task model records the settings it was learned with: this value
    # (which imports nothing of demoplan but errors) sits on the model's floor.
    "demoplan.learning.settings": 0,
}


def _modules() -> dict[str, Path]:
    found = {}
    for path in (SRC / "demoplan").rglob("*.py"):
        name = ".".join(path.relative_to(SRC).with_suffix("").parts)
        found[name.removesuffix(".__init__")] = path
    return found


def _floor(module: str) -> int:
    if module in VALUE_MODULES:
        return VALUE_MODULES[module]
    parts = module.split(".")
    if len(parts) == 1:
        return 7  # the package itself: its lazy names reach every floor
    return FLOORS.get(parts[1], FRONT_ENDS.get(parts[1], 0))


def _imports(modules: dict[str, Path]) -> list[tuple[str, str, int]]:
    """(importer, imported module, line) for every import of a demoplan module."""
    edges = []
    for name, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets: list[str] = []
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                for alias in node.names:  # `from demoplan import rotations` names a module
                    full = f"{node.module}.{alias.name}"
                    targets.append(full if full in modules else node.module)
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            edges += [(name, t, node.lineno) for t in targets if t in modules and t != name]
    return edges


def test_no_import_runs_back_up_a_floor() -> None:
    upward = sorted(
        {
            f"{a} (floor {_floor(a)}) imports {b} (floor {_floor(b)}), line {line}"
            for a, b, line in _imports(_modules())
            if _floor(b) > _floor(a)
        }
    )
    assert not upward, "\n".join(upward)


def test_no_import_circle() -> None:
    import networkx as nx

    graph = nx.DiGraph((a, b) for a, b, _ in _imports(_modules()))
    circles = [" -> ".join(c) for c in nx.simple_cycles(graph)]
    assert not circles, "\n".join(circles)


def test_no_front_end_reaches_into_the_command_line() -> None:
    """The studio and the library share what they need with the command line
    through demoplan.frontends (Ctrl-C and SIGTERM), never by importing cli/."""
    reaching = sorted(
        f"{a} imports {b}, line {line}"
        for a, b, line in _imports(_modules())
        if a.startswith(("demoplan.studio", "demoplan.api", "demoplan.frontends"))
        and b.startswith("demoplan.cli")
    )
    assert not reaching, "\n".join(reaching)


def test_at_most_ten_modules_at_the_package_root() -> None:
    root = sorted(p.name for p in (SRC / "demoplan").glob("*.py"))
    assert len(root) <= 10, root


def test_the_command_line_starts_without_the_numeric_stack() -> None:
    """``demoplan --help`` and a lean ``solve`` load the typer application but
    none of the stages' libraries: the CLI imports the command layer inside
    each command, so that starting it stays cheap."""
    import subprocess
    import sys

    heavy = ("numpy", "scipy", "shapely", "matplotlib", "mujoco", "pydantic", "sklearn")
    script = (
        "import sys, demoplan.cli.application, demoplan.cli.launcher\n"
        f"print(sorted(m for m in {heavy!r} if m in sys.modules))"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert loaded == "[]", loaded


ARCHITECTURE = SRC.parent / "docs" / "architecture.md"


def documented_floors(text: str) -> dict[str, int]:
    """Each folder (``learning/``) of the floors table in docs/architecture.md
    and the floor its row names."""
    floors = {}
    for line in text.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) >= 3 and cells[0].isdigit():
            for folder in re.findall(r"`([a-z_]+)/`", cells[1]):
                floors.setdefault(folder, int(cells[0]))
        elif line.startswith("## ") and floors:
            break  # the floors table is the page's first numbered table
    return floors


def test_every_package_is_on_its_floor_in_the_architecture_page() -> None:
    packages = sorted(path.parent.name for path in (SRC / "demoplan").glob("*/__init__.py"))
    assert {"learning", "studio", "evaluation"} <= set(packages)  # the walk found them
    documented = documented_floors(ARCHITECTURE.read_text(encoding="utf-8"))
    wrong = [
        f"{package}/: floor {_floor(f'demoplan.{package}')} by the imports, "
        f"{documented.get(package, 'none')} in docs/architecture.md"
        for package in packages
        if documented.get(package) != _floor(f"demoplan.{package}")
    ]
    assert not wrong, "\n".join(wrong)
    assert set(documented) == set(packages), sorted(set(documented) ^ set(packages))


def test_the_floors_table_is_read() -> None:
    text = (
        "| floor | folders | owns |\n|---|---|---|\n"
        "| 0 | package root, `fileio/`, `documents/` | `x/` is not read here |\n"
        "| 6 | `commands/` | ... |\n\n## Next\n\n| 0 | `tight/` | |\n"
    )
    assert documented_floors(text) == {"fileio": 0, "documents": 0, "commands": 6}
