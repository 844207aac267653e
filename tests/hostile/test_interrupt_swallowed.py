"""Ctrl-C that a library swallows still stops the command.

An extension module that Ctrl-C interrupts while it loads fails with
``ImportError``; an optional import's ``except ImportError`` then takes the
signal for a missing package, and the command ran on to its end (the
``experiments`` command did, for 115 s, when the signal came while matplotlib
loaded). The launcher raises a received signal again until it reaches the
launcher's report — but never cuts short a cleanup that is unwinding from it.

The commands here are the launcher's own ``main`` around a stand-in for the
command, so that the library's swallowing happens at a known line instead of
at a moment a loaded machine decides.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time

from tests.hostile.harness import HANG_SECONDS

RUN_THE_COMMAND = """
import os, signal, sys, time
from demoplan.cli import launcher

def command():
{body}
    deadline = time.monotonic() + {hang}
    while time.monotonic() < deadline:
        sum(range(1000))
    print("ran to its end", file=sys.stderr)
    return 0

launcher._dispatch = command
launcher.main()
"""


def _run(body: str) -> tuple[subprocess.CompletedProcess[str], float]:
    script = RUN_THE_COMMAND.format(body=textwrap.indent(body, "    "), hang=HANG_SECONDS)
    began = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        timeout=3 * HANG_SECONDS,
        check=False,
    )
    return done, time.monotonic() - began


def test_an_interrupt_an_optional_import_swallowed_still_stops_the_command() -> None:
    done, seconds = _run(
        textwrap.dedent("""
        try:  # an extension module interrupted while it loads
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(5)
            except KeyboardInterrupt:
                raise ImportError("initialization failed") from None
        except ImportError:  # taken for a package that is not installed
            pass
        """)
    )
    assert "ran to its end" not in done.stderr
    assert done.returncode == 130, done.stderr
    assert done.stderr.splitlines()[-1:] == ["demoplan: interrupted"], done.stderr
    assert seconds < HANG_SECONDS


def test_sigterm_a_library_swallowed_stops_the_command_with_143() -> None:
    done, _ = _run(
        textwrap.dedent("""
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
        except BaseException:  # a library's bare except
            pass
        """)
    )
    assert "ran to its end" not in done.stderr
    assert done.returncode == 143, done.stderr


def test_a_cleanup_unwinding_from_the_interrupt_is_not_cut_short() -> None:
    # A cleanup four times longer than the redelivery interval: the timer waits.
    done, _ = _run(
        textwrap.dedent("""
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        finally:
            began = time.monotonic()
            while time.monotonic() - began < 1.0:
                sum(range(1000))
            print("cleanup complete", file=sys.stderr, flush=True)
        """)
    )
    assert "cleanup complete" in done.stderr
    assert "ran to its end" not in done.stderr
    assert done.returncode == 130, done.stderr
    assert "Traceback" not in done.stderr


def test_a_command_that_is_not_interrupted_is_untouched() -> None:
    done, _ = _run("return 0\n")
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
