"""The studio's web application (docs/studio-api.md): the HTTP API over the
work folder and the command layer, and the page in ``static/``.

Safe by default: a body is at most :data:`~demoplan.studio.requests.MAX_BODY_BYTES`
(413, checked before it is parsed), JSON with finite numbers only; every
request is validated (:mod:`demoplan.studio.requests`, then the project's own
parsers) and a bad one is answered with a 4xx and one line,
``{"detail": "..."}``; files are read and written inside the work folder only
(:mod:`demoplan.studio.workfolder`); no endpoint runs code it is sent.
"""

from __future__ import annotations

import errno
import json
import logging
import os
import threading
from collections.abc import (
    AsyncIterator,
    Awaitable,
    Callable,
    Collection,
    Iterator,
    MutableMapping,
)
from contextlib import asynccontextmanager, contextmanager
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse
from fastapi.staticfiles import StaticFiles

from demoplan.errors import DemoplanError, InputError, LimitReachedError, NoPlanError, UsageError
from demoplan.fileio import os_reason
from demoplan.studio.jobs import LAST_RUN_FILE, Jobs, TooManyRunsError
from demoplan.studio.requests import (
    MAX_BODY_BYTES,
    MAX_SEED,
    DemonstrationRequest,
    DropRequest,
    LandmarkRequest,
    LearnRequest,
    ObjectsRequest,
    PlanRequest,
    RunRequest,
    SceneRequest,
    ScrambleRequest,
    SourceBody,
)
from demoplan.studio.workfolder import FileConflictError, FileMissingError, WorkFolder

__all__ = ["STATIC", "create_app"]

ERROR_STATUS: tuple[tuple[type[Exception], int], ...] = (
    (InputError, 422),
    (UsageError, 422),
    (LimitReachedError, 422),  # the request's work outgrew its budget: ask for less
    (FileMissingError, 404),
    (FileConflictError, 409),
    (TooManyRunsError, 429),
)
"""The answer's status for each refusal (one line, ``{"detail": ...}``)."""

