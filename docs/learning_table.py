"""Print docs/learning.md's table: what learning gives at the defaults (and with the
paper's reading) on the shipped examples and on robosuite's recordings.

    python docs/learning_table.py

Run from the repository root with demoplan installed (``pip install -e ".[dev]"``);
robosuite's demonstrations are fetched as the tests fetch them (PyPI, cached).
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # for tests.support.robosuite_data

from tests.support.robosuite_data import robosuite_demonstrations  # noqa: E402

from demoplan.learning import learn  # noqa: E402
from demoplan.documents.demonstrations import load_demonstrations  # noqa: E402
from demoplan.learning.settings import PAPER_SETTINGS, LearningSettings  # noqa: E402
from demoplan.model import Demonstration, TaskModel  # noqa: E402
from demoplan.segmentation.importing import import_recording  # noqa: E402


def describe(model: TaskModel) -> tuple[str, str, str]:
    """States (object → reference), constraints by object, precision."""
    objects = {s.id: s.object for s in model.states}
    states = ", ".join(
        f"{s.id} {s.object}" + (f"→{s.position.reference}" if s.position.reference else "")
        for s in model.states
    )
    pairs = sorted(
        {f"{objects[a.split('#')[0]]}<{objects[b.split('#')[0]]}" for a, b in model.constraints}
    )
    constraints = f"{len(model.constraints)}" + (f": {', '.join(pairs)}" if len(pairs) <= 4 else "")
    precision = "—"
    if model.precision is not None:
        precision = f"{model.precision[0] * 1000:.1f} mm"
    return states, constraints, precision


def main() -> None:
    logging.disable(logging.WARNING)
    examples = ROOT / "examples"
    files = robosuite_demonstrations()
    imported = {name: import_recording(path) for name, path in files.items()}
    cases: list[tuple[str, list[Demonstration], LearningSettings, str]] = [
        (
            "set_table (shipped)",
            load_demonstrations([examples / "set_table"]),
            LearningSettings(),
            "defaults",
        ),
        (
            "set_table (shipped)",
            load_demonstrations([examples / "set_table"]),
            PAPER_SETTINGS,
            "--paper",
        ),
        (
            "blocks (shipped)",
            load_demonstrations([examples / "blocks"]),
            LearningSettings(),
            "defaults",
        ),
        ("blocks (shipped)", load_demonstrations([examples / "blocks"]), PAPER_SETTINGS, "--paper"),
    ]
    for label, names in (
        ("robosuite PickPlace, 2 Sawyer", ["SawyerPickPlace"]),
        ("robosuite PickPlace, + Panda", ["SawyerPickPlace", "PickPlace"]),
        ("robosuite NutAssembly, 2 Sawyer", ["SawyerNutAssembly"]),
        ("robosuite NutAssembly, + Panda", ["SawyerNutAssembly", "NutAssembly"]),
        ("robosuite Stack, 2 Sawyer", ["SawyerStack"]),
        ("robosuite Stack, + Panda", ["SawyerStack", "Stack"]),
    ):
        demos = [d for name in names for d in imported[name]]
        cases.append((label, demos, LearningSettings(), "defaults"))
    print("| data | settings | states | constraints | precision |")
    print("|---|---|---|---|---|")
    for label, demos, settings, how in cases:
        states, constraints, precision = describe(learn(demos, settings=settings))
        print(f"| {label} | {how} | {states} | {constraints} | {precision} |")


if __name__ == "__main__":
    main()
