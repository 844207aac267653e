"""How fast ``demoplan studio`` starts: the time from spawning
``demoplan studio --no-browser --port 0`` to its URL printed, and from there
to the first page (``GET /``) answered; the median of N starts (issue 28's
targets: started in under 2 s, the first page in under 100 ms).

    python benchmarks/studio_start.py             # 10 starts
    python benchmarks/studio_start.py --runs 3    # fewer
    python benchmarks/studio_start.py --out start.json

Each start is a new process in a new empty work folder, stopped with Ctrl-C
(SIGINT) after its answer; a start that does not exit 130 is reported.
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from rich.console import Console

from common import Target, median, package_version, print_targets

STARTED_TARGET = 2.0  # s: spawned → URL printed
FIRST_PAGE_TARGET = 0.1  # s: URL printed → GET / answered


def command() -> list[str]:
    script = Path(sys.executable).parent / "demoplan"
    return [str(script)] if script.exists() else [sys.executable, "-m", "demoplan.cli"]


def one_start(folder: Path) -> tuple[float, float, int]:
    """Seconds to the URL, seconds from it to the first page, and the exit code."""
    start = time.perf_counter()
    process = subprocess.Popen(
        [*command(), "studio", "--no-browser", "--port", "0", "--workdir", str(folder)],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        printed = time.perf_counter()
        url = next(word for word in line.split() if word.startswith("http://"))
        with urllib.request.urlopen(url, timeout=60) as page:
            page.read()
        answered = time.perf_counter()
        process.send_signal(signal.SIGINT)
        code = process.wait(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    return printed - start, answered - printed, code


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=10, help="starts to time (default 10)")
    parser.add_argument("--out", type=Path, help="also write every figure as JSON here")
    args = parser.parse_args()
    console = Console()
    console.print(
        f"demoplan studio start benchmark — {args.runs} starts; Python "
        f"{platform.python_version()}, FastAPI {package_version('fastapi')}, uvicorn "
        f"{package_version('uvicorn')}, {platform.machine()}",
        highlight=False,
    )
    started: list[float] = []
    first_page: list[float] = []
    codes: list[int] = []
    for _ in range(args.runs):
        folder = Path(tempfile.mkdtemp(prefix="studio-start-"))
        try:
            to_url, to_page, code = one_start(folder)
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        started.append(to_url)
        first_page.append(to_page)
        codes.append(code)
    up, page = median(started), median(first_page)
    assert up is not None and page is not None
    console.print(
        f"spawned → URL printed: median {up:.3f} s (min {min(started):.3f}, max "
        f"{max(started):.3f}); URL → first page: median {1000 * page:.1f} ms (min "
        f"{1000 * min(first_page):.1f}, max {1000 * max(first_page):.1f})",
        highlight=False,
    )
    stopped = sum(code == 130 for code in codes)
    print_targets(
        console,
        [
            Target("started in under 2 s", up < STARTED_TARGET, f"median {up:.3f} s"),
            Target(
                "first page in under 100 ms",
                page < FIRST_PAGE_TARGET,
                f"median {1000 * page:.1f} ms",
            ),
            Target("Ctrl-C exits 130", stopped == len(codes), f"{stopped} of {len(codes)}"),
        ],
    )
    if args.out is not None:
        figures = {"started_s": started, "first_page_s": first_page, "exit_codes": codes}
        args.out.write_text(json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    main()
