"""A command forked from the tests' fork server answers as the executable
started fresh does (tests/support/forkserver.py): the same exit code, stdout
and stderr, byte for byte — on a success, a refusal, a usage error, input on
stdin, stdout on a full disk, a file name that is not UTF-8, and a planning
budget that runs out (the clock counts from the fork)."""

from __future__ import annotations

import os
import shlex
import shutil
import socket
import struct
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

from tests.support import forkrelay, forkserver
from tests.support.helpers import EXAMPLES

pytestmark = pytest.mark.slow  # each case also starts the executable fresh

CASES = {
    "learn": [b"learn", b"demos.json", b"--paper", b"-o", b"model.json"],
    "show-json": [b"show", b"model.json", b"--json"],
    # a budget no load reaches (the default 2 s, wall time, ran out at load 10 in one
    # process and not in the other): the plan is proved long before, the same in both
    "plan": [b"plan", b"model.json", b"scene.json", b"--timeout", b"60"],
    "plan-out-of-time": [b"plan", b"model.json", b"scene.json", b"--timeout", b"0"],
    "run": [b"run", b"model.json", b"scene.json", b"--timeout", b"60"],
    "missing-file": [b"plan", b"model.json", b"missing.json"],
    "not-utf8-name": [b"show", b"odd-\xff.json"],
    "usage-error": [b"plan", b"model.json", b"--timeout", b"soon"],
    "no-such-command": [b"bogus"],
    "help": [b"plan", b"--help"],
}
TIMEOUT = 120.0
HEADER = 8  # bytes: a reply's length, before the reply


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("forkserver")
    shutil.copy(EXAMPLES / "blocks" / "demonstrations.json", folder / "demos.json")
    shutil.copy(EXAMPLES / "scenes" / "pyramid-fig4.json", folder / "scene.json")
    shutil.copy(EXAMPLES / "planning" / "paper-example.xml", folder / "problem.xml")
    learned = forkserver.fresh(CASES["learn"], folder, _env(), timeout=TIMEOUT)
    assert learned.returncode == 0, learned.stderr
    shutil.copy(folder / "model.json", os.fsdecode(os.fsencode(folder) + b"/odd-\xff.json"))
    return folder


@pytest.fixture(autouse=True)
def _a_server_of_this_environment() -> None:
    """Each test here checks what the server answers, so it starts from a server
    of the environment the worker has now: one started earlier in this worker
    may have ended, or the environment have changed since (a library setting a
    variable at its import), and every command would then start fresh."""
    if forkserver._server_for(forkserver.command_env()) is None:
        forkserver.stop_servers()


def _env() -> dict[str, str]:
    return forkserver.command_env()


def _forked(args: list[bytes], folder: Path, **options: object) -> tuple[int, bytes, bytes]:
    before = forkserver.started["forked"]
    answer = forkserver.run(args, folder, _env(), timeout=TIMEOUT, **options)  # type: ignore[arg-type]
    assert forkserver.started["forked"] == before + 1, "not forked: the server did not serve"
    return answer.returncode, answer.stdout, answer.stderr


_FRESH: dict[tuple[object, ...], tuple[int, bytes, bytes]] = {}
"""The executable's answers started fresh, by command, folder and environment:
several tests compare a forked command with the same fresh one (the missing
file's four times). No command here changes what another reads (``learn``
writes model.json again byte for byte)."""


def _fresh(args: list[bytes], folder: Path, **options: object) -> tuple[int, bytes, bytes]:
    env = _env()
    # by the environment less pytest's PYTEST_CURRENT_TEST (the test's name: the
    # server's own check leaves it out too, forkserver.PER_TEST)
    key = (tuple(args), folder, tuple(sorted(forkserver._lasting(env).items())))
    if not options and key in _FRESH:
        return _FRESH[key]
    answer = forkserver.fresh(args, folder, env, timeout=TIMEOUT, **options)  # type: ignore[arg-type]
    found = answer.returncode, answer.stdout, answer.stderr
    if not options:  # none given on stdin, stdout a pipe
        _FRESH[key] = found
    return found


