"""``demoplan`` commands in processes of their own without paying the imports
each time: a fork server.

A test of what a command answers to hostile input runs the command in a
process of its own (a FIFO or a device can block its reader; the exit code,
stdout and stderr are the process's own), and most of such a process's second
goes to importing NumPy, SciPy, typer and demoplan. The server is a Python
process that imports those once and then forks a child per command: the child
takes the request's stdin, stdout and stderr (passed over a Unix socket),
working folder and arguments, and runs the ``demoplan`` executable's entry
point (:func:`demoplan.cli.launcher.main`) as the console script does, exit
included (``SystemExit``, an uncaught exception's traceback, non-daemon
threads, ``atexit``, the final flush of stdout). The child is a process like
any other: its exit code, its two streams, a signal that kills it, a hang the
caller's timeout ends.

What a fork cannot give is a fresh interpreter start, so :func:`run` starts
the executable itself (:func:`fresh`) whenever the start could matter:

* the request's environment differs from the server's (a test setting
  ``MUJOCO_GL``, ``HOME`` or ``TMPDIR``: libraries read some of it when
  imported);
* the server could not start clean: its imports wrote to stderr (a warning
  a fresh process would print in every command), changed the environment,
  started a thread, or imported MuJoCo, matplotlib or Ray (which keep state
  from their import: a GL backend, a config folder, a cluster address);
* ``DEMOPLAN_TEST_FORK=0`` (to compare, or to rule the server out).

A full run once hung here: a command that refused its input at once ended
before the asking thread had read the server's first reply (the child's
pid), the first read took both replies and the exit code was lost; the
command timed out, and under hypothesis the next example's replies went to
the earlier command's thread, still reading. A reply is now read to its
length and no further, and a command out of time leaves no reader behind
(:func:`_kill`); test_forkserver.py forces both.

The command clock (:mod:`demoplan.cli.clock`) counts from the process start,
which for a child is the fork (:func:`demoplan.cli.clock.restart_process_clock`).
tests/support/test_forkserver.py checks that a child's answer is a fresh
process's, byte for byte, on commands that succeed, refuse, read stdin, write
to a full disk and run out of time.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import socket
import struct
import subprocess
import sys
import threading
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    import typer

Command = TypeVar("Command")

DEMOPLAN = Path(sys.executable).parent / "demoplan"  # the installed console script
PRELOAD = (
    "numpy",
    "scipy.optimize",
    "scipy.spatial",
    "yaml",
    "typer",
    "rich.console",
    "demoplan.commands.evaluation",
    "demoplan.commands.execution",
    "demoplan.commands.experiments",
    "demoplan.commands.export",
    "demoplan.commands.learning",
    "demoplan.commands.objects",
    "demoplan.commands.planning",
    "demoplan.commands.recordings",
    "demoplan.commands.scenes",
    "demoplan.commands.solving",
    "demoplan.cli.launcher",
    "demoplan.cli.application",
)
"""What the server imports before it forks: what most commands import."""
KEEPING_STATE = ("mujoco", "matplotlib", "ray")
"""Libraries whose import keeps state a command's environment should decide."""
PER_TEST = frozenset({"PYTEST_CURRENT_TEST"})
"""Variables that change from test to test and that no library reads: a
request may differ from the server's environment in these (the child takes
the request's)."""
SERVER_SECONDS = 10.0
"""How long the server may take to answer after a command's time ran out (it
answers at once: its child is killed)."""
_HEADER = struct.Struct("!Q")


def _send(sock: socket.socket, value: Any, fds: Sequence[int] = ()) -> None:
    data = pickle.dumps(value)
    socket.send_fds(sock, [_HEADER.pack(len(data)) + data], list(fds))


