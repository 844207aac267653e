"""The studio's web application (docs/studio-api.md): the HTTP API over the
work folder and the command layer (its routes: :mod:`demoplan.studio.routes`,
one router per resource), and the page in ``static/``.

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
from collections.abc import (
    AsyncIterator,
    Awaitable,
    Callable,
    Collection,
    MutableMapping,
)
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse
from fastapi.staticfiles import StaticFiles

from demoplan.errors import InputError, LimitReachedError, NoPlanError, UsageError
from demoplan.fileio import os_reason
from demoplan.studio.jobs import LAST_RUN_FILE, Jobs, TooManyRunsError
from demoplan.studio.requests import (
    MAX_BODY_BYTES,
)
from demoplan.studio.routes import ROUTERS
from demoplan.studio.routes.depends import one_line
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
    for router in ROUTERS:
        app.include_router(router)
    return app


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
