"""demoplan: learn pick-and-place task models from a few human demonstrations.

Implements "Learning Task Models from Multiple Human Demonstrations": state
generation (§IV.A), task generalization (§IV.B) and task planning (§IV.C).
Names are imported on first use, so ``demoplan solve`` does not pay for NumPy.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS = {
    "DemoplanError": "demoplan.errors",
    "InputError": "demoplan.errors",
    "NoPlanError": "demoplan.errors",
    "LimitReachedError": "demoplan.errors",
    "Demonstration": "demoplan.model",
    "Pose": "demoplan.model",
    "State": "demoplan.model",
    "Step": "demoplan.model",
    "TaskModel": "demoplan.model",
    "TaskModelLearner": "demoplan.learning.learner",
    "learn": "demoplan.api",
    "plan": "demoplan.api",
    "run": "demoplan.api",
    "LearningSettings": "demoplan.learning.settings",
    "PAPER_SETTINGS": "demoplan.learning.settings",
    "Scene": "demoplan.scenes.scene",
    "load_scene": "demoplan.scenes.scene",
    "ScenePlan": "demoplan.scenes.plan",
    "World": "demoplan.execution.world",
    "Observation": "demoplan.execution.world",
    "Faults": "demoplan.execution.faults",
    "RunReport": "demoplan.execution.executor",
    "load_demonstrations": "demoplan.documents.demonstrations",
    "load_inputs": "demoplan.commands.inputs",
    "load_model": "demoplan.learning.modelfile",
    "save_model": "demoplan.learning.modelfile",
    "Problem": "demoplan.planning.problem",
    "Plan": "demoplan.planning.problem",
    "load_problem": "demoplan.planning.xml",
    "solve": "demoplan.planning.search",
}

__all__ = [
    "PAPER_SETTINGS",
    "Demonstration",
    "DemoplanError",
    "Faults",
    "InputError",
    "LearningSettings",
    "LimitReachedError",
    "NoPlanError",
    "Observation",
    "Plan",
    "Pose",
    "Problem",
    "RunReport",
    "Scene",
    "ScenePlan",
    "State",
    "Step",
    "TaskModel",
    "TaskModelLearner",
    "World",
    "learn",
    "load_demonstrations",
    "load_inputs",
    "load_model",
    "load_problem",
    "load_scene",
    "plan",
    "run",
    "save_model",
    "solve",
]

if TYPE_CHECKING:
    from demoplan.api import learn, plan, run
    from demoplan.commands.inputs import load_inputs
    from demoplan.documents.demonstrations import load_demonstrations
    from demoplan.errors import DemoplanError, InputError, LimitReachedError, NoPlanError
    from demoplan.execution.faults import Faults
    from demoplan.execution.report import RunReport
    from demoplan.execution.world import Observation, World
    from demoplan.learning.learner import TaskModelLearner
    from demoplan.learning.modelfile import load_model, save_model
    from demoplan.learning.settings import PAPER_SETTINGS, LearningSettings
    from demoplan.model import Demonstration, Pose, State, Step, TaskModel
    from demoplan.planning.problem import Plan, Problem
    from demoplan.planning.search import solve
    from demoplan.planning.xml import load_problem
    from demoplan.scenes.plan import ScenePlan
    from demoplan.scenes.scene import Scene, load_scene


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'demoplan' has no attribute {name!r}")