def _receive(sock: socket.socket, fd_count: int = 0) -> tuple[Any, list[int]]:
    """One message: its header, then exactly the bytes it announces — never
    more. The server's two replies to a command (the child's pid, then its
    exit code) arrive together when the command ends before the asking thread
    reads the first (a refusal on a loaded machine); reading whatever the
    socket held took both, unpickling the first dropped the second, and the
    asker waited for an exit code already consumed."""
    header, fds, _, _ = socket.recv_fds(sock, _HEADER.size, fd_count)
    header += _exactly(sock, _HEADER.size - len(header)) if header else b""
    if not header:
        raise EOFError("the fork server's socket closed")
    (size,) = _HEADER.unpack(header)
    return pickle.loads(_exactly(sock, size)), fds


def _exactly(sock: socket.socket, size: int) -> bytes:
    data = b""
    while len(data) < size:
        more = sock.recv(size - len(data))
        if not more:
            raise EOFError("the fork server's socket closed")
        data += more
    return data


class CommandServer:
    """One fork server, started by :meth:`start` with an environment; serves one
    command at a time (a test worker runs its tests one after another)."""

    def __init__(self, process: subprocess.Popen[bytes], sock: socket.socket, env: dict[str, str]):
        self.process = process
        self.sock = sock
        self.env = env

    @classmethod
    def start(cls, env: Mapping[str, str]) -> CommandServer | None:
        """A server in ``env``, or None when it could not start clean."""
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
        process = subprocess.Popen(
            [sys.executable, __file__, str(theirs.fileno())],
            env=dict(env),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            pass_fds=(theirs.fileno(),),
        )
        theirs.close()
        server = cls(process, ours, dict(env))
        try:
            ready, _ = _receive(ours)
        except (EOFError, OSError):
            ready = "the server ended"
        if ready != "ready":
            server.stop()
            return None
        return server

    def run(
        self,
        argv: Sequence[bytes],
        cwd: Path,
        env: Mapping[str, str],
        stdin: int,
        stdout: int,
        stderr: int,
        on_pid: Any,
        on_sent: Any = None,
    ) -> int:
        """The command's exit code (minus the signal's number when one killed
        it, as :mod:`subprocess` says); ``on_pid`` is told the child's pid,
        ``on_sent`` (if given) called once the server holds the request and
        its copies of the streams."""
        request = {"argv": list(argv), "cwd": str(cwd), "env": dict(env)}
        _send(self.sock, request, [stdin, stdout, stderr])
        if on_sent is not None:
            on_sent()
        pid, _ = _receive(self.sock)
        on_pid(pid)
        code, _ = _receive(self.sock)
        assert isinstance(code, int)
        return code

    def stop(self) -> None:
        self.sock.close()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


_servers: dict[str, CommandServer | None] = {}  # this process's (one)
started = {"forked": 0, "fresh": 0}
"""How this process's commands were started (for a report)."""
killed: list[int] = []
"""The forked commands killed when their time ran out (their pids)."""


def _server_for(env: Mapping[str, str]) -> CommandServer | None:
    """This process's server if ``env`` is its environment (the first asked for
    starts it); None: start the command fresh (and always where
    ``DEMOPLAN_TEST_FORK=0``)."""
    if os.environ.get("DEMOPLAN_TEST_FORK") == "0" or not hasattr(socket, "send_fds"):
        return None
    if not _servers:
        _servers["only"] = CommandServer.start(env)
    server = _servers["only"]
    if server is None or server.process.poll() is not None or _lasting(server.env) != _lasting(env):
        return None
    return server


def _lasting(env: Mapping[str, str]) -> dict[str, str]:
    return {key: value for key, value in env.items() if key not in PER_TEST}


def command_env() -> dict[str, str]:
    """The environment tests run ``demoplan`` in: this process's, 100 columns,
    every warning shown (one printed would break a one-line error), bytecode
    written and standard output buffered as a user's would be (a harness's
    ``PYTHONUNBUFFERED`` hid a note printed before a full disk's error)."""
    env = dict(os.environ, COLUMNS="100", PYTHONWARNINGS="default")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env.pop("PYTHONUNBUFFERED", None)
    return env


