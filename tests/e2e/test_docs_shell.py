"""Every shell block of README.md, docs/ and the examples' READMEs runs, and
prints what the block shows (see tests/support/docs_blocks.py for the comparison);
every Python block runs. Each document's blocks run in order, in a fresh
folder where ``examples/``, ``benchmarks/`` and ``docs/`` are the
repository's, so a block may use what an earlier one wrote.

What a planning command prints on its default time budget (2 s from the
process start, docs/planning.md) depends on the machine's speed: on a loaded
machine start-up alone can spend it, and the plan comes back unproved (or
longer). Such a command (``plan``, ``solve``, ``run`` without ``--timeout``)
that does not print what its block shows is run once more with
``--timeout inf``, which must then print exactly that — so the output shown
is still checked, only not the machine's speed (that is benchmarks/planning.py's).

The README's set-up commands (its first block, a plain ``` block) are what
CI runs; they are not run again here.

Each ``demoplan`` of a block is a process of its own forked from a fork
server that has imported what the commands import (tests/support/forkrelay.py),
not a fresh interpreter: its exit code and streams are a fresh process's
(tests/support/test_forkserver.py), without a second of imports each.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.docs_blocks import ROOT, Block, blocks, documents, mismatch, without_time_limit
from tests.support.forkrelay import forked_demoplan

TIMEOUT = 900
"""Seconds per command: a hang guard only (an arm run takes 70-90 s alone, several
times that on a loaded machine)."""
SHARED = ("examples", "benchmarks", "docs", "tests")


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    bin_dir = str(Path(sys.executable).parent)
    env["PATH"] = bin_dir + os.pathsep + env.get("PATH", "")
    env.pop("COLUMNS", None)
    env.update(NO_COLOR="1", TERM="dumb", MPLBACKEND="Agg", MUJOCO_GL="egl")
    env.setdefault("PYTHONPATH", str(ROOT))
    return env


def _run(command: str, folder: Path, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(  # stderr merged, in the order a terminal shows them
        ["bash", "-c", command],
        cwd=folder,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=TIMEOUT,
        check=False,
    )


def _run_block(block: Block, folder: Path, env: dict[str, str], last: list[int]) -> None:
    if block.language == "python":
        done = subprocess.run(
            [sys.executable, "-c", block.source],
            cwd=folder,
            env=env,
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
            check=False,
        )
        assert done.returncode == 0, f"{block.where}: the Python block failed:\n{done.stderr}"
        return
    for index, command in enumerate(block.commands):
        where = f"{block.path.relative_to(ROOT)}:{command.line}"
        if command.text.strip() == "echo $?":
            output, code = f"{last[0]}\n", 0
        else:
            following = (
                block.commands[index + 1].text.strip() if index + 1 < len(block.commands) else ""
            )
            ran = command.text
            done = _run(ran, folder, env)
            unlimited = without_time_limit(command.text)
            if unlimited is not None and (
                (done.returncode != 0 and following != "echo $?")
                or mismatch(command.expected, done.stdout) is not None
            ):  # the default budget ran out first (a loaded machine): the same, unhurried
                ran = unlimited
                done = _run(ran, folder, env)
            output, code = done.stdout, done.returncode
            if code != 0 and following != "echo $?":
                pytest.fail(f"{where}: `{ran}` exited {code}:\n{output[-2000:]}")
        last[0] = code
        why = mismatch(command.expected, output)
        assert why is None, f"{where}: `{ran}`: {why}\n--- real output ---\n{output[-3000:]}"


def _provide(document: Path, folder: Path) -> None:
    """Files a document's commands read that cannot be in the repository:
    robosuite's demo.hdf5 (docs/segmentation.md), from PyPI, cached."""
    if document.name != "segmentation.md":
        return
    from tests.support.robosuite_data import (
        RobosuiteDataError,
        robosuite_demonstrations,
        skip_or_fail,
    )

    try:
        source = robosuite_demonstrations()["Stack"]
    except RobosuiteDataError as exc:
        skip_or_fail(exc)
    (folder / "demo.hdf5").symlink_to(source)
    if (source.parent / "models").is_dir():  # robosuite 1.0 keeps each demo's model beside it
        (folder / "models").symlink_to(source.parent / "models")


DOCUMENTS = [
    path for path in documents() if any(b.commands or b.language == "python" for b in blocks(path))
]


@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_the_documents_blocks_run_and_print_what_they_show(document: Path, tmp_path: Path) -> None:
    for name in SHARED:
        (tmp_path / name).symlink_to(ROOT / name)
    _provide(document, tmp_path)
    last = [0]
    with forked_demoplan(_environment()) as env:  # each `demoplan` forked, not started fresh
        for block in blocks(document):  # (the README's set-up block has no language: not run)
            _run_block(block, tmp_path, env, last)