STATIC = Path(__file__).resolve().parent / "static"
"""The page: ``index.html`` and its modules, served as they are."""
MEDIA_SUFFIXES = {".mp4": "video/mp4", ".png": "image/png", ".svg": "image/svg+xml"}
PLACEHOLDER = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>demoplan studio</title></head>
<body><h1>demoplan studio</h1>
<p role="status">The page is not installed; the HTTP API answers under /api
(docs/studio-api.md).</p></body></html>
"""

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]


def one_line(text: str) -> str:
    """``text`` on one line, control characters written as escapes."""
    flat = " ".join(text.split())
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in flat)


LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
"""The names a page served on loopback is reached by (the ``Host`` it is sent)."""


class LocalOnly:
    """ASGI middleware against other web pages: a request must name an allowed
    host in its ``Host`` header (a page of another site that resolves its own
    name to 127.0.0.1 — DNS rebinding — names its own), a request from a page
    must come from the studio's origin (``Origin``: its scheme, host and port;
    not ``null``), and a body must be JSON
    (``Content-Type: application/json``: a form of another page cannot send
    one without the browser asking first). 403 / 415 with one line."""

    def __init__(self, app: ASGIApp, hosts: Collection[str] | None = LOOPBACK_NAMES) -> None:
        self.app = app
        self.hosts = None if hosts is None else {h.strip("[]").lower() for h in hosts}

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or self.hosts is None:
            await self.app(scope, receive, send)
            return
        headers = dict(scope.get("headers") or [])
        host = _host_name(headers.get(b"host", b"").decode("latin-1"))
        if host not in self.hosts:
            await _answer(send, 403, f"Host: {host!r} is not this studio's; {_names(self.hosts)}")
            return
        origin = headers.get(b"origin")
        if origin is not None and not _same_origin(origin, headers.get(b"host", b"")):
            text = origin.decode("latin-1")
            await _answer(send, 403, f"Origin: {text!r} is another site's page")
            return
        if scope["method"] in {"POST", "PUT", "PATCH"}:
            kind = headers.get(b"content-type", b"").split(b";")[0].strip().lower()
            if kind != b"application/json":
                await _answer(send, 415, "Content-Type: application/json expected")
                return
        await self.app(scope, receive, send)


def _same_origin(origin: bytes, host: bytes) -> bool:
    """Is ``origin`` the studio's own page: ``http://`` and the very host and
    port the request was sent to (``Host``)? Another port of the same machine
    is another site, and ``null`` (a sandboxed or local file's page) is no site."""
    scheme, _, authority = origin.decode("latin-1").strip().lower().partition("://")
    return scheme == "http" and authority == host.decode("latin-1").strip().lower()


def _host_name(value: str) -> str:
    """``127.0.0.1:8000`` → ``127.0.0.1``; ``[::1]:8000`` → ``::1``."""
    value = value.strip().lower()
    if value.startswith("["):
        return value[1:].partition("]")[0]
    return value.rpartition(":")[0] if value.count(":") == 1 else value


def _names(hosts: Collection[str]) -> str:
    return "one of " + ", ".join(sorted(hosts)) + " expected"


class BodyLimit:
    """ASGI middleware: a body over ``limit`` bytes is refused with 413 — by its
    ``Content-Length`` before it is read, or while it streams in — and a body
    that is not JSON, or holds NaN or Infinity, or nests too deep for a
    parser, with 422; the body read is handed on to the application."""

    def __init__(self, app: ASGIApp, limit: int = MAX_BODY_BYTES) -> None:
        self.app = app
        self.limit = limit

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] not in {"POST", "PUT", "PATCH", "DELETE"}:
            await self.app(scope, receive, send)
            return
        headers = dict(scope.get("headers") or [])
        length = headers.get(b"content-length")
        too_large = f"body: larger than {self.limit // 1024} KiB; a smaller request expected"
        if length is not None:
            try:
                declared = int(length)
            except ValueError:
                await _answer(send, 400, "Content-Length: not a number")
                return
            if declared > self.limit:
                await _answer(send, 413, too_large)
                return
        chunks: list[bytes] = []
        size = 0
        while True:
            message = await receive()
            if message["type"] == "http.disconnect":
                return
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > self.limit:
                await _answer(send, 413, too_large)
                return
            chunks.append(chunk)
            if not message.get("more_body", False):
                break
        body = b"".join(chunks)
        if body:
            problem = _json_problem(body)
            if problem is not None:
                await _answer(send, 422, f"body: {problem}")
                return
        sent = False

        async def replay() -> Message:
            nonlocal sent
            if not sent:
                sent = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)


def _json_problem(body: bytes) -> str | None:
    """Why ``body`` is not acceptable JSON, or None."""

    def refuse(constant: str) -> Any:
        raise ValueError(f"{constant} is not a number; finite numbers expected")

    try:
        json.loads(body, parse_constant=refuse)
    except RecursionError:
        return "nested too deep; a JSON document expected"
    except UnicodeDecodeError:
        return "not UTF-8; JSON text expected"
    except ValueError as exc:
        return one_line(str(exc)) if "finite" in str(exc) else f"not JSON ({one_line(str(exc))})"
    return None


async def _answer(send: Send, status: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode("utf-8")
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})


def _validation_line(exc: RequestValidationError) -> str:
    """The first validation error as one line: where, and what was expected."""
    errors = exc.errors()
    if not errors:
        return "request: not what was expected"
    first = errors[0]
    where = ".".join(str(part) for part in first.get("loc", ()) if part != "body") or "body"
    message = str(first.get("msg", "invalid")).removeprefix("Value error, ")
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    return one_line(f"{where}: {message}{more}")


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


def create_app(workdir: Path, hosts: Collection[str] | None = LOOPBACK_NAMES) -> FastAPI:
    """The studio on the work folder ``workdir`` (made if missing), answering
    requests sent to ``hosts`` only (None: any, for a studio served to a
    network on purpose)."""
    folder = WorkFolder(workdir)
    jobs = Jobs(record=folder.root / LAST_RUN_FILE)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        yield
        jobs.cancel_all()  # served with a lifespan: no run's process outlives the studio

    app = FastAPI(
        title="demoplan studio",
        docs_url=None,
        redoc_url=None,
        openapi_url=None,
        lifespan=lifespan,
    )
    app.state.workfolder = folder
    app.state.jobs = jobs
    app.add_middleware(BodyLimit)
    app.add_middleware(LocalOnly, hosts=hosts)  # the outermost: checked first
    _add_error_handlers(app)
    _add_page(app)
    _add_layout_routes(app, folder)
    _add_table_routes(app, folder)
    _add_learning_routes(app, folder, jobs)
    _add_run_routes(app, folder, jobs)
    _add_last_run_route(app, jobs)
    return app