def stop_servers() -> None:
    """Stop this process's server (they also end when this process does)."""
    for server in _servers.values():
        if server is not None:
            server.stop()
    _servers.clear()


def _pump_in(pipe: int, data: bytes) -> None:
    try:
        with open(pipe, "wb", closefd=True) as writer:
            writer.write(data)
    except BrokenPipeError:
        pass


def _pump_out(pipe: int, into: list[bytes]) -> None:
    with open(pipe, "rb", closefd=True) as reader:
        into.append(reader.read())


def run(
    argv: Sequence[bytes],
    cwd: Path,
    env: Mapping[str, str],
    *,
    timeout: float,
    stdin: bytes | None = None,
    stdout_file: IO[bytes] | None = None,
    server: CommandServer | None = None,
) -> subprocess.CompletedProcess[bytes]:
    """``demoplan ARGV`` in a process of its own, as :func:`subprocess.run` would
    start it (stdin: ``stdin`` or this process's; stdout: ``stdout_file`` or a
    pipe; stderr a pipe): a fork of this process's server where it serves
    ``env``, else the executable (:func:`fresh`). ``server``: a server of the
    caller's own instead (:meth:`CommandServer.start`, in ``env``), for commands
    that run at the same time (each server serves one at a time). Raises
    :class:`subprocess.TimeoutExpired` after killing a command that took
    longer than ``timeout``."""
    if server is None:
        server = _server_for(env)
    if server is None:
        started["fresh"] += 1
        return fresh(argv, cwd, env, timeout=timeout, stdin=stdin, stdout_file=stdout_file)
    started["forked"] += 1
    opened: list[int] = []
    threads: list[threading.Thread] = []
    out: list[bytes] = []
    err: list[bytes] = []
    try:
        if stdin is None:
            child_in = 0
        else:
            read_end, write_end = os.pipe()
            opened.append(read_end)
            child_in = read_end
            threads.append(threading.Thread(target=_pump_in, args=(write_end, stdin)))
        if stdout_file is not None:
            child_out = stdout_file.fileno()
        else:
            read_end, write_end = os.pipe()
            opened.append(write_end)
            child_out = write_end
            threads.append(threading.Thread(target=_pump_out, args=(read_end, out)))
        read_end, write_end = os.pipe()
        opened.append(write_end)
        threads.append(threading.Thread(target=_pump_out, args=(read_end, err)))
        for thread in threads:
            thread.daemon = True
            thread.start()
        pids: list[int] = []
        told = threading.Event()  # the child's pid came
        answered: list[int] = []
        failed: list[BaseException] = []
        sent = threading.Event()  # the server holds the request and the streams
        done = threading.Event()

        def on_pid(pid: int) -> None:
            pids.append(pid)
            told.set()

        def serve() -> None:
            try:
                answered.append(
                    server.run(
                        argv,
                        cwd,
                        env,
                        child_in,
                        child_out,
                        write_end,
                        on_pid=on_pid,
                        on_sent=sent.set,
                    )
                )
            except BaseException as exc:  # raised again in the test's thread
                failed.append(exc)
            done.set()

        asking = threading.Thread(target=serve, daemon=True)
        asking.start()
        # The streams are closed here only once the server holds its copies: closed
        # before (a time limit of 0), the request went out with closed descriptors,
        # was never served, and the time-out waited SERVER_SECONDS for a child's pid.
        # (A server that does not take the request is stopped by _kill.)
        sent.wait(SERVER_SECONDS)
        finished = done.wait(timeout)
        for fd in opened:  # the child has its copies: EOF comes when it (and its children) close
            os.close(fd)
        opened.clear()
        if not finished:
            _kill(server, pids, told, asking)
            for thread in threads:
                thread.join(5)
            raise subprocess.TimeoutExpired(
                [os.fsencode(DEMOPLAN), *argv], timeout, b"".join(out), b"".join(err)
            )
        asking.join()
        for thread in threads:
            thread.join()
    finally:
        for fd in opened:
            os.close(fd)
    if failed:
        raise failed[0]
    return subprocess.CompletedProcess(
        [os.fsencode(DEMOPLAN), *argv],
        answered[0],
        None if stdout_file is not None else b"".join(out),
        b"".join(err),
    )


