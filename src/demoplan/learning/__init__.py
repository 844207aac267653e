"""The learning stage: demonstrations in, a task model out (paper §IV.A–B).

- demonstration files (docs/formats.md) are read by
  :mod:`demoplan.documents.demonstrations`, below learning and segmentation.
- :mod:`demoplan.learning.states` and :mod:`demoplan.learning.clustering` —
  state generation (§IV.A, eq. 1–2).
- :mod:`demoplan.learning.constraints` — task generalization (§IV.B).
- :mod:`demoplan.learning.settings` — :class:`LearningSettings`, the one
  settings value from ``learn``'s options to the model file.
- :mod:`demoplan.learning.learner` — :class:`TaskModelLearner`, :func:`learn`,
  :func:`update`.
- :mod:`demoplan.learning.modelfile` — model files (docs/formats.md ``demoplan/model-1``).
- :mod:`demoplan.learning.tables` — the paper's tables as text rows.

Names are imported on first use, so the value types (:mod:`demoplan.model`)
can name this package's settings without loading NumPy.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

_EXPORTS = {
    "TaskModelLearner": "demoplan.learning.learner",
    "learn": "demoplan.learning.learner",
    "update": "demoplan.learning.learner",
    "LearningSettings": "demoplan.learning.settings",
    "check_demonstrations": "demoplan.documents.demonstrations",
    "demonstration_to_dict": "demoplan.documents.demonstrations",
    "demonstrations_from_document": "demoplan.documents.demonstrations",
    "demonstrations_from_path": "demoplan.documents.demonstrations",
    "load_demonstrations": "demoplan.documents.demonstrations",
    "load_object_geometry": "demoplan.documents.demonstrations",
    "label_key": "demoplan.learning.constraints",
    "visit_sequence": "demoplan.learning.constraints",
    "load_model": "demoplan.learning.modelfile",
    "model_from_dict": "demoplan.learning.modelfile",
    "model_to_dict": "demoplan.learning.modelfile",
    "save_model": "demoplan.learning.modelfile",
}

__all__ = [
    "LearningSettings",
    "TaskModelLearner",
    "check_demonstrations",
    "demonstration_to_dict",
    "demonstrations_from_document",
    "demonstrations_from_path",
    "label_key",
    "learn",
    "load_demonstrations",
    "load_model",
    "load_object_geometry",
    "model_from_dict",
    "model_to_dict",
    "save_model",
    "update",
    "visit_sequence",
]

if TYPE_CHECKING:
    from demoplan.documents.demonstrations import (
        check_demonstrations,
        demonstration_to_dict,
        demonstrations_from_document,
        demonstrations_from_path,
        load_demonstrations,
        load_object_geometry,
    )
    from demoplan.learning.constraints import label_key, visit_sequence
    from demoplan.learning.learner import TaskModelLearner, learn, update
    from demoplan.learning.modelfile import load_model, model_from_dict, model_to_dict, save_model
    from demoplan.learning.settings import LearningSettings


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'demoplan.learning' has no attribute {name!r}")
