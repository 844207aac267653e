"""The studio's work folder changed under it — removed, replaced by a file,
made read-only: every request is answered in one line saying what happened to
the folder (503), and nothing is logged as a traceback."""

from __future__ import annotations

import errno
import logging
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from demoplan.studio.app import create_app
from tests.hostile.harness import check_refused, run
from tests.studio.test_studio_api import blocks_demonstrations, scene_body


@pytest.fixture
def studio(tmp_path: Path) -> Iterator[tuple[TestClient, Path]]:
    folder = tmp_path / "work"
    app = create_app(folder)
    with TestClient(app, base_url="http://127.0.0.1", raise_server_exceptions=False) as client:
        yield client, folder


def _requests(client: TestClient) -> list[tuple[str, Any]]:
    body = {"document": blocks_demonstrations()[0]}
    scene = {"document": scene_body(), "name": "fig4.json"}
    return [
        ("list the files", lambda: client.get("/api/files")),
        ("save a demonstration", lambda: client.post("/api/demonstrations", json=body)),
        ("save a scene", lambda: client.post("/api/scenes", json=scene)),
    ]


def _removed(folder: Path) -> None:
    shutil.rmtree(folder)


def _replaced(folder: Path) -> None:
    shutil.rmtree(folder)
    folder.write_text("not a folder")


CHANGES: dict[str, tuple[Callable[[Path], None], str]] = {
    "removed": (_removed, "was removed while the studio runs"),
    "replaced by a file": (_replaced, "is no longer a folder"),
}


@pytest.mark.parametrize("change", sorted(CHANGES))
def test_a_folder_changed_under_the_studio_is_answered_in_one_line(
    studio: tuple[TestClient, Path], change: str, caplog: pytest.LogCaptureFixture
) -> None:
    client, folder = studio
    requests = _requests(client)
    make_change, expected = CHANGES[change]
    make_change(folder)
    with caplog.at_level(logging.DEBUG):
        for what, request in requests:
            answer = request()
            assert answer.status_code == 503, (what, answer.text)
            text = answer.json()["detail"]
            assert f"the work folder {folder.resolve()} {expected}" in text, (what, text)
            assert "\n" not in text
    assert "Traceback" not in caplog.text and "internal error" not in caplog.text


def test_a_read_only_folder_is_named_as_such(
    studio: tuple[TestClient, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A read-only folder cannot be made here (the tests may run as root, who
    writes anyway): the write is refused as the kernel refuses it, EROFS."""
    client, folder = studio

    def read_only(*args: Any, **kwargs: Any) -> Any:
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr("demoplan.studio.workfolder.tempfile.mkstemp", read_only)
    answer = client.post("/api/demonstrations", json={"document": blocks_demonstrations()[0]})
    assert answer.status_code == 503
    assert answer.json()["detail"].startswith(
        f"the work folder {folder.resolve()} cannot be written"
    )
    assert "was it made read-only?" in answer.json()["detail"]
    assert client.get("/api/files").status_code == 200  # reading still works


@pytest.mark.parametrize(
    ("make", "said"),
    [
        (lambda p: p.write_text("notes\n"), "is a file, not a folder; a work folder expected"),
        (lambda p: p.symlink_to("/dev/null"), "is a device, pipe or socket, not a folder"),
    ],
    ids=["a-file", "a-device"],
)
def test_a_work_folder_that_is_a_file_is_named_as_such(
    tmp_path: Path, make: Callable[[Path], Any], said: str
) -> None:
    """``studio --workdir notes.txt`` answered ``cannot make the work folder
    (file exists)``, as if the folder were missing; it is a file."""
    where = tmp_path / "notes.txt"
    make(where)
    answer = run(["studio", "--workdir", where, "--no-browser", "--port", "0"], tmp_path)
    check_refused(answer, [str(where)], codes={1})
    assert said in answer.stderr, answer