def _kill(
    server: CommandServer, pids: list[int], told: threading.Event, asking: threading.Thread
) -> None:
    """End a command that ran out of time: kill its child (once the server
    has said which it is: the timeout may come before) and wait for the
    server's exit code. A server that does not answer is stopped and
    forgotten (the next command starts a new one): a thread left reading its
    socket would take the next command's replies for this one's."""
    if told.wait(SERVER_SECONDS):
        for pid in pids:
            with contextlib.suppress(ProcessLookupError):  # it ended meanwhile
                os.kill(pid, signal.SIGKILL)
            killed.append(pid)
    asking.join(SERVER_SECONDS)
    if asking.is_alive():
        with contextlib.suppress(OSError):
            server.sock.shutdown(socket.SHUT_RDWR)  # the asking thread reads EOF
        server.process.kill()
        asking.join()
        server.stop()
        if _servers.get("only") is server:
            _servers.clear()


def fresh(
    argv: Sequence[bytes],
    cwd: Path,
    env: Mapping[str, str],
    *,
    timeout: float,
    stdin: bytes | None = None,
    stdout_file: IO[bytes] | None = None,
) -> subprocess.CompletedProcess[bytes]:
    """``demoplan ARGV`` started as the executable (a fresh interpreter)."""
    return subprocess.run(
        [os.fsencode(DEMOPLAN), *argv],
        cwd=cwd,
        input=stdin,
        stdout=stdout_file if stdout_file is not None else subprocess.PIPE,
        stderr=subprocess.PIPE,
        timeout=timeout,
        env=dict(env),
        check=False,
    )


# The server's side: runs as a script (python forkserver.py FD), stdlib only
# until it imports PRELOAD.


def _serve(fd: int) -> None:
    import importlib
    import tempfile

    sock = socket.socket(fileno=fd)
    before = dict(os.environ)
    stderr = os.dup(2)
    with tempfile.TemporaryFile() as written:
        os.dup2(written.fileno(), 2)  # what the imports print
        for name in PRELOAD:
            importlib.import_module(name)
        _build_command_line()
        sys.stderr.flush()
        os.dup2(stderr, 2)
        printed = os.fstat(written.fileno()).st_size
    os.close(stderr)
    clean = (
        not printed
        and dict(os.environ) == before
        and threading.active_count() == 1
        and not any(name in sys.modules for name in KEEPING_STATE)
    )
    if not clean:
        _send(sock, "not clean")
        return
    _send(sock, "ready")
    while True:
        try:
            request, fds = _receive(sock, 3)
        except EOFError:
            return
        pid = os.fork()
        if pid == 0:
            sock.close()
            _child(request["argv"], request["cwd"], request["env"], fds)  # never returns
        for received in fds:
            os.close(received)
        _send(sock, pid)
        _, status = os.waitpid(pid, 0)
        _send(sock, os.waitstatus_to_exitcode(status))


def _build_command_line() -> None:
    """Build the command line's click command (typer's conversion of every
    command's signature, ~27 ms of CPU, made on every call of the app) once,
    here, for every child to use: the same object a child would build, from the
    same functions in the same environment, only built before the fork."""
    import typer.main

    from demoplan.cli.application import app

    get_command = converting_once(app, typer.main.get_command)
    get_command(app)  # built here, before any fork
    typer.main.get_command = get_command  # what Typer.__call__ calls


