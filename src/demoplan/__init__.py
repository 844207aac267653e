"""demoplan: learn pick-and-place task models from a few human demonstrations.

Implements "Learning Task Models from Multiple Human Demonstrations": state
generation (§IV.A), task generalization (§IV.B), planning and execution.
"""

from demoplan.demonstrations import load_demonstrations
from demoplan.errors import DemoplanError, InputError, NoPlanError
from demoplan.learning import TaskModelLearner, learn
from demoplan.model import Demonstration, Pose, State, Step, TaskModel
from demoplan.modelfile import load_model, save_model

__all__ = [
    "Demonstration",
    "DemoplanError",
    "InputError",
    "NoPlanError",
    "Pose",
    "State",
    "Step",
    "TaskModel",
    "TaskModelLearner",
    "learn",
    "load_demonstrations",
    "load_model",
    "save_model",
]

__version__ = "0.1.0"