@pytest.mark.parametrize("name", list(CASES))
def test_a_forked_command_answers_as_a_fresh_one(
    workspace: Path, name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("DEMOPLAN_TEST_FORK", raising=False)  # on, whatever the run says
    assert _forked(CASES[name], workspace) == _fresh(CASES[name], workspace)


def test_stdin_and_a_full_disk_reach_the_forked_command(
    workspace: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("DEMOPLAN_TEST_FORK", raising=False)  # on, whatever the run says
    scene = (workspace / "scene.json").read_bytes()
    args = [b"plan", b"model.json", b"/dev/stdin"]
    forked = _forked(args, workspace, stdin=scene)
    assert forked == _fresh(args, workspace, stdin=scene)
    assert forked[0] == 1 and b"/dev/stdin: not a regular file" in forked[2], forked
    with Path("/dev/full").open("wb") as full:
        forked = _forked([b"show", b"model.json"], workspace, stdout_file=full)
        assert forked == _fresh([b"show", b"model.json"], workspace, stdout_file=full)
    assert forked[0] == 1 and b"standard output" in forked[2], forked
    with Path("/dev/full").open("wb") as full:  # the lean path, buffered as the executable's
        solve = [b"solve", b"problem.xml", b"--timeout", b"inf"]
        assert _forked(solve, workspace, stdout_file=full) == _fresh(
            solve, workspace, stdout_file=full
        )


def test_another_environment_starts_the_command_fresh(
    workspace: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A variable libraries may read at import (here MuJoCo's backend) is not
    the server's: the command starts as the executable."""
    monkeypatch.delenv("DEMOPLAN_TEST_FORK", raising=False)  # on, whatever the run says
    _forked(CASES["missing-file"], workspace)  # the server runs
    monkeypatch.setenv("MUJOCO_GL", "bogus")
    before = dict(forkserver.started)
    forkserver.run(CASES["missing-file"], workspace, _env(), timeout=TIMEOUT)
    assert forkserver.started == {**before, "fresh": before["fresh"] + 1}


def _both_replies_queued(sock: socket.socket) -> None:
    """Wait until the server's two replies to a command (the child's pid and
    its exit code) both sit in the socket, unread."""
    deadline = time.monotonic() + TIMEOUT
    while time.monotonic() < deadline:
        queued = sock.recv(1 << 16, socket.MSG_PEEK)
        if len(queued) >= 2 * HEADER:
            (first,) = struct.unpack_from("!Q", queued)
            if len(queued) >= HEADER + first + HEADER:
                (second,) = struct.unpack_from("!Q", queued, HEADER + first)
                if len(queued) >= 2 * HEADER + first + second:
                    return
        time.sleep(0.01)
    pytest.fail("the server never sent both replies")


def test_a_command_that_ends_before_its_pid_is_read_gives_its_exit_code(
    workspace: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The reply carrying the child's pid is read only once the exit code has
    come too (as on a loaded machine when a command refuses its input at
    once): both must be read, each as its own reply. Reading all the socket
    held once took both and dropped the exit code; the asker then waited for
    it until its timeout (the hang of a full run)."""
    monkeypatch.delenv("DEMOPLAN_TEST_FORK", raising=False)  # on, whatever the run says
    expected = _fresh(CASES["missing-file"], workspace)
    assert _forked(CASES["missing-file"], workspace) == expected  # the server runs
    receive = forkserver._receive
    asked: list[int] = []

    def late(sock: socket.socket, fd_count: int = 0) -> tuple[Any, list[int]]:
        asked.append(1)
        if len(asked) % 2:  # the pid's reply: read it only when the exit code's has come
            _both_replies_queued(sock)
        return receive(sock, fd_count)

    monkeypatch.setattr(forkserver, "_receive", late)
    for _ in range(2):  # and the next command's replies are its own
        assert _forked(CASES["missing-file"], workspace) == expected
    assert len(asked) == 4


def test_a_command_out_of_time_is_killed_and_the_next_gets_its_own_answer(
    workspace: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A time limit that ends before the server has even told the child's pid:
    the child is still killed and the server's replies read, so that the next
    command's answer is its own."""
    monkeypatch.delenv("DEMOPLAN_TEST_FORK", raising=False)  # on, whatever the run says
    _forked(CASES["missing-file"], workspace)  # the server runs
    server = forkserver._server_for(_env())
    assert server is not None
    killed = len(forkserver.killed)
    with pytest.raises(subprocess.TimeoutExpired):
        forkserver.run(CASES["plan"], workspace, _env(), timeout=0)
    assert len(forkserver.killed) == killed + 1  # the command was forked, then killed
    assert forkserver._server_for(_env()) is server  # the same server, still in step
    assert _forked(CASES["missing-file"], workspace) == _fresh(CASES["missing-file"], workspace)


@pytest.mark.parametrize("name", ["show-json", "missing-file", "usage-error", "help"])
def test_a_shells_demoplan_is_forked_and_answers_as_a_fresh_one(
    workspace: Path, name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The docs' shell blocks' ``demoplan`` (tests/support/forkrelay.py): the
    shell sees a fresh process's exit code, stdout and stderr."""
    monkeypatch.delenv("DEMOPLAN_TEST_FORK", raising=False)
    args = [os.fsdecode(a) for a in CASES[name]]
    with forkrelay.forked_demoplan(_env()) as env:
        before = dict(forkrelay.relayed)
        shell = subprocess.run(
            ["bash", "-c", shlex.join(["demoplan", *args])],
            cwd=workspace,
            env=env,
            capture_output=True,
            timeout=TIMEOUT,
            check=False,
        )
        assert forkrelay.relayed == {**before, "forked": before["forked"] + 1}
    assert (shell.returncode, shell.stdout, shell.stderr) == _fresh(CASES[name], workspace)
