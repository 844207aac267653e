"""Move flat test files to the folder that mirrors what they test
(tests/README.md), with ``git mv``, and fix every reference to them.

    python -m tests.support.relayout            # the moves below, where a file is still flat
    python -m tests.support.relayout --dry-run  # only say what it would move
    python -m tests.support.relayout --helpers  # only the helper modules

:data:`FOLDERS` says where each flat ``tests/test_NAME.py`` goes (``""``: it
stays, a test of a module at the package's root) and :data:`HELPERS` which
helper modules belong in tests/support. A file added flat later gets its entry
here and the script run again. Besides the moves it rewrites, in every file
git tracks: ``tests.NAME`` and ``from tests import NAME`` (imports,
``python -m``) and ``tests/NAME.py``
(node ids, docs), and in a moved file the ``Path(__file__)`` steps up to the
repository, one more now that the file lies one folder deeper.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

E2E = "e2e"
FOLDERS: dict[str, str] = {
    # the package's root modules (api.py, fileio.py, rotations.py) and the tree as a whole
    "test_api": "",
    "test_files": "fileio",
    "test_rotations": "",
    "test_clock": "",
    "test_structure": "",
    "test_structure_layers": "",
    # whole commands, documents and the repository
    "test_docs_blocks": E2E,
    "test_docs_generated": E2E,
    "test_docs_shell": E2E,
    "test_readme": E2E,
    "test_self_contained": E2E,
    "test_breakfast": E2E,
    "test_numbering": E2E,
    "test_interrupt": "frontends",
    "test_edge_cases": E2E,
    "test_fixed_problems": "support",
    "test_cli": "cli",
    "test_cli_tables": "cli",
    "test_launcher": "cli",
    "test_commands": "commands",
    "test_masses": "documents",
    "test_units_sanity": "documents",
    "test_evaluate": "evaluation",
    "test_arm": "execution",
    "test_arm_flat": "execution",
    "test_arm_layouts": "execution",
    "test_arm_mass": "execution",
    "test_behaviour_tree": "execution",
    "test_drops": "execution",
    "test_execution": "execution",
    "test_landmark_physics": "execution",
    "test_physics": "execution",
    "test_retries": "execution",
    "test_robosuite_run": "execution",
    "test_robosuite_evaluate": "evaluation",
    "test_robosuite_pickplace": "execution",
    "test_region_goals": "learning",
    "test_perception_budget": "perception",
    "test_plan_shortening": "planning",
    "test_preparations": "scenes",
    "test_studio_modules": "studio",
    "test_stable_names": "execution",
    "test_truthful_runs": "execution",
    "test_experiments": "experiments",
    "test_figure_labels": "experiments",
    "test_changes": "learning",
    "test_clustering": "learning",
    "test_constraint_graph": "learning",
    "test_constraint_support": "learning",
    "test_constraints": "learning",
    "test_learn_files": "learning",
    "test_learning": "learning",
    "test_learning_families": "learning",
    "test_learning_real": "learning",
    "test_orientation_follows": "learning",
    "test_rule_edges": "learning",
    "test_states": "learning",
    "test_calibration": "perception",
    "test_hough": "perception",
    "test_perception": "perception",
    "test_perception_false_blocks": "perception",
    "test_perception_families": "perception",
    "test_perception_fits": "perception",
    "test_perception_instances": "perception",
    "test_perception_overlay": "perception",
    "test_perception_photos": "perception",
    "test_perception_real_photos": "perception",
    "test_perception_regions": "perception",
    "test_perception_scale": "perception",
    "test_perception_sequence": "perception",
    "test_order_semantics": "planning",
    "test_parts": "planning",
    "test_pddl": "planning",
    "test_pddl_roles": "planning",
    "test_planning_limits": "planning",
    "test_plateau": "planning",
    "test_problem_xml": "planning",
    "test_search": "planning",
    "test_solve_cli": "planning",
    "test_tight": "planning",
    "test_colours": "plotting",
    "test_plotting": "plotting",
    "test_roles_display": "plotting",
    "test_free_space": "scenes",
    "test_geometry_pairs": "scenes",
    "test_identical_objects": "scenes",
    "test_names": "scenes",
    "test_objects_file": "scenes",
    "test_plan_time_checks": "scenes",
    "test_prepared": "scenes",
    "test_scene_geometry": "scenes",
    "test_scene_plan": "scenes",
    "test_show_scene": "scenes",
    "test_import": "segmentation",
    "test_real_recordings": "segmentation",
    "test_segment_cli": "segmentation",
    "test_segmentation": "segmentation",
    "test_segmentation_families": "segmentation",
    "test_segmentation_plot": "segmentation",
    "test_stream_inputs": "segmentation",
    "test_tf_tree": "segmentation",
    "test_studio_api": "studio",
    "test_studio_browser": "studio",
    "test_studio_objects": "studio",
    "test_studio_own_objects_browser": "studio",
    "test_studio_run_view": "studio",
}

HELPERS = (
    "arm_layouts",
    "background",
    "breakfast",
    "browser",
    "docs_blocks",
    "fixture_families",
    "helpers",
    "identical_families",
    "learning_families",
    "lunch_box",
    "planning_families",
    "robosuite_data",
    "robosuite_tasks",
    "scene_checker",
    "shared_experiments",
    "studio_browser",
    "table_for_two",
)
"""Helper modules (not tests) shared by tests, benchmarks and docs: tests/support."""

SCRIPTS = (".ci/",)  # CI's scripts, without a suffix
TEXT = (".py", ".md", ".toml", ".yml", ".yaml", ".cfg", ".ini", ".txt", ".sh", ".html", ".js")
_DEEPER = (  # a moved file's way up to the repository: one folder more
    (r"Path\(__file__\)\.resolve\(\)\.parents\[1\]", "Path(__file__).resolve().parents[2]"),
    (r"Path\(__file__\)\.parents\[1\]", "Path(__file__).parents[2]"),
    (r"Path\(__file__\)\.resolve\(\)\.parent\.parent", "Path(__file__).resolve().parents[2]"),
    (r"Path\(__file__\)\.parent\.parent", "Path(__file__).parents[2]"),
    (r"Path\(__file__\)\.parent / \"data\"", 'Path(__file__).parents[1] / "data"'),
)


def moves(helpers_only: bool = False) -> dict[str, str]:
    """Each flat module still to move (``tests/NAME.py``) and its new folder."""
    wanted = {name: "support" for name in HELPERS}
    if not helpers_only:
        wanted |= {name: folder for name, folder in FOLDERS.items() if folder}
    return {name: f for name, f in wanted.items() if (ROOT / "tests" / f"{name}.py").exists()}


def _tracked() -> list[Path]:
    listed = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
    ).stdout.decode()
    return [
        ROOT / name
        for name in listed.split("\0")
        if name.endswith(TEXT) or name.startswith(SCRIPTS)
    ]


def rewritten(text: str, planned: dict[str, str]) -> str:
    """``text`` with every module and path of ``planned`` at its new place."""
    for name, folder in planned.items():
        text = re.sub(rf"\btests\.{name}\b", f"tests.{folder}.{name}", text)
        text = re.sub(
            rf"^(\s*)from tests import {name}$",
            rf"\1from tests.{folder} import {name}",
            text,
            flags=re.M,
        )
        text = re.sub(rf"(?<![\w/.-])tests/{name}\.py\b", f"tests/{folder}/{name}.py", text)
    return text


def main(argv: list[str]) -> int:
    planned = moves(helpers_only="--helpers" in argv)
    for name, folder in sorted(planned.items()):
        print(f"tests/{name}.py -> tests/{folder}/{name}.py")
    if "--dry-run" in argv or not planned:
        return 0
    for folder in sorted(set(planned.values())):
        package = ROOT / "tests" / folder / "__init__.py"
        if not package.exists():
            package.parent.mkdir(exist_ok=True)
            package.write_text("")
            subprocess.run(["git", "add", str(package)], cwd=ROOT, check=True)
    for name, folder in planned.items():
        subprocess.run(
            ["git", "mv", f"tests/{name}.py", f"tests/{folder}/{name}.py"], cwd=ROOT, check=True
        )
    moved = {ROOT / "tests" / folder / f"{name}.py" for name, folder in planned.items()}
    for path in _tracked():
        if not path.exists():
            continue
        text = path.read_text(encoding="utf-8")
        new = rewritten(text, planned)
        if path in moved:
            for pattern, replacement in _DEEPER:
                new = re.sub(pattern, replacement, new)
        if new != text:
            path.write_text(new, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
