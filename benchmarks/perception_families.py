"""Benchmark: how often block perception meets the real-photograph thresholds on
the generated photograph families, over many seeds.

What it measures
----------------
Every family of :mod:`demoplan.perception.photo_families` (cubes touching in
rows, stacks, black and white cubes, patterned tops, hands, side faces,
over-exposure, small cubes, a tilted camera, shapes that are no cubes, cubes
lying tipped over, towers), seeds ``--first`` to ``--last``, each perceived in
process twice: with the cubes' side given (``--side``) and without. A draw
*meets* the thresholds the development set's real photographs are held to
(docs/perception.md, "Real photographs"): at least 90 % of its labelled,
non-partial top faces found within 0.6 of their side, at most one false block
(none in a draw without cubes), exit 0.

The table gives per family the draws meeting, the tops found of those needed,
the false blocks, and the draws that fail as ``seed`` (without ``--side``) or
``seed+s`` (with it); the last row the totals. The test suite checks a few
draws of each family by hypothesis; this is the rate behind them.

How to run
----------
From the repository root, with demoplan installed::

    python benchmarks/perception_families.py                      # seeds 0–9 (~4 min of CPU)
    python benchmarks/perception_families.py --first 0 --last 80 --jobs 2
    python benchmarks/perception_families.py --families achromatic,small --out rows.json

About one second of CPU a draw. Seeds give the same photographs on every
machine; the counts do not depend on the machine's speed.
"""

from __future__ import annotations

import os

# One core per process: must happen before NumPy (and its BLAS) is imported.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from dataclasses import asdict, dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

from demoplan.perception.photo_families import FAMILIES, family_case, perceive_case  # noqa: E402


@dataclass(frozen=True)
class Draw:
    """One family draw perceived: its score and whether it meets the thresholds."""

    family: str
    seed: int
    side_given: bool
    exit_code: int
    found: int
    needed: int
    false: int

    @property
    def meets(self) -> bool:
        """At least 90 % of the needed tops found, at most one false block (none
        without cubes), exit 0."""
        allowed_false = 1 if self.needed else 0
        return (
            self.exit_code == 0 and self.found >= 0.9 * self.needed and self.false <= allowed_false
        )


def perceive_draw(job: tuple[str, int, bool]) -> Draw:
    """The family ``job`` names at its seed, perceived with or without ``--side``."""
    family, seed, side_given = job
    run = perceive_case(family_case(family, seed), side_given=side_given)
    score = run.score
    return Draw(family, seed, side_given, run.exit_code, score.found, score.needed, score.false)


def _failing(draws: Sequence[Draw]) -> str:
    names = [f"{d.seed}{'+s' if d.side_given else ''}" for d in draws if not d.meets]
    return " ".join(names) if names else "—"


def families_table(draws: Sequence[Draw], first: int, last: int) -> Table:
    """Per family: draws meeting, tops found, false blocks, failing draws; totals."""
    table = Table(
        title=f"Generated families, seeds {first}–{last}, --side given and not "
        "(meets: ≥ 90 % of tops found, ≤ 1 false)"
    )
    for heading in ("family", "draws meeting", "tops found", "false blocks"):
        table.add_column(heading, justify="left" if heading == "family" else "right")
    table.add_column("failing draws (seed, +s: with --side)", overflow="fold")
    for family in sorted({d.family for d in draws}):
        own = [d for d in draws if d.family == family]
        table.add_row(*_row(family, own), _failing(own))
    table.add_section()
    table.add_row(*_row("all", draws), "")
    return table


def _row(name: str, draws: Sequence[Draw]) -> tuple[str, str, str, str]:
    meeting = sum(d.meets for d in draws)
    found, needed = sum(d.found for d in draws), sum(d.needed for d in draws)
    share = f" ({found / needed:.1%})" if needed else ""
    return (
        name,
        f"{meeting}/{len(draws)} ({meeting / max(len(draws), 1):.0%})",
        f"{found}/{needed}{share}",
        str(sum(d.false for d in draws)),
    )


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--first", type=int, default=0, help="first seed (default 0)")
    parser.add_argument("--last", type=int, default=9, help="last seed (default 9)")
    parser.add_argument(
        "--families", default="", help="comma-separated families (default: all of them)"
    )
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--out", type=Path, help="also write every draw as JSON")
    args = parser.parse_args(argv)
    if args.first < 0 or args.last < args.first:
        parser.error("--first must be at least 0 and --last at least --first")
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    families = args.families.split(",") if args.families else sorted(FAMILIES)
    unknown = sorted(set(families) - set(FAMILIES))
    if unknown:
        parser.error(f"unknown families {unknown}; known: {', '.join(sorted(FAMILIES))}")
    args.families = families
    return args


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    console = Console(width=max(Console().width, 140))
    jobs = [
        (family, seed, side)
        for family in args.families
        for seed in range(args.first, args.last + 1)
        for side in (False, True)
    ]
    draws: list[Draw] = []
    with ProcessPoolExecutor(args.jobs) as pool:
        for done, draw in enumerate(pool.map(perceive_draw, jobs, chunksize=2), start=1):
            draws.append(draw)
            if done % 20 == 0 or done == len(jobs):
                console.print(f"[dim]{done}/{len(jobs)} draws[/dim]", highlight=False)
    console.print(families_table(draws, args.first, args.last))
    if args.out:
        args.out.write_text(
            json.dumps([asdict(d) | {"meets": d.meets} for d in draws], indent=1) + "\n"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
