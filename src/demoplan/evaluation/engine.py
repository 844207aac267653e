"""Where evaluated runs are carried out: one after the other in this process
(:class:`SerialEngine`), or as Ray tasks on local workers or a cluster
(:class:`RayEngine`). Both take the same runs and yield one row per run as
runs finish; the rows are the same whichever engine made them (a run is a
function of its spec). A Ray worker that dies mid-run (killed, out of memory)
makes its run start again, up to ``max_retries`` times; then the run is an
``error`` row — never a lost or a duplicated row.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import socket
import subprocess
import sys
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol

from demoplan.errors import UsageError
from demoplan.evaluation.runs import RunRow, RunSpec, error_row
from demoplan.fileio import os_reason

__all__ = [
    "CONNECT_SECONDS",
    "Engine",
    "RayEngine",
    "Runner",
    "SerialEngine",
    "check_address",
    "require_ray",
]

Runner = Callable[[RunSpec], RunRow]
"""One run: a picklable callable (a module-level function, or a partial of one)."""


class Engine(Protocol):
    def session(self) -> contextlib.AbstractContextManager[None]:
        """Where the runs will be made, made ready (a Ray started or joined) — before
        an evaluation writes anything, so that a cluster that does not answer
        leaves no folder to resume — and let go at the end."""
        ...

    def rows(self, specs: Sequence[RunSpec], runner: Runner) -> Iterator[RunRow]:
        """One row per spec, in the order runs finish."""
        ...


@dataclass(frozen=True, slots=True)
class SerialEngine:
    """The runs one after the other, here (the reference a Ray evaluation equals)."""

    def session(self) -> contextlib.AbstractContextManager[None]:
        return contextlib.nullcontext()

    def rows(self, specs: Sequence[RunSpec], runner: Runner) -> Iterator[RunRow]:
        for spec in specs:
            try:
                yield runner(spec)
            except Exception as exc:  # the runner's own defect: still the run's row
                yield error_row(spec, f"exception: {type(exc).__name__}: {exc}")


def require_ray() -> Any:
    """The ``ray`` module, or a usage error saying what to install."""
    try:
        import ray
    except ImportError:
        raise UsageError(
            "evaluating on Ray needs the 'scale' extra: pip install 'demoplan[scale]' "
            "(or --workers 0: the runs one after the other, without Ray)"
        ) from None
    return ray


CONNECT_SECONDS = 30.0
"""How long ``--address`` may take to answer as a Ray cluster."""

_OPTIONS: dict[str, Any] = {
    "include_dashboard": False,
    "log_to_driver": False,
    "configure_logging": False,
}

_PROBE = """
import sys
import ray
try:
    ray.init(address=sys.argv[1], include_dashboard=False, log_to_driver=False,
             configure_logging=False)
except BaseException as exc:
    text = str(exc).strip().splitlines()
    said = type(exc).__name__ + (": " + text[0] if text else "")
    print("demoplan-probe: " + said, file=sys.stderr, flush=True)
    sys.exit(3)
ray.shutdown()
"""
"""Joining a cluster in a process of its own: Ray retries an address where
nothing (or no Ray) answers for minutes, in C++ that neither a timeout nor a
Ctrl-C reaches; that process can be killed."""


def check_address(address: str, seconds: float = CONNECT_SECONDS) -> None:
    """A UsageError in one line unless ``address`` (``host:port``, ``ray://host:port``
    or ``auto``) answers as a Ray cluster within ``seconds``."""
    if not re.fullmatch(
        r"auto|(ray://)?[A-Za-z0-9._\-]+:\d{1,5}|(ray://)?\[[0-9A-Fa-f:.]+\]:\d{1,5}", address
    ):
        raise UsageError(f"--address {address[:80]!r}: host:port, ray://host:port or auto expected")
    _listening(address)
    try:
        probe = subprocess.run(
            [sys.executable, "-c", _PROBE, address],
            capture_output=True,
            text=True,
            timeout=seconds,
            check=False,
        )
    except subprocess.TimeoutExpired:
        raise UsageError(
            f"--address {address}: no Ray cluster answered within {seconds:g} s "
            "(nothing listens there, or not Ray)"
        ) from None
    if probe.returncode != 0:
        said = [
            line.removeprefix("demoplan-probe: ")
            for line in probe.stderr.splitlines()
            if line.startswith("demoplan-probe: ")
        ]
        reason = said[-1] if said else f"exit code {probe.returncode}"
        if "InvalidAuthToken" in probe.stderr:
            reason += (
                " — the cluster refused this machine's authentication token (Ray's token "
                "authentication: the cluster's token is needed here, or RAY_AUTH_MODE=disabled "
                "on both)"
            )
        raise UsageError(f"--address {address}: Ray says {reason[:300]}")


def _listening(address: str) -> None:
    """Something accepts connections at ``host:port`` (a refused or unknown one
    answers at once, where Ray would retry for minutes)."""
    if address == "auto":
        return
    host, _, port = address.removeprefix("ray://").rpartition(":")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=5.0).close()
    except OSError as exc:
        raise UsageError(f"--address {address}: nothing listens there ({os_reason(exc)})") from None


def _first_line(exc: BaseException) -> str:
    lines = str(exc).strip().splitlines()
    return type(exc).__name__ + (f": {lines[0][:300]}" if lines else "")


_own_ray: list[bool] = [False]
"""Whether the Ray this process is connected to was started (or joined) by a
:class:`RayEngine`, which shuts it down (disconnects) when its runs end."""


def _call(runner: Runner, spec: RunSpec) -> RunRow:
    """The Ray task's body (module level: workers import it)."""
    return runner(spec)