def _add_layout_routes(app: FastAPI, folder: WorkFolder) -> None:
    """Templates, the work folder's files, and the template or file the Teach view starts from."""

    @app.get("/api/templates")
    def templates() -> dict[str, Any]:
        from demoplan.studio.layouts import TEMPLATES

        return {"templates": [{"id": t.id, "title": t.title} for t in TEMPLATES]}

    @app.get("/api/templates/{template_id}")
    def template(
        template_id: str, seed: int | None = Query(default=None, ge=0, le=MAX_SEED)
    ) -> dict[str, Any]:
        from demoplan.studio.layouts import template_layout

        return template_layout(template_id, seed)

    @app.get("/api/files")
    def files() -> dict[str, list[str]]:
        return folder.listing()

    @app.get("/api/files/{name}")
    def file(name: str) -> dict[str, Any]:
        document = folder.read(name)
        answer: dict[str, Any] = {"name": name, "document": document}
        kind = folder.kind(document, name)
        if kind == "demonstrations":
            from demoplan.documents.demonstrations import demonstrations_from_document
            from demoplan.studio.layouts import layout_of_demonstration

            demonstrations = demonstrations_from_document(document, name)
            answer["layout"] = layout_of_demonstration(demonstrations[0], demonstrations)
        elif kind == "scenes":
            from demoplan.scenes.scene import scene_from_document
            from demoplan.studio.layouts import layout_of_scene

            answer["layout"] = layout_of_scene(scene_from_document(document, name))
        elif kind == "objects":
            from demoplan.commands.objects import objects_from_document
            from demoplan.studio.layouts import layout_of_objects

            answer["layout"] = layout_of_objects(objects_from_document(document, name), name)
        return answer

    @app.get("/api/source")
    def source() -> dict[str, Any]:
        return {"source": folder.source()}

    @app.put("/api/source")
    def keep_source(body: SourceBody) -> dict[str, Any]:
        if body.kind == "template":
            from demoplan.studio.layouts import TEMPLATES

            if body.id not in {t.id for t in TEMPLATES}:
                raise FileMissingError(
                    f"id: no template {body.id!r}; one of {', '.join(t.id for t in TEMPLATES)}"
                )
        elif not folder.path(body.id, "id").is_file():
            raise FileMissingError(f"id: no file {body.id!r} in the work folder")
        folder.keep_source(body.kind, body.id)
        return {"source": folder.source()}


def _add_table_routes(app: FastAPI, folder: WorkFolder) -> None:
    """What happens on the table: a user's own objects saved, landmarks moved,
    drops and scrambles, and saving demonstrations and scenes."""

    @app.put("/api/objects/{name}")
    def save_objects(name: str, body: ObjectsRequest) -> dict[str, str]:
        from demoplan.commands.objects import objects_from_document
        from demoplan.studio.layouts import objects_document

        document = objects_document(body.layout)
        objects_from_document(document, "layout")  # as the studio reads it back
        path = folder.path(name)
        if not path.exists():
            return {"file": folder.create(document, name, "objects")}
        if not body.replace or folder.kind(folder.read(name), name) != "objects":
            how = "only an objects file is replaced" if body.replace else '"replace": true expected'
            raise FileConflictError(f"name: {name} exists in the work folder; {how}")
        folder.replace(document, name)
        return {"file": name}

    @app.post("/api/landmark")
    def move_landmark(body: LandmarkRequest) -> dict[str, Any]:
        from demoplan.studio.layouts import placed_landmark

        return placed_landmark(
            body.layout, body.landmark, (body.position[0], body.position[1]), body.yaw
        )

    @app.post("/api/drop")
    def drop(body: DropRequest) -> dict[str, Any]:
        from demoplan.studio.layouts import dropped_pose

        return dropped_pose(
            body.layout, body.object, (body.position[0], body.position[1]), body.yaw
        )

    @app.post("/api/scramble")
    def scramble(body: ScrambleRequest) -> dict[str, Any]:
        from demoplan.studio.layouts import scattered

        return scattered(body.layout, body.seed)

    @app.post("/api/demonstrations", status_code=201)
    def save_demonstration(body: DemonstrationRequest) -> dict[str, str]:
        from demoplan.documents.demonstrations import demonstrations_from_document

        document = {"format": "demoplan/demonstration-1", **body.document}
        demonstrations_from_document(document, "document")  # as `learn` reads it
        return {"file": folder.create(document, body.name, "demonstration")}

    @app.post("/api/scenes", status_code=201)
    def save_scene(body: SceneRequest) -> dict[str, str]:
        from demoplan.scenes.scene import scene_from_document

        document = {"format": "demoplan/scene-1", **body.document}
        scene_from_document(document, "document")  # as `plan` reads it
        return {"file": folder.create(document, body.name, "scene")}


