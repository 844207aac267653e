"""Markers and camera files (``calibrate --markers``, ``perceive --camera``)
go through the same validation as every other document: marker ids are ASCII
whole numbers, numbers are JSON numbers within bounds, matrices are 3 × 3 —
each bad value one line naming the file and the field, never a traceback."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.errors import InputError
from demoplan.perception.calibration import (
    calibration_from_document,
    is_marker_id,
    load_calibration,
    markers_from_document,
)
from tests.hostile.harness import check_refused, run
from tests.support.helpers import EXAMPLES

MARKERS = json.loads((EXAMPLES / "perception" / "markers.json").read_text())
CAMERA: dict[str, Any] = {
    "format": "demoplan/camera-1",
    "image_size": [640, 480],
    "homography": [[0.001, 0.0, 0.0], [0.0, -0.001, 0.48], [0.0, 0.0, 1.0]],
    "markers": {
        "dictionary": "DICT_4X4_50",
        "side": 0.04,
        "ids": [0],
        "corners": {"0": [[0, 0], [10, 0], [10, 10], [0, 10]]},
    },
    "intrinsics": {"camera_matrix": [[800, 0, 320], [0, 800, 240], [0, 0, 1]]},
}


def _markers(change: dict[str, Any]) -> dict[str, Any]:
    document = copy.deepcopy(MARKERS)
    document["markers"] = {**document["markers"], **change.pop("markers", {})}
    return document | change


BAD_MARKERS = {
    "superscript two as an id": ({"markers": {"²": [0.1, 0.1]}}, "markers", "marker id"),
    "an Arabic-Indic 3 as an id": ({"markers": {"٣": [0.1, 0.1]}}, "markers", "marker id"),
    "an id of 5,000 digits": ({"markers": {"9" * 5000: [0.1, 0.1]}}, "markers", "marker id"),
    "a side as a string": ({"side": "0.04"}, "side", "number"),
}


@pytest.mark.parametrize("case", sorted(BAD_MARKERS))
def test_a_bad_markers_file_is_one_line(case: str) -> None:
    change, field, expected = BAD_MARKERS[case]
    with pytest.raises(InputError) as caught:
        markers_from_document(_markers(dict(change)), "markers.json")
    text = str(caught.value)
    assert text.startswith(f"markers.json: {field}") and expected in text, text
    assert "\n" not in text and len(text) < 300


def _camera(path: tuple[str, ...], value: Any) -> dict[str, Any]:
    document = copy.deepcopy(CAMERA)
    where = document
    for key in path[:-1]:
        where = where[key]
    where[path[-1]] = value
    return document


BAD_CAMERAS = {
    "a ragged camera matrix": (
        ("intrinsics", "camera_matrix"),
        [[800, 0], [0, 800, 240], [0, 0, 1]],
    ),
    "a camera matrix of 1e308": (
        ("intrinsics", "camera_matrix"),
        [[1e308, 0, 320], [0, 1e308, 240], [0, 0, 1]],
    ),
    "a ragged homography": (("homography",), [[1, 0, 0], [0, 1], [0, 0, 1]]),
    "a homography whose last entry is 0": (
        ("homography",),
        [[0.001, 0, 0], [0, -0.001, 0.48], [0, 1, 0]],
    ),
    "a corner id of superscript two": (
        ("markers", "corners"),
        {"²": [[0, 0], [1, 0], [1, 1], [0, 1]]},
    ),
    "a corner id of 5,000 digits": (
        ("markers", "corners"),
        {"7" * 5000: [[0, 0], [1, 0], [1, 1], [0, 1]]},
    ),
    "a ragged corner": (("markers", "corners"), {"0": [[0, 0], [1], [1, 1], [0, 1]]}),
    "a side as a string": (("markers", "side"), "0.04"),
}


@pytest.mark.parametrize("case", sorted(BAD_CAMERAS))
def test_a_bad_camera_file_is_one_line(case: str) -> None:
    path, value = BAD_CAMERAS[case]
    with pytest.raises(InputError) as caught:
        calibration_from_document(_camera(path, value), "camera.json")
    text = str(caught.value)
    assert text.startswith(f"camera.json: {path[0]}"), text
    assert "\n" not in text and len(text) < 300


def test_the_unchanged_camera_file_is_read() -> None:
    calibration = calibration_from_document(copy.deepcopy(CAMERA), "camera.json")
    assert calibration.image_size == (640, 480) and set(calibration.marker_corners) == {0}


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=8))
def test_a_marker_id_is_read_exactly_when_it_is_ascii_digits(key: str) -> None:
    document = _markers({"markers": {key: [0.1, 0.1]}})
    if key and len(key) <= 6 and key.isascii() and key.isdigit():
        assert int(key) in markers_from_document(document, "m.json").positions
        assert is_marker_id(key)
    else:
        with pytest.raises(InputError, match="marker id"):
            markers_from_document(document, "m.json")


def test_the_command_answers_in_one_line(tmp_path: Path) -> None:
    camera = tmp_path / "camera.json"
    camera.write_text(json.dumps(_camera(("homography",), [[1, 0, 0], [0, 1, 0], [0, 1, 0]])))
    image = EXAMPLES / "perception" / "blocks-top.png"
    done = run(["perceive", image, "--camera", camera], tmp_path)
    check_refused(done, [f"demoplan: error: {camera}: homography"], codes={1})
    with pytest.raises(InputError):
        load_calibration(camera)
