"""``demoplan`` in shell commands (the documents' blocks, tests/e2e/test_docs_shell.py)
forked from the tests' fork server (tests/support/forkserver.py) instead of
started fresh: a folder holding a ``demoplan`` of its own, put first on the
shell's PATH, and a relay in the test's process that it asks.

That ``demoplan`` is a small stdlib-only Python script (``python -IS``: no
site-packages, a few milliseconds to start). It connects to the relay's Unix
socket and passes its stdin, stdout and stderr (the shell's pipes, files or
terminal), its folder, arguments and environment; the relay has the server
fork the command with them and sends back its exit code, which the script
exits with (or dies of the signal that killed the command, as the shell
expects of a child). Where the server cannot serve (another environment than
the one it was started in, no server), the relay says so and the script
becomes the real executable (``exec``): a fresh start, as before.

The child is the server's fork as in the hostile suite: the console script's
entry point, its exit, its streams, its clock counting from the fork."""

from __future__ import annotations

import os
import socket
import struct
import sys
import tempfile
import threading
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

from tests.support import forkserver

SHELL_OWN = frozenset({"PWD", "OLDPWD", "SHLVL", "_", "PS1", "PS2"})
"""Variables a shell sets for each command it starts, or drops (bash unsets the
prompts ``PS1``/``PS2`` when it runs a script: a virtual environment's
``activate`` exports ``PS1``) — no library reads them at import: a request may
differ from the server's environment in these."""

_SCRIPT = """\
#!{python} -IS
import os, pickle, socket, struct, sys
sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
sock.connect({address!r})
data = pickle.dumps({{"argv": [os.fsencode(a) for a in sys.argv[1:]], "cwd": os.getcwd(),
                     "env": dict(os.environ)}})
socket.send_fds(sock, [struct.pack("!Q", len(data)) + data], [0, 1, 2])
answer = b""
while len(answer) < 8:
    more = sock.recv(8 - len(answer))
    if not more:
        sys.exit("demoplan: the tests' fork relay closed")
    answer += more
(code,) = struct.unpack("!q", answer)
if code == {fresh}:
    os.execv({executable!r}, [{executable!r}, *sys.argv[1:]])
if code < 0:
    import signal
    signal.signal(-code, signal.SIG_DFL)
    os.kill(os.getpid(), -code)
sys.exit(code)
"""
FRESH = -(1 << 40)
"""The relay's answer: start the executable fresh."""
relayed = {"forked": 0, "fresh": 0}
"""How the scripts' commands were started (for a report and a test)."""


@contextmanager
def forked_demoplan(env: Mapping[str, str]) -> Iterator[dict[str, str]]:
    """``env`` with a ``demoplan`` first on its PATH that is forked from a fork
    server started in that environment, for as long as the context lasts."""
    with tempfile.TemporaryDirectory(prefix="demoplan-relay-") as name:
        folder = Path(name)
        address = str(folder / "relay")
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        listener.bind(address)
        listener.listen(4)
        script = folder / "bin" / "demoplan"
        script.parent.mkdir()
        script.write_text(
            _SCRIPT.format(
                python=sys.executable,
                address=address,
                fresh=FRESH,
                executable=os.fsdecode(forkserver.DEMOPLAN),
            )
        )
        script.chmod(0o755)
        shell_env = dict(env, PATH=f"{script.parent}{os.pathsep}{env.get('PATH', '')}")
        server = (
            None
            if os.environ.get("DEMOPLAN_TEST_FORK") == "0"  # every command fresh
            else forkserver.CommandServer.start(shell_env)
        )
        relay = threading.Thread(target=_relay, args=(listener, server, shell_env), daemon=True)
        relay.start()
        try:
            yield shell_env
        finally:
            listener.shutdown(socket.SHUT_RDWR)
            listener.close()
            relay.join(10)
            if server is not None:
                server.stop()


def _relay(
    listener: socket.socket, server: forkserver.CommandServer | None, env: dict[str, str]
) -> None:
    """Serve the scripts' requests one at a time until the listener closes."""
    served = {k: v for k, v in env.items() if k not in SHELL_OWN}
    while True:
        try:
            connection, _ = listener.accept()
        except OSError:
            return
        with connection:
            request, fds = forkserver._receive(connection, 3)
            try:
                asked = {k: v for k, v in request["env"].items() if k not in SHELL_OWN}
                if server is None or server.process.poll() is not None or asked != served:
                    code = FRESH
                    relayed["fresh"] += 1
                else:
                    relayed["forked"] += 1
                    stdin, stdout, stderr = fds
                    code = server.run(
                        request["argv"],
                        Path(request["cwd"]),
                        request["env"],
                        stdin,
                        stdout,
                        stderr,
                        on_pid=lambda pid: None,
                    )
            finally:
                for fd in fds:
                    os.close(fd)
            connection.sendall(struct.pack("!q", code))
