"""Regenerate the arm's figures of docs/execution.md ("The arm").

Run from anywhere: ``python docs/images/execution/make_figures.py``. It learns
the paper's two experiments (``--paper``), runs them on the arm with
``demoplan run … --sim arm --frames DIR`` in a temporary folder, and writes
into this folder:

- ``arm-set-table.png``: Experiment 1, the frame after the arm took the knife
  (a 5 mm part the floating hand's pads cannot lift);
- ``arm-storyboard.png``: Experiment 2's storyboard, the pyramid built by the arm.

Needs the ``sim`` and ``plot`` extras (``pip install -e ".[all]"``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]


def demoplan(*args: str) -> str:
    """Run ``demoplan ARGS`` from the repository root; its standard output."""
    command = [sys.executable, "-m", "demoplan", *args]
    print("$ demoplan", " ".join(args), flush=True)
    env = {**os.environ, "MPLBACKEND": "Agg", "COLUMNS": "200"}
    done = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        sys.exit(f"demoplan {args[0]} exited {done.returncode}:\n{done.stdout}{done.stderr}")
    return done.stdout


def frame_after(frames: Path, run_output: str, action: str) -> Path:
    """The frame written after the first step whose action starts with ``action``."""
    for line in run_output.splitlines():
        cells = [c.strip() for c in line.split("│") if c.strip()]
        if len(cells) >= 2 and cells[0].isdigit() and cells[1].startswith(action):
            return frames / f"frame-{int(cells[0]):04d}.png"
    sys.exit(f"no step {action!r} in the run")


def main() -> None:
    with tempfile.TemporaryDirectory() as scratch:
        tmp = Path(scratch)
        table = tmp / "set-table.json"
        blocks = tmp / "blocks.json"
        demoplan("learn", "examples/set_table", "--paper", "-o", str(table))
        demoplan("learn", "examples/blocks/demonstrations.json", "--paper", "-o", str(blocks))
        frames = tmp / "set-table"
        output = demoplan(
            "run",
            str(table),
            "examples/scenes/set-table-cluttered.json",
            "--sim",
            "arm",
            "--frames",
            str(frames),
        )
        shutil.copyfile(frame_after(frames, output, "GRASP knife"), HERE / "arm-set-table.png")
        frames = tmp / "blocks"
        demoplan(
            "run",
            str(blocks),
            "examples/scenes/pyramid-fig4.json",
            "--sim",
            "arm",
            "--frames",
            str(frames),
        )
        shutil.copyfile(frames / "storyboard.png", HERE / "arm-storyboard.png")
    for name in ("arm-set-table.png", "arm-storyboard.png"):
        print("wrote", (HERE / name).relative_to(ROOT))


if __name__ == "__main__":
    main()
