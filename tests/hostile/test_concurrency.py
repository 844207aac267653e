"""Two ``learn --update`` on one model at once both land (issue 14): the second
waits for the first (``fileio.locked_for_update``), so no demonstration is lost.

Each update is a ``demoplan`` process of its own (the lock is between
processes), forked from one of two fork servers (tests/support/forkserver.py)
so that both of a pair start at the same moment, without a second of imports
each: their read-modify-write windows overlap in every pair, and without the
lock one of the two updates is lost."""

from __future__ import annotations

import json
import os
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.support import forkserver
from tests.support.helpers import EXAMPLES

PAIRS = 20
TIMEOUT = 120.0


def _variant(base: dict[str, object], name: str, shift_mm: float) -> dict[str, object]:
    """One of the blocks demonstrations under another name, shifted by a little,
    so that it is new evidence (an exact repeat changes nothing)."""
    demo: dict[str, Any] = json.loads(json.dumps(base))
    demo["format"] = "demoplan/demonstration-1"
    demo["name"] = name
    for step in demo["steps"]:
        step["position"][0] += shift_mm / 1000.0
    return demo


@pytest.fixture(scope="module")
def servers() -> Iterator[list[forkserver.CommandServer | None]]:
    """Two fork servers (None where one could not start clean: that side's
    commands then start as the executable)."""
    started = [forkserver.CommandServer.start(forkserver.command_env()) for _ in range(2)]
    yield started
    for server in started:
        if server is not None:
            server.stop()


def _update(
    server: forkserver.CommandServer | None,
    model: Path,
    path: Path,
    answers: list[subprocess.CompletedProcess[bytes]],
) -> None:
    argv = [b"learn", b"--update", os.fsencode(model), os.fsencode(path)]
    env = forkserver.command_env()
    if server is None:
        answers.append(forkserver.fresh(argv, model.parent, env, timeout=TIMEOUT))
    else:
        answers.append(forkserver.run(argv, model.parent, env, timeout=TIMEOUT, server=server))


def test_twenty_pairs_of_simultaneous_updates_lose_no_demonstration(
    tmp_path: Path, servers: list[forkserver.CommandServer | None]
) -> None:
    source = json.loads((EXAMPLES / "blocks" / "demonstrations.json").read_text())
    model = tmp_path / "model.json"
    learned = forkserver.run(
        [
            b"learn",
            os.fsencode(EXAMPLES / "blocks" / "demonstrations.json"),
            b"--paper",
            b"-o",
            os.fsencode(model),
        ],
        tmp_path,
        forkserver.command_env(),
        timeout=TIMEOUT,
    )
    assert learned.returncode == 0, learned.stderr
    added: list[str] = []
    for pair in range(PAIRS):
        answers: list[subprocess.CompletedProcess[bytes]] = []
        updates = []
        for side in range(2):
            name = f"pair{pair}-{side}"
            added.append(name)
            base = source["demonstrations"][side % len(source["demonstrations"])]
            path = tmp_path / f"{name}.json"
            path.write_text(json.dumps(_variant(base, name, 0.1 * (2 * pair + side + 1))))
            updates.append(
                threading.Thread(target=_update, args=(servers[side], model, path, answers))
            )
        for update in updates:
            update.start()
        for update in updates:
            update.join()
        assert len(answers) == 2
        for answer in answers:
            assert answer.returncode == 0, answer.stderr.decode()
    names = [d["name"] for d in json.loads(model.read_text())["demonstrations"]]
    missing = [name for name in added if name not in names]
    assert not missing, f"{len(missing)} of {len(added)} updates lost: {missing}"
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []
