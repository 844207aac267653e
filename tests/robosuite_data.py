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

__all__ = ["DEMONSTRATIONS", "RobosuiteDataError", "cache_folder", "robosuite_demonstrations"]

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


class RobosuiteDataError(RuntimeError):
    """The demonstrations could not be found, fetched or extracted."""


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
