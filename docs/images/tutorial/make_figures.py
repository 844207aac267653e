"""Regenerate the figures of docs/tutorial.md ("Teach your own task").

Run from anywhere: ``python docs/images/tutorial/make_figures.py``. It runs the
tutorial's own commands on examples/kitting/ — with the model and the run's
frames in a temporary folder — and writes into this folder:

- ``demonstrations.png``: the three demonstrations from above and, under each,
  the constraints among its states (``demoplan learn`` has no ``--plot``; this
  one is drawn with ``demoplan.plotting.figures``, as ``demoplan experiments`` draws its
  own);
- ``scene.png``: ``demoplan show SCENE --model kit.json --plot``;
- ``plan.png``: ``demoplan plan kit.json SCENE --plot``;
- ``storyboard.png``: ``demoplan run kit.json SCENE --faults drop=0.3 --seed 0
  --frames DIR``, the storyboard it writes.

Needs matplotlib (``pip install -e ".[plot]"`` or ``".[all]"``).
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
DEMONSTRATIONS = "examples/kitting/demonstrations.json"
SCENE = "examples/kitting/scene-manual-on-motor.json"


def demoplan(*args: str) -> None:
    """Run ``demoplan ARGS`` from the repository root (paths as in the tutorial)."""
    command = [sys.executable, "-m", "demoplan", *args]
    print("$ demoplan", " ".join(args), flush=True)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    done = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        sys.exit(f"demoplan {args[0]} exited {done.returncode}:\n{done.stdout}{done.stderr}")


def demonstrations_figure(model_path: Path, out: Path) -> None:
    from demoplan import load_model
    from demoplan.plotting.figures import save_demonstrations

    save_demonstrations(load_model(model_path), out, "examples/kitting (the tray is a landmark)")
    print("wrote", out.relative_to(ROOT))


def main() -> None:
    with tempfile.TemporaryDirectory() as scratch:
        tmp = Path(scratch)
        kit = tmp / "kit.json"
        demoplan("learn", DEMONSTRATIONS, "-o", str(kit))
        demonstrations_figure(kit, HERE / "demonstrations.png")
        demoplan("show", SCENE, "--model", str(kit), "--plot", str(HERE / "scene.png"))
        demoplan("plan", str(kit), SCENE, "--plot", str(HERE / "plan.png"))
        frames = tmp / "run"
        demoplan(
            "run", str(kit), SCENE, "--faults", "drop=0.3", "--seed", "0", "--frames", str(frames)
        )
        shutil.copyfile(frames / "storyboard.png", HERE / "storyboard.png")
        print("wrote", (HERE / "storyboard.png").relative_to(ROOT))


if __name__ == "__main__":
    main()
