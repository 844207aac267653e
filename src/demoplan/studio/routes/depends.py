"""What the studio's handlers share: their typed dependencies (the work
folder and the runs of the application answering the request), the readers of
what a request names (a model file, a scene document), and answers in one line
(with the warnings logged while a request works)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

from fastapi import Depends, Request

from demoplan.studio.jobs import Jobs
from demoplan.studio.workfolder import FileMissingError, WorkFolder

__all__ = ["Folder", "Runs", "logged_warnings", "model_path", "one_line", "scene_of"]


def _work_folder(request: Request) -> WorkFolder:
    folder: WorkFolder = request.app.state.workfolder
    return folder


def _jobs(request: Request) -> Jobs:
    jobs: Jobs = request.app.state.jobs
    return jobs


Folder = Annotated[WorkFolder, Depends(_work_folder)]
"""The application's work folder."""
Runs = Annotated[Jobs, Depends(_jobs)]
"""The application's runs (and its work while a request learns or plans)."""


def model_path(folder: WorkFolder, name: str) -> Path:
    """The model file ``name`` of the work folder (404 where there is none)."""
    path = folder.path(name, "model")
    if not path.is_file():
        raise FileMissingError(f"model: no file {name!r} in the work folder")
    return path


def scene_of(document: dict[str, Any], source: str) -> Any:
    """A scene document read by the project's scene parser (as ``plan`` reads a
    file), its errors naming it ``source`` (``views.PLAN_START``, ``views.LEARN_TABLE``)."""
    from demoplan.scenes.scene import scene_from_document

    return scene_from_document({"format": "demoplan/scene-1", **document}, source)


def one_line(text: str) -> str:
    """``text`` on one line, control characters written as escapes."""
    flat = " ".join(text.split())
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in flat)


@contextmanager
def logged_warnings() -> Iterator[list[str]]:
    """The warnings demoplan logs in this thread while the block runs, each as
    the CLI prints it (``demoplan: WARNING: ...``)."""
    lines: list[str] = []
    me = threading.get_ident()

    class Held(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            if record.thread == me:
                lines.append(one_line(f"demoplan: {record.levelname}: {record.getMessage()}"))

    handler = Held(logging.WARNING)
    logger = logging.getLogger("demoplan")
    logger.addHandler(handler)
    try:
        yield lines
    finally:
        logger.removeHandler(handler)
