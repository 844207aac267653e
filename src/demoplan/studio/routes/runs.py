"""Runs, each in a process of its own (:mod:`demoplan.studio.jobs`), the media
an arm run writes, and the run that ended last (``/api/runs``,
``/api/media``, ``/api/last-run``)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from fastapi import APIRouter
from fastapi.responses import FileResponse

from demoplan.errors import DemoplanError, InputError
from demoplan.studio.requests import RunRequest
from demoplan.studio.routes.depends import Folder, Runs, model_path, one_line, scene_of
from demoplan.studio.views import PLAN_START
from demoplan.studio.workfolder import FileMissingError, WorkFolder

__all__ = ["MEDIA_SUFFIXES", "router"]

MEDIA_SUFFIXES = {".mp4": "video/mp4", ".png": "image/png", ".svg": "image/svg+xml"}

router = APIRouter()


@router.post("/api/runs", status_code=202)
def start_run(body: RunRequest, folder: Folder, jobs: Runs) -> dict[str, str]:
    model = model_path(folder, body.model)
    _check_run(body)

    def order(run_id: str) -> dict[str, Any]:
        """What the run's process is told (demoplan.studio.worker): the
        request as checked here; an arm run's video named by the run."""
        video = f"run-{run_id}.mp4" if body.sim == "arm" else None
        return {
            "model": str(model),
            "scene": body.scene,
            "sim": body.sim,
            "faults": body.faults,
            "seed": body.seed,
            "clutter": body.clutter,
            "video": str(folder.root / video) if video else None,
            "media": f"/api/media/{video}" if video else None,
        }

    return {"run": jobs.start(order).id}


@router.get("/api/runs/{run_id}")
def run_state(run_id: str, jobs: Runs) -> dict[str, Any]:
    return jobs.get(run_id).to_json()


@router.delete("/api/runs/{run_id}")
def cancel_run(run_id: str, jobs: Runs) -> dict[str, Any]:
    return jobs.cancel(run_id).to_json()


@router.get("/api/media/{name}")
def media(name: str, folder: Folder) -> FileResponse:
    path = _media_path(folder, name)
    return FileResponse(path, media_type=MEDIA_SUFFIXES[path.suffix])


@router.get("/api/last-run")
def last_run(jobs: Runs) -> dict[str, Any] | None:
    """The run that ended last in the work folder, for a page opened again."""
    from demoplan.studio.layouts import layout_of_scene

    record = jobs.last()
    if record is None:
        return None
    try:
        layout = layout_of_scene(scene_of(record["scene"], PLAN_START))
    except DemoplanError as exc:
        raise FileMissingError(
            f"run: the last run's scene cannot be drawn ({one_line(str(exc))})"
        ) from None
    return record | {"layout": layout}


def _check_run(body: RunRequest) -> None:
    """The scene, the faults and the simulator refused here, before a process
    starts (the run's process reads them again)."""
    from demoplan.execution.faults import parse_faults

    scene_of(body.scene, PLAN_START)
    try:
        parse_faults(body.faults or None)
    except DemoplanError as exc:
        raise InputError(str(exc), field="faults") from None
    if body.sim == "arm":
        from importlib.util import find_spec

        if find_spec("mujoco") is None:
            raise InputError("the arm needs MuJoCo (pip install 'demoplan[sim]')", field="sim")


def _media_path(folder: WorkFolder, name: str) -> Path:
    if not re.fullmatch(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,79}", name) or ".." in name:
        raise InputError(f"{name!r} is not a media file name", field="name")
    suffix = Path(name).suffix
    if suffix not in MEDIA_SUFFIXES:
        raise InputError(
            f"{name!r}: one of {', '.join(sorted(MEDIA_SUFFIXES))} expected", field="name"
        )
    path = folder.root / name
    if path.is_symlink() or not path.is_file() or path.resolve().parent != folder.root:
        raise FileMissingError(f"name: no media file {name!r} in the work folder")
    return path
