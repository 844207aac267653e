"""The Plan view's **Model** starts on the model learned last, not the first by
name: a work folder with ``cli-model.json`` (written by ``demoplan learn``) and
``model.json`` (learned in the page afterwards) plans with ``model.json`` after
a reload, and the other way round (docs/studio-api.md, ``GET /api/files``)."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from demoplan.learning import learn
from demoplan.learning.modelfile import save_model
from demoplan.studio.app import create_app
from tests.support.lunch_box import lunch_demonstrations

NAMES = ("cli-model.json", "model.json")


@pytest.fixture(scope="module")
def model_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("model") / "model.json"
    save_model(learn(lunch_demonstrations()), path)
    return path


def work_folder(root: Path, model_file: Path, order: tuple[str, ...]) -> Path:
    """A work folder holding the model under each of ``order``'s names, written
    one second apart in that order (the file times set, not waited for)."""
    folder = root / "work"
    folder.mkdir(exist_ok=True)
    for second, name in enumerate(order):
        path = folder / name
        path.write_bytes(model_file.read_bytes())
        os.utime(path, ns=(1_700_000_000_000_000_000 + second * 10**9,) * 2)
    return folder


@pytest.fixture
def client(tmp_path: Path) -> Iterator[TestClient]:
    with TestClient(create_app(tmp_path / "work"), base_url="http://127.0.0.1") as test_client:
        yield test_client


@pytest.mark.parametrize("order", [NAMES, NAMES[::-1]], ids=["page-last", "cli-last"])
def test_the_listing_names_the_model_written_last(
    tmp_path: Path, model_file: Path, order: tuple[str, ...]
) -> None:
    folder = work_folder(tmp_path, model_file, order)
    with TestClient(create_app(folder), base_url="http://127.0.0.1") as client:
        listing = client.get("/api/files").json()
    assert listing["models"] == sorted(NAMES)  # the list stays by name
    assert listing["latest_model"] == order[-1]


def test_no_model_is_none(client: TestClient) -> None:
    assert client.get("/api/files").json()["latest_model"] is None


@pytest.mark.slow
@pytest.mark.parametrize("order", [NAMES, NAMES[::-1]], ids=["page-last", "cli-last"])
def test_the_plan_view_starts_on_the_model_learned_last(
    tmp_path: Path, model_file: Path, order: tuple[str, ...]
) -> None:
    from tests.support.studio_browser import studio_page

    folder = work_folder(tmp_path, model_file, order)
    with studio_page(folder, tmp_path) as page:  # opened afresh: no run, no choice yet
        assert page.tab.locator("#plan-model").input_value() == order[-1]
