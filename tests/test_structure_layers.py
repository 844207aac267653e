"""The command line only parses options and renders what the command layer
(demoplan.commands) returns: no call from a CLI module into a pipeline stage
(learning, planning, scenes, execution, segmentation, perception,
experiments) other than the renderers and option parsers named here."""

from __future__ import annotations

import ast
from pathlib import Path

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
    "demoplan.learning.demonstrations.demonstration_to_dict",
    "demoplan.planning.problem.format_plan",
    "demoplan.planning.problem.optimality_line",
    "demoplan.planning.problem.plan_to_json",
    # options parsed into the values the command layer takes
    "demoplan.execution.faults.parse_faults",
    "demoplan.segmentation.types.parse_object_patterns",
    "demoplan.segmentation.settings.settings_help",
    "demoplan.scenes.geometry.GeometrySettings",
    "demoplan.planning.budget.Budget",
}


def _stage_calls(path: Path) -> list[str]:
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
        if any(
            target == allowed or target.startswith(allowed + ".")
            for allowed in RENDERING_AND_PARSING
        ):
            continue
        found.append(f"{path.name}:{node.lineno}: {target}")
    return found


def test_cli_modules_call_the_command_layer_not_the_stages() -> None:
    calls = [call for path in sorted(CLI.glob("*.py")) for call in _stage_calls(path)]
    assert not calls, "work inside CLI commands:\n" + "\n".join(calls)


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
