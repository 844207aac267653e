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
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol

from demoplan.errors import UsageError
from demoplan.evaluation.runs import RunRow, RunSpec, error_row

__all__ = ["Engine", "RayEngine", "Runner", "SerialEngine", "require_ray"]

Runner = Callable[[RunSpec], RunRow]
"""One run: a picklable callable (a module-level function, or a partial of one)."""


class Engine(Protocol):
    def rows(self, specs: Sequence[RunSpec], runner: Runner) -> Iterator[RunRow]:
        """One row per spec, in the order runs finish."""
        ...


@dataclass(frozen=True, slots=True)
class SerialEngine:
    """The runs one after the other, here (the reference a Ray evaluation equals)."""

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

    def _start(self, ray: Any) -> bool:
        if ray.is_initialized():
            return False
        options: dict[str, Any] = {
            "include_dashboard": False,
            "log_to_driver": False,
            "configure_logging": False,
        }
        quiet = logging.getLogger("ray")  # its start-up notes are no demoplan output
        level = quiet.level
        quiet.setLevel(logging.ERROR)
        try:
            if self.address is not None:
                ray.init(address=self.address, **options)
            else:
                ray.init(num_cpus=self.workers or os.cpu_count() or 1, **options)
        finally:
            quiet.setLevel(level)
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
            for ref in pending:  # stopped (Ctrl-C, the caller closed us): the rest goes
                with contextlib.suppress(Exception):  # finished meanwhile, or its node gone
                    ray.cancel(ref, force=True)
            if started:
                ray.shutdown()

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
