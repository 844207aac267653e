"""What happens on the table: a user's own objects saved, landmarks moved,
drops and scrambles, demonstrations and scenes saved (``/api/objects``,
``/api/landmark``, ``/api/drop``, ``/api/scramble``, ``/api/demonstrations``,
``/api/scenes``)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from demoplan.studio.requests import (
    DemonstrationRequest,
    DropRequest,
    LandmarkRequest,
    ObjectsRequest,
    SceneRequest,
    ScrambleRequest,
)
from demoplan.studio.routes.depends import Folder
from demoplan.studio.workfolder import FileConflictError

__all__ = ["router"]

router = APIRouter()


@router.put("/api/objects/{name}")
def save_objects(name: str, body: ObjectsRequest, folder: Folder) -> dict[str, str]:
    from demoplan.commands.objects import objects_from_document
    from demoplan.studio.layouts import objects_document

    document = objects_document(body.layout)
    objects_from_document(document, "layout")  # as the studio reads it back
    if not folder.path(name).exists():
        return {"file": folder.create(document, name, "objects")}
    if not body.replace or folder.kind(folder.read(name), name) != "objects":
        how = "only an objects file is replaced" if body.replace else '"replace": true expected'
        raise FileConflictError(f"name: {name} exists in the work folder; {how}")
    folder.replace(document, name)
    return {"file": name}


@router.post("/api/landmark")
def move_landmark(body: LandmarkRequest) -> dict[str, Any]:
    from demoplan.studio.layouts import placed_landmark

    return placed_landmark(
        body.layout, body.landmark, (body.position[0], body.position[1]), body.yaw
    )


@router.post("/api/drop")
def drop(body: DropRequest) -> dict[str, Any]:
    from demoplan.studio.layouts import dropped_pose

    return dropped_pose(body.layout, body.object, (body.position[0], body.position[1]), body.yaw)


@router.post("/api/scramble")
def scramble(body: ScrambleRequest) -> dict[str, Any]:
    from demoplan.studio.layouts import scattered

    return scattered(body.layout, body.seed)


@router.post("/api/demonstrations", status_code=201)
def save_demonstration(body: DemonstrationRequest, folder: Folder) -> dict[str, str]:
    from demoplan.documents.demonstrations import demonstrations_from_document

    document = {"format": "demoplan/demonstration-1", **body.document}
    demonstrations_from_document(document, "document")  # as `learn` reads it
    return {"file": folder.create(document, body.name, "demonstration")}


@router.post("/api/scenes", status_code=201)
def save_scene(body: SceneRequest, folder: Folder) -> dict[str, str]:
    from demoplan.scenes.scene import scene_from_document

    document = {"format": "demoplan/scene-1", **body.document}
    scene_from_document(document, "document")  # as `plan` reads it
    return {"file": folder.create(document, body.name, "scene")}
