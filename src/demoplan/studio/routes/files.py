"""Templates, the work folder's files, and the template or file the Teach view
starts from (``/api/templates``, ``/api/files``, ``/api/source``)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Query

from demoplan.studio.requests import MAX_SEED, SourceBody
from demoplan.studio.routes.depends import Folder
from demoplan.studio.workfolder import FileMissingError, WorkFolder

__all__ = ["router"]

router = APIRouter()


@router.get("/api/templates")
def templates() -> dict[str, Any]:
    from demoplan.studio.layouts import TEMPLATES

    return {"templates": [{"id": t.id, "title": t.title} for t in TEMPLATES]}


@router.get("/api/templates/{template_id}")
def template(
    template_id: str, seed: int | None = Query(default=None, ge=0, le=MAX_SEED)
) -> dict[str, Any]:
    from demoplan.studio.layouts import template_layout

    return template_layout(template_id, seed)


@router.get("/api/files")
def files(folder: Folder) -> dict[str, Any]:
    listing = folder.listing()
    return {**listing, "latest_model": folder.latest_model(listing["models"])}


@router.get("/api/files/{name}")
def file(name: str, folder: Folder) -> dict[str, Any]:
    document = folder.read(name)
    answer: dict[str, Any] = {"name": name, "document": document}
    layout = _layout(folder.kind(document, name), document, name)
    if layout is not None:
        answer["layout"] = layout
    return answer


@router.get("/api/source")
def source(folder: Folder) -> dict[str, Any]:
    return {"source": folder.source()}


@router.put("/api/source")
def keep_source(body: SourceBody, folder: Folder) -> dict[str, Any]:
    _check_source(body, folder)
    folder.keep_source(body.kind, body.id)
    return {"source": folder.source()}


def _layout(kind: str | None, document: dict[str, Any], name: str) -> dict[str, Any] | None:
    """The table a demonstrations, scene or objects file starts from (None for a model)."""
    if kind == "demonstrations":
        from demoplan.documents.demonstrations import demonstrations_from_document
        from demoplan.studio.layouts import layout_of_demonstration

        demonstrations = demonstrations_from_document(document, name)
        return layout_of_demonstration(demonstrations[0], demonstrations)
    if kind == "scenes":
        from demoplan.scenes.scene import scene_from_document
        from demoplan.studio.layouts import layout_of_scene

        return layout_of_scene(scene_from_document(document, name))
    if kind == "objects":
        from demoplan.commands.objects import objects_from_document
        from demoplan.studio.layouts import layout_of_objects

        return layout_of_objects(objects_from_document(document, name), name)
    return None


def _check_source(body: SourceBody, folder: WorkFolder) -> None:
    """A template that exists, or a file of the work folder (404 otherwise)."""
    if body.kind == "template":
        from demoplan.studio.layouts import TEMPLATES

        if body.id not in {t.id for t in TEMPLATES}:
            raise FileMissingError(
                f"id: no template {body.id!r}; one of {', '.join(t.id for t in TEMPLATES)}"
            )
    elif not folder.path(body.id, "id").is_file():
        raise FileMissingError(f"id: no file {body.id!r} in the work folder")
