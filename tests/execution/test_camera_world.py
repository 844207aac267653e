"""``--perception camera``'s scene checks: what the top camera would mistake."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from demoplan.errors import UsageError
from demoplan.scenes.scene import scene_from_document

ROOT = Path(__file__).resolve().parents[2]


def _pyramid_with_landmark(size: list[float], shape: str = "box") -> dict[str, Any]:
    document: dict[str, Any] = json.loads(
        (ROOT / "examples" / "scenes" / "pyramid-fig4.json").read_text()
    )
    document["landmarks"] = {"mat": {"position": [0.1, -0.15], "size": size, "shape": shape}}
    return document


def _camera_world(document: dict[str, Any]) -> Any:
    pytest.importorskip("mujoco")
    from demoplan.execution.camera_world import CameraWorld
    from demoplan.execution.physics import MujocoWorld

    scene = scene_from_document(document, "plain_mark.json")
    return CameraWorld(MujocoWorld(scene), scene)


def test_a_landmark_of_a_block_s_size_is_refused_naming_its_size() -> None:
    """A 4 × 4 cm mat beside 4 cm blocks is one more block to the top camera: the
    run was refused at its end blaming ``objects.block1.position``, a field the
    file never had; now it is refused first, naming the landmark's size."""
    with pytest.raises(UsageError) as error:
        _camera_world(_pyramid_with_landmark([0.04, 0.04, 0.01]))
    message = str(error.value)
    assert error.value.exit_code == 2 and "\n" not in message
    assert message.startswith("plain_mark.json: landmarks.mat.size: 4.0 × 4.0 cm is a block's size")


@pytest.mark.parametrize(
    ("size", "shape"),
    [([0.2, 0.2, 0.01], "box"), ([0.04, 0.12, 0.01], "box"), ([0.04, 0.04, 0.01], "cylinder")],
    ids=["tray", "strip", "disc"],
)
def test_a_landmark_the_camera_tells_from_a_block_is_accepted(
    size: list[float], shape: str
) -> None:
    """Larger (a tray), longer (a strip) or round (a disc): the detector does not
    take it for a block, and the scene is accepted."""
    world = _camera_world(_pyramid_with_landmark(size, shape))
    assert world.world.scene.landmark_names == ("mat",)