def _add_learning_routes(app: FastAPI, folder: WorkFolder, jobs: Jobs) -> None:
    """Learning a model and planning with it."""

    @app.post("/api/learn")
    def learn(body: LearnRequest) -> dict[str, Any]:
        from demoplan.commands.learning import learn_files
        from demoplan.learning.tables import diagnostic_lines
        from demoplan.studio.views import final_scene, model_json, targets_json

        names = body.files if body.files is not None else folder.listing()["demonstrations"]
        if not names:
            raise InputError(
                "the work folder holds no demonstrations; save one first", field="files"
            )
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
        scene = _scene(body.scene, "scene") if body.scene is not None else None
        with jobs.working(), logged_warnings() as logged:
            model = learn_files(paths, output=output).model
        # as `learn` prints them: the model's diagnostics, then what was logged,
        # files named as in the work folder
        where = f"{folder.root}{os.sep}"
        warnings = [f"warning: {line}" for line in diagnostic_lines(model)]
        warnings += [line.replace(where, "") for line in dict.fromkeys(logged)]
        with jobs.working():
            targets = _targets(model, scene) if scene is not None else None
            if targets is None:  # no scene, or one of another task: the first demonstration's end
                targets = targets_json(model, final_scene(model))
        return {"model": body.output, **model_json(model), "targets": targets, "warnings": warnings}

    @app.post("/api/plan")
    def plan(body: PlanRequest) -> dict[str, Any]:
        from demoplan.commands.planning import plan as plan_task
        from demoplan.scenes.plan import SceneLimitReachedError, SceneNoPlanError
        from demoplan.studio.views import no_plan_json, plan_json

        model = _model_path(folder, body.model)
        scene = _scene(body.scene, "scene")
        try:
            with jobs.working():
                result = plan_task(model, scene, clutter=body.clutter)
        except (SceneNoPlanError, SceneLimitReachedError) as failure:
            return no_plan_json(failure)
        return plan_json(result)


def _add_run_routes(app: FastAPI, folder: WorkFolder, jobs: Jobs) -> None:
    """Runs, each in a process of its own (demoplan.studio.jobs), and the media
    an arm run writes."""

    @app.post("/api/runs", status_code=202)
    def start_run(body: RunRequest) -> dict[str, str]:
        from demoplan.execution.faults import parse_faults

        model = _model_path(folder, body.model)
        _scene(body.scene, "scene")  # refused here; the run's process reads it again
        try:
            parse_faults(body.faults or None)  # refused here; the run's process reads it again
        except DemoplanError as exc:
            raise InputError(str(exc), field="faults") from None
        if body.sim == "arm":
            from importlib.util import find_spec

            if find_spec("mujoco") is None:
                raise InputError("the arm needs MuJoCo (pip install 'demoplan[sim]')", field="sim")

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

        job = jobs.start(order)
        return {"run": job.id}

    @app.get("/api/runs/{run_id}")
    def run_state(run_id: str) -> dict[str, Any]:
        return jobs.get(run_id).to_json()

    @app.delete("/api/runs/{run_id}")
    def cancel_run(run_id: str) -> dict[str, Any]:
        return jobs.cancel(run_id).to_json()

    @app.get("/api/media/{name}")
    def media(name: str) -> FileResponse:
        path = _media_path(folder, name)
        return FileResponse(path, media_type=MEDIA_SUFFIXES[path.suffix])


