"""Two ``learn --update`` on one model at once both land (issue 14): the second
waits for the first (``fileio.locked_for_update``), so no demonstration is lost."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

from tests.hostile.harness import DEMOPLAN
from tests.support.helpers import EXAMPLES

PAIRS = 20


def _variant(base: dict[str, object], name: str, shift_mm: float) -> dict[str, object]:
    """One of the blocks demonstrations under another name, shifted by a little,
    so that it is new evidence (an exact repeat changes nothing)."""
    demo = json.loads(json.dumps(base))
    demo["format"] = "demoplan/demonstration-1"
    demo["name"] = name
    for step in demo["steps"]:  # type: ignore[attr-defined]
        step["position"][0] += shift_mm / 1000.0
    return demo


def test_twenty_pairs_of_simultaneous_updates_lose_no_demonstration(tmp_path: Path) -> None:
    source = json.loads((EXAMPLES / "blocks" / "demonstrations.json").read_text())
    model = tmp_path / "model.json"
    learned = subprocess.run(
        [DEMOPLAN, "learn", EXAMPLES / "blocks" / "demonstrations.json", "--paper", "-o", model],
        capture_output=True,
        check=False,
    )
    assert learned.returncode == 0, learned.stderr
    added: list[str] = []
    for pair in range(PAIRS):
        processes = []
        for side in range(2):
            name = f"pair{pair}-{side}"
            added.append(name)
            base = source["demonstrations"][side % len(source["demonstrations"])]
            path = tmp_path / f"{name}.json"
            path.write_text(json.dumps(_variant(base, name, 0.1 * (2 * pair + side + 1))))
            processes.append(
                subprocess.Popen(
                    [DEMOPLAN, "learn", "--update", model, path],
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.PIPE,
                    env=dict(os.environ, COLUMNS="100"),
                )
            )
        for process in processes:
            _, err = process.communicate(timeout=120)
            assert process.returncode == 0, err.decode()
    names = [d["name"] for d in json.loads(model.read_text())["demonstrations"]]
    missing = [name for name in added if name not in names]
    assert not missing, f"{len(missing)} of {len(added)} updates lost: {missing}"
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []
