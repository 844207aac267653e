"""Learning a model from the work folder's demonstrations, and planning with
it (``/api/learn``, ``/api/plan``)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from fastapi import APIRouter

from demoplan.errors import DemoplanError, InputError
from demoplan.studio.requests import LearnRequest, PlanRequest
from demoplan.studio.routes.depends import Folder, Runs, logged_warnings, model_path, scene_of
from demoplan.studio.views import LEARN_TABLE, PLAN_START
from demoplan.studio.workfolder import FileConflictError, FileMissingError, WorkFolder

__all__ = ["router"]

router = APIRouter()


@router.post("/api/learn")
def learn(body: LearnRequest, folder: Folder, jobs: Runs) -> dict[str, Any]:
    from demoplan.commands.learning import learn_files

    paths, output = _learn_files(body, folder)
    scene = scene_of(body.scene, LEARN_TABLE) if body.scene is not None else None
    with jobs.working(), logged_warnings() as logged:
        model = learn_files(paths, output=output).model
    with jobs.working():
        targets = _targets(model, scene)
    return _learned(body.output, model, targets, logged, folder)


@router.post("/api/plan")
def plan(body: PlanRequest, folder: Folder, jobs: Runs) -> dict[str, Any]:
    from demoplan.commands.planning import plan as plan_task
    from demoplan.scenes.plan import SceneLimitReachedError, SceneNoPlanError
    from demoplan.studio.views import no_plan_json, plan_json

    model = model_path(folder, body.model)
    scene = scene_of(body.scene, PLAN_START)
    try:
        with jobs.working():
            result = plan_task(model, scene, clutter=body.clutter)
    except (SceneNoPlanError, SceneLimitReachedError) as failure:
        return no_plan_json(failure)
    return plan_json(result)


def _learn_files(body: LearnRequest, folder: WorkFolder) -> tuple[list[Path], Path]:
    """The demonstrations to learn from (all of the work folder's by default)
    and the model file to write (a new one, or a model file replaced)."""
    names = body.files if body.files is not None else folder.listing()["demonstrations"]
    if not names:
        raise InputError("the work folder holds no demonstrations; save one first", field="files")
    paths = [folder.path(name, f"files[{k}]") for k, name in enumerate(names)]
    for name, path in zip(names, paths, strict=True):
        if not path.is_file():
            raise FileMissingError(f"files: no file {name!r} in the work folder")
    output = folder.path(body.output, "output")
    if output.exists():
        kind = folder.kind(folder.read(body.output, "output"), body.output)
        if kind != "models":
            raise FileConflictError(
                f"output: {body.output} is not a model file; a model's file name expected"
            )
    return paths, output


def _targets(model: Any, scene: Any) -> list[dict[str, Any]]:
    """The learned targets resolved in ``scene`` (the table as the page shows
    it, landmarks where they stand now); with no scene, or one that does not
    hold the model's objects, in the first demonstration's end."""
    from demoplan.studio.views import targets_json

    if scene is not None:
        try:
            return targets_json(model, scene)
        except DemoplanError:
            pass
    return targets_json(model, None)


def _learned(
    name: str, model: Any, targets: list[dict[str, Any]], logged: list[str], folder: WorkFolder
) -> dict[str, Any]:
    """The answer: the model as the page shows it, its targets, and the
    warnings as ``learn`` prints them — the model's diagnostics, then what was
    logged, files named as in the work folder."""
    from demoplan.learning.tables import diagnostic_lines
    from demoplan.studio.views import model_json

    where = f"{folder.root}{os.sep}"
    warnings = [f"warning: {line}" for line in diagnostic_lines(model)]
    warnings += [line.replace(where, "") for line in dict.fromkeys(logged)]
    return {"model": name, **model_json(model), "targets": targets, "warnings": warnings}
