"""Ctrl-C at the end of a command's life (docs/limits.md, "Interruption").

A signal that comes while the command works stops it: exit 130 (143) and the
one line ``demoplan: interrupted``. Once its work is done — its outputs in
place, its answer printed — the signal finds nothing to stop, and the command
exits with its own code, saying nothing more. Between the two there must be
no moment where the signal is neither: an outside pass's Ctrl-C in the last
tenth of a second of ``demoplan perceive`` ended it with exit 0, and a signal
landing between the launcher's report and its ignoring signals escaped the
launcher (the process died of SIGINT, without the one line).

The command here is the launcher's own ``main`` around a stand-in that returns
at once; a trace function sends the signal at the k-th line the launcher (and
the interrupts module it calls) runs after the stand-in has returned, for
every k until the launcher has no line left. A loaded machine cannot move the
moment: it is a line, not a time.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap

import pytest

from tests.hostile.harness import HANG_SECONDS

END_OF_THE_COMMAND = """
import os, signal, sys
from demoplan.cli import launcher

WATCHED = ("demoplan/cli/launcher.py", "demoplan/frontends/interrupts.py")
lines = [0]

def tracer(frame, event, arg):
    if not frame.f_code.co_filename.endswith(WATCHED):
        return None
    if event == "line":
        lines[0] += 1
        if lines[0] == {k}:
            sys.settrace(None)
            frame.f_trace = None
            print("signal sent", file=sys.stderr, flush=True)
            os.kill(os.getpid(), {signum})
            return None
    return tracer

def command():
    print("the answer", flush=True)
    launcher_frame = sys._getframe(1)
    launcher_frame.f_trace = tracer
    sys.settrace(tracer)
    return {code}

launcher._dispatch = command
launcher.main()
"""

AT_EXIT = """
import atexit, os, signal, sys
from demoplan.cli import launcher

def command():
    print("the answer", flush=True)
    atexit.register(os.kill, os.getpid(), {signum})
    return {code}

launcher._dispatch = command
launcher.main()
"""

LAST_LINE = 200
"""More lines than the launcher runs after a command returns (about 20)."""


def _run(script: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        timeout=HANG_SECONDS,
        check=False,
    )


def _check(done: subprocess.CompletedProcess[str], code: int, interrupted: int, where: str) -> None:
    """Either stopped (its exit code and the one line) or finished (its own code,
    nothing more said) — never a third answer."""
    err = [line for line in done.stderr.splitlines() if line != "signal sent"]
    if done.returncode == interrupted:
        assert err == ["demoplan: interrupted"], f"{where}: {done.stderr}"
        return
    assert done.returncode == code, f"{where}: exit {done.returncode}: {done.stderr}"
    assert err == [], f"{where}: {done.stderr}"
    assert done.stdout == "the answer\n", where


@pytest.mark.parametrize(
    ("signum", "interrupted"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["int", "term"]
)
@pytest.mark.parametrize("code", [0, 3])
def test_a_signal_at_any_line_of_the_end_stops_or_finds_the_command_finished(
    signum: int, interrupted: int, code: int
) -> None:
    sent_at = []
    for k in range(1, LAST_LINE):
        done = _run(END_OF_THE_COMMAND.format(k=k, signum=int(signum), code=code))
        if "signal sent" not in done.stderr:  # the launcher ran fewer lines
            _check(done, code, interrupted, "no signal")
            break
        sent_at.append(k)
        _check(done, code, interrupted, f"signal at the launcher's line {k} after the command")
    assert len(sent_at) >= 5, sent_at  # the trace saw the launcher's end


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["int", "term"])
def test_a_signal_while_the_interpreter_ends_changes_nothing(signum: int) -> None:
    # atexit handlers run as the interpreter ends, after the launcher has returned
    done = _run(textwrap.dedent(AT_EXIT.format(signum=int(signum), code=0)))
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert done.stdout == "the answer\n"
