"""Learning from files, as ``demoplan learn`` does it: read the demonstrations
(and pose streams, segmented on the way), the teacher's constraints, learn or
update a model within a time budget, and write it — one function the command
line only renders (:func:`learn_files`).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.budget import LEARNING_TIMEOUT, time_budget
from demoplan.commands.inputs import load_inputs
from demoplan.errors import InputError
from demoplan.fileio import locked_for_update, read_input_text, refuse_overwriting_inputs
from demoplan.learning.changes import ModelChanges, model_changes
from demoplan.learning.learner import learn, update
from demoplan.learning.modelfile import load_model, save_model
from demoplan.learning.settings import LearningSettings, paper_overrides
from demoplan.model import Demonstration, TaskModel
from demoplan.scenes.preview import ScenePreview

if TYPE_CHECKING:
    from demoplan.segmentation.streams import StreamOptions

__all__ = [
    "LearnedFiles",
    "ShownModel",
    "ShownScene",
    "learn_files",
    "learn_model",
    "read_requirements",
    "show",
]


@dataclass(frozen=True, slots=True)
class LearnedFiles:
    """What :func:`learn_files` did: the model, what an update changed, and
    the file written (None: nothing was written)."""

    model: TaskModel
    changes: ModelChanges | None
    written: Path | None


def learn_model(
    sources: Iterable[Demonstration | str | Path],
    *,
    require: Sequence[str] = (),
    settings: LearningSettings | None = None,
) -> TaskModel:
    """A task model from demonstrations (paper §IV.A–B): objects, or files and
    folders (demonstration files, pose streams — CSV, ROS 2 bags — segmented on
    the way), in the order given. Default settings unless ``settings``;
    ``require``: teacher constraints such as ``"red<green"``."""
    demonstrations: list[Demonstration] = []
    for source in sources:
        if isinstance(source, Demonstration):
            demonstrations.append(source)
        else:
            demonstrations += load_inputs([source])
    return learn(demonstrations, require=require, settings=settings)


def read_requirements(path: Path) -> list[str]:
    """Teacher constraints from a file, one ``A<B`` per line; ``#`` starts a
    comment where it follows whitespace (``C#2`` is a visit label)."""
    lines = read_input_text(path, "a requirements file (one 'A<B' per line)").splitlines()
    kept = (re.split(r"(?:^|\s)#", line, maxsplit=1)[0].strip() for line in lines)
    return [line for line in kept if line]


def learn_files(
    inputs: Sequence[Path],
    *,
    output: Path | None = None,
    update_path: Path | None = None,
    require: Sequence[str] = (),
    require_file: Path | None = None,
    paper: bool = False,
    overrides: Mapping[str, Any] | None = None,
    stream: StreamOptions | None = None,
    timeout: float = LEARNING_TIMEOUT,
    working: Callable[[], AbstractContextManager[object]] | None = None,
) -> LearnedFiles:
    """Learn a model from ``inputs`` (demonstration files or folders, pose
    streams), or with ``update_path`` extend that model with them (written
    back unless ``output``); ``paper``: the paper's fixed thresholds, then
    ``overrides`` (settings by name); ``working``: a progress display around
    the work. Nothing is written when neither ``output`` nor ``update_path``
    is given. Two updates of one model at once both land (the second waits).
    ``stream``: how pose streams are read
    (:func:`demoplan.commands.inputs.load_inputs`)."""
    objects_file = None if stream is None else stream.objects_file
    target = output or update_path
    if target is not None:
        refuse_overwriting_inputs(
            target, [*inputs, *([objects_file] if objects_file is not None else [])]
        )
    settings: dict[str, Any] = paper_overrides() if paper else {}
    settings.update(overrides or {})
    requirements = list(require)
    from_file = read_requirements(require_file) if require_file is not None else []
    requirements += from_file
    with (
        locked_for_update(update_path) if update_path is not None else nullcontext(),
        time_budget(
            timeout,
            f"learning stopped at its time budget (--timeout {timeout:g} s){{where}}; give it more "
            "time, or for many scattered placements cap the clusters (--max-clusters 5)",
        ),
        working() if working is not None else nullcontext(),
    ):
        try:
            new = load_inputs(inputs, stream=stream)
            changes = None
            if update_path is not None:
                previous = load_model(update_path)
                model = update(previous, new, require=requirements, settings=settings)
                changes = model_changes(previous, model)
            else:
                chosen = LearningSettings(require=tuple(dict.fromkeys(requirements)), **settings)
                model = learn(new, settings=chosen)
        except InputError as exc:
            # A requirement read from --require-file: say which file it came from.
            if exc.field == "require" and any(repr(t) in str(exc) for t in from_file):
                raise InputError(str(exc), source=str(require_file)) from None
            raise
        if target is not None:
            save_model(model, target)
    return LearnedFiles(model, changes, target)


@dataclass(frozen=True, slots=True)
class ShownModel:
    """``show MODEL``: the model read (and the figure written, if asked)."""

    model: TaskModel
    figure: Path | None = None


@dataclass(frozen=True, slots=True)
class ShownScene:
    """``show SCENE``: the scene as the planner will see it (and the figure written)."""

    preview: ScenePreview
    figure: Path | None = None


def show(
    path: Path, *, model: Path | None = None, plot: Path | None = None
) -> ShownModel | ShownScene:
    """A model file (its tables; ``plot``: its demonstrations, each step marked
    with its learned state), or a scene file as the planner will see it —
    where each object stands, which grasps its neighbours block, the landmarks
    and free space (``model``: sizes the scene omits; ``plot``: from above)."""
    from demoplan.fileio import check_format, display_path, read_document
    from demoplan.learning.modelfile import model_from_dict
    from demoplan.plotting.figures import save_demonstrations, save_scene_targets
    from demoplan.plotting.output import check_figure_path, figure_errors
    from demoplan.scenes.landmarks import complete_scene
    from demoplan.scenes.preview import preview_scene
    from demoplan.scenes.scene import scene_from_document, scene_of_objects_file

    document = read_document(path)
    kind, _ = check_format(document, {"model", "scene", "objects"}, display_path(path))
    if kind == "model" and model is not None:
        raise InputError(f"--model is for a scene; {path} is a model", field="--model")
    if plot is not None:
        check_figure_path(plot, "--plot")
    if kind == "model":
        task = model_from_dict(document, str(path))
        if plot is not None:
            with figure_errors(plot):
                save_demonstrations(task, plot, display_path(path))
        return ShownModel(task, plot)
    if kind == "objects":
        document = scene_of_objects_file(document, str(path))
    scene = scene_from_document(document, str(path))
    if model is not None:
        scene = complete_scene(scene, load_model(model))
    preview = preview_scene(scene)
    if plot is not None:
        with figure_errors(plot):
            title = f"{display_path(path)}: the scene before planning"
            save_scene_targets(scene, preview.problem, "", plot, title)
    return ShownScene(preview, plot)
