"""Render the segmentation figures of docs/segmentation.md from robosuite's recordings.

From the repository root::

    python docs/images/segmentation_figures.py

fetches robosuite's demonstrations if they are not cached
(``tests/support/robosuite_data.py``) and writes ``segmentation-nutassembly.png`` and
``segmentation-pickplace.png`` next to this file.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

HERE = Path(__file__).resolve().parent
sys.path.insert(1, str(HERE.parent.parent))  # the repository root, for tests.support.robosuite_data

from tests.support.robosuite_data import robosuite_demonstrations  # noqa: E402

from demoplan.plotting.segmentation import plot_segmentation  # noqa: E402
from demoplan.segmentation.importing import import_recording_details  # noqa: E402

FIGURES = (
    ("SawyerNutAssembly", "demo_2", "segmentation-nutassembly.png"),
    ("SawyerPickPlace", "demo_1", "segmentation-pickplace.png"),
)


def main() -> None:
    files = robosuite_demonstrations()
    for recording, key, name in FIGURES:
        item = next(i for i in import_recording_details(files[recording]) if i.key == key)
        found = item.segmentation
        counts = f"{len(found.moves)} steps, {len(found.nudges)} nudges, {len(found.pushes)} pushes"
        plot_segmentation(
            found,
            HERE / name,
            heights=True,
            dpi=80,
            title=f"robosuite {recording} {key}: speed and height per object ({counts})",
        )
        print(HERE / name)


if __name__ == "__main__":
    main()