def converting_once(
    app: typer.Typer, convert: Callable[[typer.Typer], Command]
) -> Callable[[typer.Typer], Command]:
    """``convert`` (typer's conversion of an application into its click command)
    made once for ``app`` and that command returned on every later call; any other
    application converted as before. The fork server and the tests' in-process runner
    (tests/support/cli.py) both put it in typer's place."""
    built: list[Command] = []

    def get_command(instance: typer.Typer) -> Command:
        if instance is not app:
            return convert(instance)
        if not built:
            built.append(convert(app))
        return built[0]

    return get_command


def _child(argv: list[bytes], cwd: str, env: dict[str, str], fds: list[int]) -> None:
    """Become ``demoplan ARGV``: the console script's run, then the interpreter's exit."""
    import atexit
    import signal
    import traceback

    code = 1
    try:
        for target, received in enumerate(fds):
            os.dup2(received, target)
        for received in set(fds) - {0, 1, 2}:
            os.close(received)
        _new_stdio()
        os.chdir(cwd)
        os.environ.clear()
        os.environ.update(env)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        sys.argv = [str(DEMOPLAN), *(os.fsdecode(a) for a in argv)]
        sys.path[0] = str(DEMOPLAN.parent)
        from demoplan.cli import clock
        from demoplan.cli.launcher import main

        clock.restart_process_clock()
        try:
            main()
            code = 0
        except SystemExit as exc:
            code = _exit_code(exc)
        except KeyboardInterrupt:
            traceback.print_exc()
            code = -signal.SIGINT
        except BaseException:
            sys.excepthook(*sys.exc_info())
            code = 1
        threading._shutdown()  # type: ignore[attr-defined]  # non-daemon threads, as at exit
        atexit._run_exitfuncs()
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                if stream is sys.stdout:
                    sys.stderr.write(f"Exception ignored in: {sys.stdout!r}\n")
                    code = 120
    finally:
        if code < 0:  # died of the signal, as Python does for an uncaught KeyboardInterrupt
            signal.signal(-code, signal.SIG_DFL)
            os.kill(os.getpid(), -code)
        os._exit(code & 0xFF)


def _new_stdio() -> None:
    """``sys.stdin``, ``stdout`` and ``stderr`` made anew on fds 0, 1, 2, as the
    interpreter makes them at its start (Python/pylifecycle.c ``create_stdio``):
    buffered by the file's block size unless ``PYTHONUNBUFFERED`` (stdin
    always), line-buffered on a terminal (stderr always), the server's
    encoding and error handlers (its environment is the command's)."""
    import io

    buffered = not getattr(
        sys.stdout, "write_through", False
    )  # as the server's start made it (PYTHONUNBUFFERED)
    made: list[io.TextIOWrapper[Any]] = []
    for fd, name, old in (
        (0, "<stdin>", sys.stdin),
        (1, "<stdout>", sys.stdout),
        (2, "<stderr>", sys.stderr),
    ):
        reading = fd == 0
        buffer: Any = io.open(  # noqa: UP020, SIM115 - a buffer, as the interpreter opens it
            fd, "rb" if reading else "wb", buffering=-1 if buffered or reading else 0, closefd=False
        )
        raw = buffer.raw if hasattr(buffer, "raw") else buffer
        text = io.TextIOWrapper(
            buffer,
            encoding=old.encoding,
            errors=old.errors,
            newline="\n",
            line_buffering=buffered and (raw.isatty() or fd == 2),
            write_through=not buffered and not reading,
        )
        raw.name = name
        text.mode = "r" if reading else "w"  # type: ignore[misc]
        made.append(text)
    sys.stdin, sys.stdout, sys.stderr = made
    sys.__stdin__, sys.__stdout__, sys.__stderr__ = made  # type: ignore[misc]


def _exit_code(exc: SystemExit) -> int:
    """The exit code the interpreter makes of an uncaught ``SystemExit``."""
    if exc.code is None:
        return 0
    if isinstance(exc.code, int):
        return exc.code
    sys.stderr.write(f"{exc.code}\n")
    return 1


if __name__ == "__main__":
    _serve(int(sys.argv[1]))
