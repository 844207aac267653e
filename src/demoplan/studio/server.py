"""Serving the studio: uvicorn on a socket bound before it starts (so that
``--port 0`` prints the port the system chose), the URL printed, the browser
opened, and Ctrl-C stopping it as every command stops (exit 130: uvicorn
hands the signal back to the launcher's handler when it has shut down)."""

from __future__ import annotations

import socket
import sys
import threading
import webbrowser
from pathlib import Path

from demoplan.errors import UsageError

__all__ = ["bind", "serve", "url_of"]


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host``:``port`` (0: a free port)."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError) as exc:
        raise UsageError(f"--host {host!r}: not an address this machine has ({exc})") from None
    family, kind, protocol, _, address = infos[0]
    sock = socket.socket(family, kind, protocol)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(128)
    except OSError as exc:
        sock.close()
        raise UsageError(
            f"--host {host} --port {port}: cannot listen there ({exc.strerror})"
        ) from None
    return sock


def url_of(sock: socket.socket) -> str:
    host, port = sock.getsockname()[:2]
    shown = f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}/"


def serve(workdir: Path, host: str = "127.0.0.1", port: int = 0, open_browser: bool = True) -> None:
    """Serve the studio on ``workdir`` until Ctrl-C (or SIGTERM): print its URL
    on stdout, and open it in the browser unless ``open_browser`` is False."""
    try:
        import fastapi  # noqa: F401 - the application's framework
        import uvicorn
    except ImportError as exc:
        raise UsageError(
            f"the studio needs FastAPI and uvicorn ({exc.name} is missing): "
            "pip install 'demoplan[studio]'"
        ) from None

    from demoplan.studio.app import LOOPBACK_NAMES, create_app

    sock = bind(host, port)
    bound = sock.getsockname()[0]
    # served to a network on purpose (0.0.0.0, an address of this machine): any Host
    loopback = bound.startswith("127.") or bound == "::1"
    if not loopback:
        sys.stderr.write(
            f"demoplan: WARNING: --host {host}: the studio is served to the network; anyone "
            "who reaches it can read and write the work folder\n"
        )
    try:
        app = create_app(workdir, hosts=(*LOOPBACK_NAMES, bound, host) if loopback else None)
    except BaseException:
        sock.close()
        raise
    url = url_of(sock)
    folder = app.state.workfolder.root

    class Announced(uvicorn.Server):
        """The server that says where it listens once it answers there."""

        async def startup(self, sockets: list[socket.socket] | None = None) -> None:
            await super().startup(sockets=sockets)
            sys.stdout.write(f"demoplan studio: {url} (work folder {folder}); Ctrl-C stops it\n")
            sys.stdout.flush()
            if open_browser:
                threading.Thread(target=webbrowser.open, args=(url,), daemon=True).start()

    config = uvicorn.Config(app, log_level="warning", access_log=False, lifespan="off")
    server = Announced(config)
    try:
        server.run(sockets=[sock])
    finally:
        app.state.jobs.cancel_all()
        sock.close()
