"""Task models learned from robosuite's own recordings, for ``--sim robosuite:ENV``
(tests/execution/test_robosuite_run.py, benchmarks/robosuite_tasks.py).

Each environment's model is learned at default settings from the recordings in
robosuite's source distributions (:mod:`tests.support.robosuite_data`): the Panda's
(1.0) and the Sawyer's (0.3) of the same task, three demonstrations each. A
single-object environment (``NutAssemblySquare``) learns from the same
recordings watching that object only: the other objects are left out of the
imported demonstration files, as if they had not been there.
"""

from __future__ import annotations

import json
from pathlib import Path

from demoplan.commands.learning import learn_model
from demoplan.commands.recordings import import_recording
from demoplan.model import TaskModel
from tests.support.robosuite_data import robosuite_demonstrations

__all__ = ["RECORDINGS", "task_model"]

RECORDINGS: dict[str, tuple[tuple[str, ...], tuple[str, ...] | None]] = {
    # environment: (recordings learned from, the objects kept; None: all)
    "Stack": (("Stack", "SawyerStack"), None),
    "NutAssembly": (("NutAssembly", "SawyerNutAssembly"), None),
    "NutAssemblySquare": (("NutAssembly", "SawyerNutAssembly"), ("SquareNut",)),
    "NutAssemblyRound": (("NutAssembly", "SawyerNutAssembly"), ("RoundNut",)),
    "PickPlaceCan": (("PickPlace", "SawyerPickPlace"), ("Can",)),
    "PickPlace": (("PickPlace", "SawyerPickPlace"), None),
}


def _keep_only(path: Path, objects: tuple[str, ...]) -> None:
    """Rewrite the demonstration file at ``path`` with only ``objects``."""
    document = json.loads(path.read_text())
    for part in ("objects", "initial"):  # a mesh object has no "objects" entry
        kept = {k: v for k, v in document.get(part, {}).items() if k in objects}
        if kept:
            document[part] = kept
        else:
            document.pop(part, None)
    document["steps"] = [s for s in document["steps"] if s["object"] in objects]
    path.write_text(json.dumps(document))


def task_model(env: str, folder: Path) -> TaskModel:
    """The model of robosuite's ``env`` learned from its recordings (imported into ``folder``)."""
    names, objects = RECORDINGS[env]
    recordings = robosuite_demonstrations()
    files: list[Path] = []
    for name in names:
        imported = import_recording(recordings[name], folder / name)
        files += sorted(imported.files.values())
    if objects is not None:
        for path in files:
            _keep_only(path, objects)
    return learn_model(files)
