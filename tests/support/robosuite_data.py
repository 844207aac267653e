"""robosuite's human demonstrations (shipped in its PyPI source distributions) for tests.

The cache folder is ``$DEMOPLAN_TEST_DATA`` or ``~/.cache/demoplan-test-data``;
the tarballs live in its ``robosuite/`` folder. Missing tarballs are fetched
with ``pip download --no-binary :all:``; only the six pick-and-place
demonstration folders are extracted, next to the tarballs.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

import numpy as np

from demoplan.segmentation import ObjectTrack, PoseStream

__all__ = [
    "DEMONSTRATIONS",
    "EXPECTED",
    "PEG",
    "PUSHED",
    "RobosuiteDataError",
    "cache_folder",
    "resampled",
    "robosuite_demonstrations",
]

DEMONSTRATIONS: dict[str, tuple[str, str]] = {
    # name: (robosuite version, folder under robosuite/models/assets/demonstrations)
    "SawyerPickPlace": ("0.3.0", "SawyerPickPlace"),
    "SawyerNutAssembly": ("0.3.0", "SawyerNutAssembly"),
    "SawyerStack": ("0.3.0", "SawyerStack"),
    "PickPlace": ("1.0.0", "pick-place/panda"),
    "NutAssembly": ("1.0.0", "nut-assembly/panda"),
    "Stack": ("1.0.0", "stack/panda"),
}
_ASSETS = "robosuite/models/assets/demonstrations"

# The steps read by hand from plots of every object's height over time (see
# tests/segmentation/test_real_recordings.py): (recording, demonstration) → the objects in the
# order they are carried. Each object is carried once and ends where it was put.
EXPECTED: dict[tuple[str, str], list[str]] = {
    ("SawyerPickPlace", "demo_1"): ["Can", "Cereal", "Milk", "Bread"],
    ("SawyerPickPlace", "demo_2"): ["Bread", "Can", "Milk", "Cereal"],
    ("PickPlace", "demo_1"): ["Bread", "Cereal", "Milk", "Can"],
    ("SawyerNutAssembly", "demo_1"): ["SquareNut", "RoundNut"],
    ("SawyerNutAssembly", "demo_2"): ["SquareNut", "RoundNut"],
    ("NutAssembly", "demo_1"): ["RoundNut", "SquareNut"],
    ("SawyerStack", "demo_1"): ["cubeA"],
    ("SawyerStack", "demo_2"): ["cubeA"],
    ("Stack", "demo_1"): ["cubeA"],
}
# NutAssembly: the peg (landmark) each nut goes on.
PEG: dict[str, str] = {"SquareNut": "peg1", "RoundNut": "peg2"}
# Objects pushed along their support (not steps), in order.
PUSHED: dict[tuple[str, str], list[str]] = {("SawyerPickPlace", "demo_1"): ["Bread"]}


class RobosuiteDataError(RuntimeError):
    """The demonstrations could not be found, fetched or extracted."""


def skip_or_fail(exc: Exception) -> None:
    """Skip a test that needs the recordings when they cannot be had — unless
    ``DEMOPLAN_REQUIRE_DATA=1`` (CI sets it), where that is a failure."""
    import pytest

    message = f"robosuite's demonstrations are not available: {exc}"
    if os.environ.get("DEMOPLAN_REQUIRE_DATA") == "1":
        pytest.fail(message)
    pytest.skip(message)


def cache_folder() -> Path:
    """Where the robosuite tarballs are kept."""
    root = os.environ.get("DEMOPLAN_TEST_DATA")
    base = Path(root) if root else Path.home() / ".cache" / "demoplan-test-data"
    return base / "robosuite"


def _tarball(cache: Path, version: str) -> Path:
    path = cache / f"robosuite-{version}.tar.gz"
    if path.is_file():
        return path
    cache.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary", ":all:"]
    command += [f"robosuite=={version}", "-d", str(cache)]
    try:
        subprocess.run(command, check=True, capture_output=True, timeout=600)
    except (OSError, subprocess.SubprocessError) as exc:
        raise RobosuiteDataError(f"pip download robosuite=={version} failed: {exc}") from exc
    if not path.is_file():
        raise RobosuiteDataError(f"pip download did not produce {path.name}")
    return path


def _extract(tarball: Path, version: str, folders: list[str], target: Path) -> None:
    """Extract ``*/models/assets/demonstrations/<folder>/*`` for ``folders`` into ``target``."""
    prefix = f"robosuite-{version}/{_ASSETS}/"
    wanted = tuple(prefix + folder + "/" for folder in folders)
    staging = Path(tempfile.mkdtemp(prefix=".extract-", dir=target.parent))
    try:
        with tarfile.open(tarball) as archive:
            members = [m for m in archive.getmembers() if m.name.startswith(wanted)]
            if not members:
                raise RobosuiteDataError(f"{tarball.name} holds no {prefix}… demonstrations")
            archive.extractall(staging, members=members, filter="data")
        try:
            (staging / f"robosuite-{version}").rename(target)
        except OSError:
            if not target.is_dir():  # another worker finished first otherwise
                raise
    except (OSError, tarfile.TarError) as exc:
        raise RobosuiteDataError(f"cannot extract {tarball}: {exc}") from exc
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def robosuite_demonstrations(cache: Path | None = None) -> dict[str, Path]:
    """The six ``demo.hdf5`` files by name (``SawyerStack``, ``Stack``, …), extracted
    (and downloaded) as needed; raises :class:`RobosuiteDataError`."""
    cache = cache or cache_folder()
    out: dict[str, Path] = {}
    for version in sorted({v for v, _ in DEMONSTRATIONS.values()}):
        names = [n for n, (v, _) in DEMONSTRATIONS.items() if v == version]
        root = cache / f"robosuite-{version}"
        paths = {n: root / _ASSETS / DEMONSTRATIONS[n][1] / "demo.hdf5" for n in names}
        if not all(p.is_file() for p in paths.values()):
            if root.exists():
                shutil.rmtree(root)
            folders = [DEMONSTRATIONS[n][1] for n in names]
            _extract(_tarball(cache, version), version, folders, root)
        missing = [str(p) for p in paths.values() if not p.is_file()]
        if missing:
            raise RobosuiteDataError(f"not in the archive: {', '.join(missing)}")
        out.update(paths)
    return out


def resampled(stream: PoseStream, rate_hz: float, rest_s: float = 0.0) -> PoseStream:
    """The stream at ``rate_hz`` (nearest samples), with ``rest_s`` of the last pose appended."""
    tracks = []
    for track in stream.tracks:
        times = np.arange(track.times[0], track.times[-1] + 1e-9, 1.0 / rate_hz)
        index = np.minimum(np.searchsorted(track.times, times), len(track) - 1)
        extra = np.arange(1, round(rest_s * rate_hz) + 1) / rate_hz + times[-1]
        index = np.concatenate((index, np.full(extra.size, len(track) - 1)))
        times = np.concatenate((times, extra))
        orientations = None if track.orientations is None else track.orientations[index]
        tracks.append(ObjectTrack(track.name, times, track.positions[index], orientations))
    return PoseStream(tuple(tracks), stream.source)
