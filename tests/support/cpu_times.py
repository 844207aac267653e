"""Each test's CPU seconds, with its processes' — a pytest plugin (not loaded by
default): ``--durations`` gives wall times, which on a shared machine say as much
about the load as about the test, and leave out what a test's processes spend.

    DEMOPLAN_CPU_TIMES=cpu.tsv python -m pytest -p tests.support.cpu_times …
    sort -rn cpu.tsv | head -40

appends one line per test (setup, call and teardown together) to the file,
tab-separated: CPU seconds in all, of the test's process, of its children
that ended (reaped), of its descendants still running (a fork server, a local
Ray: what they spent during the test), wall seconds, node id. Under
pytest-xdist each worker appends its own lines. Linux only (``/proc``); a
process that is not a descendant (a daemon reparented to init, as Ray's
workers may be when their raylet ends) is not counted, and a descendant that
ends during a test without being reaped by one (it took its CPU with it) can
make "reaped" negative."""

from __future__ import annotations

import os
import resource
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

_TICKS = os.sysconf("SC_CLK_TCK")


@dataclass(frozen=True)
class _Snapshot:
    own: float  # this process's CPU seconds
    reaped: float  # its ended children's (and theirs, where reaped)
    descendants: dict[int, float]  # each running descendant's, with its reaped children's
    wall: float


def _processes() -> dict[int, tuple[int, float]]:
    """Every process: its parent and CPU seconds (utime, stime, cutime, cstime)."""
    found: dict[int, tuple[int, float]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            text = (entry / "stat").read_text()
        except OSError:  # ended meanwhile
            continue
        fields = text[text.rindex(")") + 2 :].split()  # after "pid (comm) "
        found[int(entry.name)] = (int(fields[1]), sum(int(f) for f in fields[11:15]) / _TICKS)
    return found


def _descendants(processes: dict[int, tuple[int, float]], root: int) -> dict[int, float]:
    children: dict[int, list[int]] = {}
    for pid, (parent, _) in processes.items():
        children.setdefault(parent, []).append(pid)
    found: dict[int, float] = {}
    todo = [root]
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in found:
                found[child] = processes[child][1]
                todo.append(child)
    return found


def _snapshot() -> _Snapshot:
    descendants = _descendants(_processes(), os.getpid())
    ended = resource.getrusage(resource.RUSAGE_CHILDREN)
    return _Snapshot(
        time.process_time(), ended.ru_utime + ended.ru_stime, descendants, time.monotonic()
    )


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Iterator[None]:
    before = _snapshot()
    yield
    after = _snapshot()
    out = os.environ.get("DEMOPLAN_CPU_TIMES")
    if not out:
        return
    reaped = after.reaped - before.reaped
    for pid, seconds in before.descendants.items():
        if pid not in after.descendants:  # reaped during the test: counted whole above
            reaped -= seconds
    running = sum(s - before.descendants.get(pid, 0.0) for pid, s in after.descendants.items())
    own = after.own - before.own
    with Path(out).open("a") as file:
        file.write(
            f"{own + reaped + running:.2f}\t{own:.2f}\t{reaped:.2f}\t{running:.2f}\t"
            f"{after.wall - before.wall:.2f}\t{item.nodeid}\n"
        )
