"""Regenerate docs/images/architecture/layers.png: demoplan's packages on their
floors, with an arrow for every package that imports another (function-level
imports included), read from the source with :mod:`ast` — the picture is the
import graph as it is, not as it was meant.

Run from anywhere: ``python docs/images/architecture/make_layers.py``.
Needs matplotlib (``pip install -e ".[plot]"``).
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

HERE = Path(__file__).resolve().parent
SRC = HERE.parents[2] / "src"
FLOORS: list[tuple[str, list[str]]] = [
    ("front ends", ["cli", "studio", "api"]),
    ("command layer", ["commands"]),
    ("report", ["experiments"]),
    ("execution", ["execution"]),
    ("figures", ["plotting"]),
    ("a task in a scene", ["scenes"]),
    ("the paper's stages", ["segmentation", "learning", "planning", "perception"]),
    ("shared floor", ["root", "documents"]),
]


VALUE_MODULES = {"demoplan.learning.settings"}
"""Values drawn on the shared floor, as tests/test_structure_layers.py counts
them: the task model records the settings it was learned with."""


def package_of(module: str) -> str:
    if module in VALUE_MODULES:
        return "root"
    parts = module.split(".")
    if len(parts) == 1 or (len(parts) == 2 and parts[1] not in _PACKAGES):
        return "api" if parts[-1] in ("api", "__main__", "launcher") else "root"
    return parts[1]


_PACKAGES = {p for _, row in FLOORS for p in row} - {"root", "api"}


def package_edges() -> dict[tuple[str, str], int]:
    modules = {}
    for path in (SRC / "demoplan").rglob("*.py"):
        name = ".".join(path.relative_to(SRC).with_suffix("").parts).removesuffix(".__init__")
        modules[name] = path
    edges: dict[tuple[str, str], int] = defaultdict(int)
    for name, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets: list[str] = []
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                for alias in node.names:
                    full = f"{node.module}.{alias.name}"
                    targets.append(full if full in modules else node.module)
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            for target in targets:
                if target in modules and len(name.split(".")) > 1:
                    a, b = package_of(name), package_of(target)
                    if a != b:
                        edges[(a, b)] += 1
    return edges


def main() -> None:
    centre: dict[str, tuple[float, float]] = {}
    figure, ax = plt.subplots(figsize=(9, 7.2))
    for row, (label, packages) in enumerate(FLOORS):
        y = len(FLOORS) - 1 - row
        ax.text(-0.3, y, label, ha="right", va="center", fontsize=9, color="0.35")
        for k, package in enumerate(packages):
            x = (k + 0.5) * 8 / len(packages)
            centre[package] = (x, y)
            ax.add_patch(
                FancyBboxPatch(
                    (x - 0.8, y - 0.22),
                    1.6,
                    0.44,
                    boxstyle="round,pad=0.02",
                    facecolor="#dde8f3",
                    edgecolor="#4a6f94",
                )
            )
            name = "root modules" if package == "root" else f"{package}/"
            ax.text(x, y, name if package != "api" else "api.py", ha="center", va="center")
    for (a, b), count in sorted(package_edges().items()):
        if a not in centre or b not in centre:
            continue
        (xa, ya), (xb, yb) = centre[a], centre[b]
        upward = yb > ya
        ax.add_patch(
            FancyArrowPatch(
                (xa, ya - 0.22 if yb < ya else ya),
                (xb, yb + 0.22 if yb < ya else yb),
                arrowstyle="-|>",
                mutation_scale=9,
                linewidth=0.4 + 0.15 * min(count, 10) ** 0.5,
                color="#c0392b" if upward else "0.45",
                alpha=0.7,
                connectionstyle="arc3,rad=0.08",
            )
        )
    ax.set_xlim(-2.6, 8.2)
    ax.set_ylim(-0.6, len(FLOORS) - 0.4)
    ax.axis("off")
    ax.set_title("demoplan's packages by floor; an arrow: imports (none runs up)", fontsize=10)
    figure.tight_layout()
    figure.savefig(HERE / "layers.png", dpi=110)


if __name__ == "__main__":
    main()