@dataclass(frozen=True, slots=True)
class RayEngine:
    """The runs as Ray tasks. ``address``: join that cluster; else a local Ray
    with ``workers`` CPUs (None: the machine's cores) is started and stopped
    here — unless Ray is running in this process already, which is used as it is.
    ``max_retries``: new starts of a run whose worker died."""

    workers: int | None = None
    address: str | None = None
    max_retries: int = 2
    in_flight: int = 0
    """Tasks submitted at a time (0: four per CPU): a Ctrl-C cancels few."""

    connect_timeout: float = CONNECT_SECONDS
    """Seconds ``address`` has to answer before the evaluation gives up."""

    @contextlib.contextmanager
    def session(self) -> Iterator[None]:
        ray = require_ray()
        started = self._start(ray)
        try:
            yield
        finally:
            if started:
                _shut_down(ray)

    def _start(self, ray: Any) -> bool:
        """Start a local Ray, or join ``address`` (checked first: it answers as
        a Ray cluster within ``connect_timeout``); False where Ray runs in this
        process already. A local Ray is always a new one (``address="local"``):
        a cluster running on the machine, or ``RAY_ADDRESS``, is joined only when
        asked for by ``--address``."""
        if ray.is_initialized():
            return False
        if self.address is not None:
            check_address(self.address, self.connect_timeout)
        quiet = logging.getLogger("ray")  # its start-up notes are no demoplan output
        level = quiet.level
        quiet.setLevel(logging.ERROR)
        try:
            if self.address is not None:
                ray.init(address=self.address, **_OPTIONS)
            else:
                ray.init(address="local", num_cpus=self.workers or os.cpu_count() or 1, **_OPTIONS)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            where = f"--address {self.address}" if self.address else "a local Ray"
            raise UsageError(f"{where}: Ray says {_first_line(exc)}") from None
        finally:
            quiet.setLevel(level)
        _own_ray[0] = True
        return True

    def rows(self, specs: Sequence[RunSpec], runner: Runner) -> Iterator[RunRow]:
        ray = require_ray()
        started = self._start(ray)
        pending: dict[Any, tuple[RunSpec, int]] = {}
        try:
            task = ray.remote(max_retries=0)(_call)
            shared = ray.put(runner)
            cpus = int(ray.cluster_resources().get("CPU", 1))
            limit = self.in_flight or 4 * max(1, cpus)
            queue = list(reversed(specs))
            while queue or pending:
                while queue and len(pending) < limit:
                    spec = queue.pop()
                    pending[task.remote(shared, spec)] = (spec, 1)
                done, _ = ray.wait(list(pending), num_returns=1, timeout=0.5)
                for ref in done:
                    spec, attempt = pending.pop(ref)
                    row = self._outcome(ray, ref, spec, attempt)
                    if row is None:  # the worker died: start the run again
                        pending[task.remote(shared, spec)] = (spec, attempt + 1)
                    else:
                        yield row
        finally:
            # Stopped (Ctrl-C, the caller closed us): the runs in flight go. On a Ray
            # of our own they go with it — a local Ray is shut down, a cluster joined
            # by --address ends this driver's tasks when it disconnects — and are not
            # cancelled: ray.cancel racing a task that finishes at that moment fails
            # a check in Ray's core worker ("Tried to complete task that was not
            # pending", ray-project/ray#54798), which ends the whole process with
            # exit 1 instead of the Ctrl-C's 130. A Ray that outlives the evaluation
            # (running in this process before it) has them cancelled — unless it has
            # been shut down meanwhile, where ray.cancel would start a new local Ray.
            for ref in pending if ray.is_initialized() and not _own_ray[0] else ():
                with contextlib.suppress(Exception):  # finished meanwhile, or its node gone
                    ray.cancel(ref, force=True)
            if started:
                _shut_down(ray)

    def _outcome(self, ray: Any, ref: Any, spec: RunSpec, attempt: int) -> RunRow | None:
        """The run's row, or None when its worker died and a retry is left."""
        from ray.exceptions import RayError, RayTaskError

        try:
            row: RunRow = ray.get(ref)
        except RayTaskError as exc:  # the runner raised: a finding, not a dead worker
            return error_row(spec, f"exception: {exc.cause!r}", attempt)
        except RayError:  # the worker (or its node) died
            if attempt <= self.max_retries:
                return None
            return error_row(spec, f"the worker died in each of {attempt} attempts", attempt)
        return replace(row, attempts=attempt)


def _shut_down(ray: Any) -> None:
    """Shut down (or disconnect from) the Ray a RayEngine started or joined."""
    _own_ray[0] = False
    ray.shutdown()
