"""One studio run in a process of its own: ``python -m demoplan.studio.worker``,
started by :class:`demoplan.studio.jobs.Jobs` for each ``POST /api/runs``.

It reads the run's request, one JSON line, on stdin; runs it through the
command layer's :func:`demoplan.commands.execution.run` (the CLI's and the
Python API's function: no second copy of the work); and writes, one JSON line
each, on its stdout:

- ``{"event": {...}}`` for each event of the run as it happens
  (:func:`demoplan.studio.views.event_json`), with the world the executor had
  last observed when it told the event (:attr:`~demoplan.execution.report.RunEvent.observation`);
- at the end, ``{"result": {...}, "events": [...]}`` (the run's JSON and its
  events, the end's marked with the run's outcome) or ``{"error": "one line"}``.

Stopping it is the CLI's own way: SIGTERM (or SIGINT) raises
:class:`~demoplan.frontends.interrupts.Terminated` through the handlers the
launcher installs (:mod:`demoplan.frontends.interrupts`), so the run's ``finally``
closes the world, stops ffmpeg and removes the video's private folder
(:mod:`demoplan.execution.video_output`); the process then exits 143 (130)
without a final line. The studio holds this process's stdin open for as long
as it lives: stdin at its end (the studio killed) stops the run the same way.

The protocol goes through a copy of the original stdout kept private to this
process (not inherited by ffmpeg); file descriptor 1 is pointed at stderr, so
that anything a library prints cannot corrupt it.
"""

from __future__ import annotations

import json
import logging
import os
import signal
import sys
import threading
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, NoReturn

from demoplan.frontends.interrupts import reports_signals

if TYPE_CHECKING:
    pass

__all__ = ["main"]

MAX_EVENTS = 10_000
"""Events kept per run (as :data:`demoplan.studio.jobs.MAX_EVENTS`)."""


@reports_signals
def main() -> NoReturn:
    """Run the request read on stdin, and exit: 0, 130 / 143 when stopped, 1
    when the studio could not be told (its end of the pipe gone)."""
    from demoplan.frontends.interrupts import (
        interrupted_exit_code,
        on_signal,
        redeliver_lost_signal,
        signals_received,
        stop_redelivery,
    )

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    sys.unraisablehook = redeliver_lost_signal
    protocol = os.fdopen(os.dup(1), "w", encoding="utf-8")  # a dup is not inherited
    os.dup2(2, 1)
    # the run's warnings are not the studio's terminal's (as when runs were threads)
    logging.basicConfig(level=logging.CRITICAL, handlers=[logging.NullHandler()], force=True)
    logging.captureWarnings(True)
    try:
        try:
            request = json.loads(sys.stdin.buffer.readline())
            threading.Thread(target=_stop_when_stdin_ends, daemon=True).start()
            _send(protocol, _outcome(request, protocol))
        finally:
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    except KeyboardInterrupt as exc:
        stop_redelivery()
        code = interrupted_exit_code(exc)
    except Exception as exc:
        stop_redelivery()
        if signals_received:  # the signal surfaced as another error
            code = 143 if signal.SIGTERM in signals_received else 130
        else:  # the studio's end of the pipe is gone
            sys.stderr.write(f"demoplan studio: run: {type(exc).__name__}: {exc}\n")
            code = 1
    else:
        stop_redelivery()
        # a signal a library swallowed still stops the run
        code = 0 if not signals_received else 143 if signal.SIGTERM in signals_received else 130
    # No interpreter teardown (MuJoCo's GL contexts, ffmpeg already closed):
    # everything was said.
    sys.stderr.flush()
    os._exit(code)


def _outcome(request: dict[str, Any], protocol: IO[str]) -> dict[str, Any]:
    """The run's final line: its result and events, or its error in one line."""
    from demoplan.errors import DemoplanError
    from demoplan.frontends.interrupts import signals_received

    try:
        return _run(request, protocol)
    except DemoplanError as exc:
        return {"error": " ".join(str(exc).split())}
    except Exception as exc:  # a fault of the studio itself: one line, never a traceback
        if signals_received:  # a signal surfaced as another error (an interrupted import)
            raise
        return {"error": f"internal error ({type(exc).__name__})"}


def _run(request: dict[str, Any], protocol: IO[str]) -> dict[str, Any]:
    from demoplan.commands.execution import run
    from demoplan.execution.faults import parse_faults
    from demoplan.execution.report import RunEvent
    from demoplan.scenes.scene import scene_from_document
    from demoplan.studio.views import (
        PLAN_START,
        event_json,
        finished_events,
        run_result_json,
    )

    scene = scene_from_document({"format": "demoplan/scene-1", **request["scene"]}, PLAN_START)
    video = Path(request["video"]) if request.get("video") else None
    events: list[dict[str, Any]] = []

    def heard(event: RunEvent) -> None:
        shown = event_json(event)
        if len(events) < MAX_EVENTS:
            events.append(shown)
        _send(protocol, {"event": shown})

    report = run(
        Path(request["model"]),
        scene,
        sim=request["sim"],
        faults=parse_faults(request.get("faults") or None),
        seed=int(request.get("seed", 0)),
        clutter=bool(request.get("clutter", False)),
        video=video,
        on_event=heard,
    )
    media = request.get("media") if video is not None and video.is_file() else None
    return {
        "result": run_result_json(report, media),
        "events": finished_events(events, report),
    }


def _send(protocol: IO[str], line: dict[str, Any]) -> None:
    protocol.write(json.dumps(line) + "\n")
    protocol.flush()


def _stop_when_stdin_ends() -> None:
    """The studio holds stdin open while it lives: at its end, stop as on SIGTERM."""
    while sys.stdin.buffer.read(1 << 12):
        pass
    os.kill(os.getpid(), signal.SIGTERM)


if __name__ == "__main__":
    main()
