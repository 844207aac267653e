"""``evaluate --address``: an address where no Ray answers fails fast and in
one line (exit 2), leaving no folder to resume; a Ray cluster running on the
machine (or ``RAY_ADDRESS``) never breaks ``--workers N``; a real local head
is joined by its address."""

from __future__ import annotations

import http.server
import importlib.util
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from demoplan.errors import UsageError
from demoplan.evaluation.engine import check_address
from demoplan.learning.modelfile import save_model
from tests.support.helpers import EXAMPLES, paper_model

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("ray") is None, reason="Ray is not installed"
)  # looked up, not imported: importing Ray costs every xdist worker's collection ~0.5 s

SCENE = EXAMPLES / "scenes" / "set-table-cluttered.json"


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("model") / "model.json"
    save_model(paper_model("set_table"), path)
    return path


NO_STORYBOARDS = (
    "import runpy, demoplan.commands.evaluation as command; command.STORYBOARDS = 0; "
    "runpy.run_module('demoplan', run_name='__main__', alter_sys=True)"
)
"""``python -m demoplan`` whose evaluations draw no storyboard: its worst run
made again frame by frame, here, after the Ray session has ended (3.4 of the
4.5 s of CPU of this scene's one-run evaluation) — nothing these tests read."""


def _evaluate(
    model: Path, out: Path, *options: str, **env: str
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [
            sys.executable,
            "-c",
            NO_STORYBOARDS,
            "evaluate",
            str(model),
            str(SCENE),
            "--out",
            str(out),
            *options,
        ],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "PYTHONWARNINGS": "ignore", **env},
        check=False,
    )


@pytest.mark.parametrize(
    ("address", "expected"),
    [
        ("127.0.0.1:{closed}", "nothing listens there (connection refused)"),
        ("ray://127.0.0.1:{closed}", "nothing listens there (connection refused)"),
        ("not an address", "host:port, ray://host:port or auto expected"),
        ("127.0.0.1:99999999", "host:port, ray://host:port or auto expected"),
    ],
)
def test_an_address_where_nothing_listens_is_one_line_at_once(address: str, expected: str) -> None:
    with pytest.raises(UsageError, match=re.escape(expected)) as caught:
        check_address(address.format(closed=_free_port()))
    assert "\n" not in str(caught.value)


def test_an_address_that_is_no_ray_fails_within_the_bound() -> None:
    """An HTTP server answers the connection but not as Ray: Ray alone would
    retry for minutes; the check gives up at its bound."""
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        started = time.monotonic()
        with pytest.raises(UsageError, match="no Ray cluster answered within 1 s"):
            check_address(f"127.0.0.1:{server.server_address[1]}", seconds=1.0)
        assert time.monotonic() - started < 60  # a hang guard: the probe is killed at 1 s
    finally:
        server.shutdown()


def test_the_command_leaves_nothing_to_resume(model: Path, tmp_path: Path) -> None:
    out = tmp_path / "evaluation"
    done = _evaluate(model, out, "--address", f"127.0.0.1:{_free_port()}")
    assert done.returncode == 2, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("demoplan: error: --address 127.0.0.1:"), lines
    assert not out.exists()


@pytest.fixture(scope="module")
def ray_head(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A real Ray head on this machine (``ray start --head --block``, its own
    temporary folder; ended by ending that command), without token
    authentication (the tests and the head share no token). The folder is a
    short one of its own: Ray's sockets live in it, and a socket's path may not
    exceed 107 bytes — pytest's basetemp under xdist
    (``/tmp/pytest-of-root/pytest-1015/popen-gw0/ray0/session_…/sockets/plasma_store``)
    passes that once its run counter has four digits."""
    port = _free_port()
    folder = Path(tempfile.mkdtemp(prefix="ray-"))
    log = tmp_path_factory.mktemp("ray-head") / "head.log"
    env = {**os.environ, "RAY_AUTH_MODE": "disabled"}
    ray = Path(sys.executable).with_name("ray")
    head = subprocess.Popen(
        [
            str(ray),
            "start",
            "--head",
            "--block",
            f"--port={port}",
            "--num-cpus=1",
            "--include-dashboard=false",
            f"--temp-dir={folder}",
        ],
        stdout=log.open("wb"),
        stderr=subprocess.STDOUT,
        env=env,
    )
    try:
        for _ in range(120):  # a hang guard: the head opens its port within seconds
            if head.poll() is not None:
                tail = log.read_text(errors="replace").strip().splitlines()[-1:]
                pytest.fail(f"the Ray head ended ({head.returncode}): {tail}")
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                time.sleep(0.5)
        else:
            pytest.fail("the Ray head did not open its port")
        yield f"127.0.0.1:{port}"
    finally:
        head.terminate()
        head.wait(timeout=60)
        shutil.rmtree(folder, ignore_errors=True)


def test_a_running_head_is_joined_by_address_and_never_breaks_local_workers(
    model: Path, ray_head: str, tmp_path: Path
) -> None:
    joined = _evaluate(
        model, tmp_path / "joined", "--address", ray_head, "--json", RAY_AUTH_MODE="disabled"
    )
    assert joined.returncode == 0, joined.stderr
    local = _evaluate(model, tmp_path / "local", "--workers", "2", "--json", RAY_ADDRESS=ray_head)
    assert local.returncode == 0, local.stderr
    rows = {name: _rows(tmp_path / name / "runs.jsonl") for name in ("joined", "local")}
    assert rows["joined"] == rows["local"] and rows["joined"][0]["success"] is True


def _rows(path: Path) -> list[dict[str, object]]:
    """The rows without their timings (which differ from run to run)."""
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    return [{k: v for k, v in row.items() if not k.endswith("_s")} for row in rows]