def _targets(model: Any, scene: Any) -> list[dict[str, Any]] | None:
    """The learned targets resolved in ``scene`` (the table as the page shows
    it, landmarks where they stand now), or None where the scene does not hold
    the model's objects."""
    from demoplan.studio.views import targets_json

    try:
        return targets_json(model, scene)
    except DemoplanError:
        return None


def _model_path(folder: WorkFolder, name: str) -> Path:
    path = folder.path(name, "model")
    if not path.is_file():
        raise FileMissingError(f"model: no file {name!r} in the work folder")
    return path


def _scene(document: dict[str, Any], field: str) -> Any:
    """A scene document read by the project's scene parser (as ``plan`` reads a file)."""
    from demoplan.scenes.scene import scene_from_document

    return scene_from_document({"format": "demoplan/scene-1", **document}, field)


def _media_path(folder: WorkFolder, name: str) -> Path:
    import re

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


def _add_page(app: FastAPI) -> None:
    @app.get("/", response_model=None)
    def index() -> FileResponse | HTMLResponse:
        page = STATIC / "index.html"
        if page.is_file():
            return FileResponse(page, media_type="text/html")
        return HTMLResponse(PLACEHOLDER)

    if STATIC.is_dir():
        app.mount("/static", StaticFiles(directory=STATIC), name="static")


def _add_error_handlers(app: FastAPI) -> None:
    def detail(status: int, text: str) -> JSONResponse:
        return JSONResponse({"detail": one_line(text)}, status_code=status)

    @app.exception_handler(RequestValidationError)
    async def invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        return detail(422, _validation_line(exc))

    @app.exception_handler(NoPlanError)
    async def no_plan(request: Request, exc: NoPlanError) -> JSONResponse:
        answer: dict[str, Any] = {
            "plan": [],
            "moves": [],
            "candidates": [],
            "chosen": None,
            "optimal": False,
        }
        no = {"reason": one_line(str(exc)), "figure": None}
        return JSONResponse({**answer, "no_plan": no}, status_code=200)

    def answered_with(status: int) -> Callable[[Request, Exception], Awaitable[JSONResponse]]:
        async def handler(request: Request, exc: Exception) -> JSONResponse:
            return detail(status, str(exc))

        return handler

    for kind, status in ERROR_STATUS:
        app.add_exception_handler(kind, answered_with(status))

    @app.exception_handler(OSError)
    async def folder_changed(request: Request, exc: OSError) -> JSONResponse:
        return detail(503, _folder_trouble(app.state.workfolder.root, exc))

    @app.exception_handler(Exception)
    async def internal(request: Request, exc: Exception) -> JSONResponse:
        logging.getLogger(__name__).warning("internal error: %r", exc)
        return detail(500, f"internal error ({type(exc).__name__}); the studio's log says more")


def _folder_trouble(root: Path, exc: OSError) -> str:
    """What happened to the work folder under the studio, in words (the
    answer's one line where a request could not read or write it)."""
    if not root.exists():
        happened = "was removed while the studio runs; make it again or start the studio anew"
    elif not root.is_dir():
        happened = "is no longer a folder (something replaced it); start the studio anew"
    elif exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS) or not os.access(root, os.W_OK):
        happened = f"cannot be written ({os_reason(exc)}): was it made read-only?"
    else:
        happened = f"cannot be read or written ({os_reason(exc)})"
    return f"the work folder {root} {happened}"


def _add_last_run_route(app: FastAPI, jobs: Jobs) -> None:
    """The run that ended last in the work folder, for a page opened again."""

    @app.get("/api/last-run")
    def last_run() -> dict[str, Any] | None:
        from demoplan.studio.layouts import layout_of_scene

        record = jobs.last()
        if record is None:
            return None
        try:
            layout = layout_of_scene(_scene(record["scene"], "scene"))
        except DemoplanError as exc:
            raise FileMissingError(
                f"run: the last run's scene cannot be drawn ({one_line(str(exc))})"
            ) from None
        return record | {"layout": layout}
