"""Generated fixture tasks: things put into a fixture (a lunch box, a kit tray)
that the demonstrations move and may or may not turn.

The fixture is either a landmark with a shape or an object the demonstrations
never move (its pose given as ``initial``); it stands at a different place in
every demonstration (at least 10 cm apart, so that "relative to it" is
decided by the data) and is turned by at most ``turn`` degrees about a common
yaw (``turn`` 0: never turned, so every orientation is a tie between the
fixture and the world). Each item lies at a fixed offset and yaw in the
fixture's frame, with placement noise of 1–3 mm and 0.3°. The truth — each
item's offset and yaw in the fixture's frame — is returned beside the
demonstrations, and :func:`fixture_scene` puts the fixture anywhere, turned
by any angle, for planning.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.scene import Scene, SceneObject

__all__ = ["FIXTURE", "ITEM_SHAPES", "FixtureTask", "fixture_scene", "fixture_task", "rotate"]

FIXTURE = ObjectGeometry("box", (0.26, 0.18, 0.02))
"""The lunch box of the issue: 26 × 18 × 2 cm."""
ITEM_SHAPES = (
    ObjectGeometry("box", (0.10, 0.09, 0.03)),  # a sandwich: the same after half a turn
    ObjectGeometry("box", (0.04, 0.06, 0.10)),  # a juice box
    ObjectGeometry("box", (0.12, 0.025, 0.025)),  # a carrot
    ObjectGeometry("box", (0.05, 0.03, 0.02)),
)
"""Items: boxes with two different sides, the same after a half turn (180°)."""
ITEM_PERIOD = 180.0


def rotate(yaw_deg: float, xy: np.ndarray) -> np.ndarray:
    """``xy`` (…, 2) turned by ``yaw_deg`` about z."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    turned: np.ndarray = np.asarray(xy, dtype=float) @ np.array([[c, s], [-s, c]])
    return turned


@dataclass(frozen=True)
class FixtureTask:
    """Demonstrations of items put into a fixture, and the truth: each item's
    offset (x, y) and yaw (degrees) in the fixture's frame."""

    demos: list[Demonstration]
    items: list[str]
    offsets: dict[str, tuple[float, float]]
    yaws: dict[str, float]
    fixture_yaws: list[float]
    landmark: bool
    sigma: float

    def _repr_pretty_(self, printer: Any, cycle: bool) -> None:  # hypothesis' reports
        printer.text(repr(self))

    def __repr__(self) -> str:  # short, for hypothesis' falsifying examples
        turns = ", ".join(f"{y:.1f}°" for y in self.fixture_yaws)
        kind = "landmark" if self.landmark else "object"
        return f"FixtureTask({kind}, {len(self.items)} items, fixture at {turns}, σ={self.sigma})"


def fixture_task(
    rng: np.random.Generator, n_items: int, n_demos: int, *, turn: float, landmark: bool
) -> FixtureTask:
    """``n_demos`` demonstrations putting ``n_items`` items into the fixture
    ``lunchbox`` (a landmark, or an unmoved object where not ``landmark``),
    which stands at ``base yaw + U(−turn, turn)`` in each, two of them at
least ``turn``/2 apart (module docstring)."""
    sigma = float(rng.uniform(0.001, 0.003))
    while True:  # items 6 cm apart inside the box's 26 × 18 cm
        offsets = rng.uniform((-0.09, -0.06), (0.09, 0.06), (n_items, 2))
        if all(
            np.linalg.norm(offsets[i] - offsets[j]) >= 0.06
            for i, j in itertools.combinations(range(n_items), 2)
        ):
            break
    while True:
        places = rng.uniform((0.3, 0.2), (0.9, 0.6), (n_demos, 2))
        if all(np.linalg.norm(a - b) >= 0.1 for a, b in itertools.combinations(places, 2)):
            break
    base = float(rng.uniform(-45.0, 45.0))
    turns = np.zeros(n_demos)
    while turn > 0 and np.ptp(turns) < turn / 2:  # turned: by at least turn/2 between two
        turns = rng.uniform(-turn, turn, n_demos)
    item_yaws = rng.uniform(-90.0, 90.0, n_items)
    items = [f"item{i}" for i in range(n_items)]
    top = FIXTURE.size[2]
    demos, fixture_yaws = [], []
    for d in range(n_demos):
        yaw = base + float(turns[d])
        fixture_yaws.append(yaw)
        fixture = Pose((float(places[d][0]), float(places[d][1]), 0.0), quat_from_yaw(yaw))
        steps = []
        for i in rng.permutation(n_items):
            xy = places[d] + rotate(yaw, offsets[i]) + rng.normal(0, sigma, 2)
            item_yaw = yaw + float(item_yaws[i]) + float(rng.normal(0, 0.3))
            position = (float(xy[0]), float(xy[1]), top)
            steps.append(Step(items[i], Pose(position, quat_from_yaw(item_yaw))))
        shapes = tuple((n, ITEM_SHAPES[i % len(ITEM_SHAPES)]) for i, n in enumerate(items))
        demos.append(
            Demonstration(
                f"lunch-{d + 1}",
                tuple(steps),
                objects=(("lunchbox", FIXTURE), *shapes),
                landmarks=(("lunchbox", fixture),) if landmark else (),
                initial=() if landmark else (("lunchbox", fixture),),
            )
        )
    return FixtureTask(
        demos,
        items,
        {n: (float(offsets[i][0]), float(offsets[i][1])) for i, n in enumerate(items)},
        {n: float(item_yaws[i]) for i, n in enumerate(items)},
        fixture_yaws,
        landmark,
        sigma,
    )


def fixture_scene(task: FixtureTask, fixture: Pose) -> Scene:
    """The items on a row away from the fixture (y = −0.5 m, yaw 0), the fixture at ``fixture``."""
    objects = [
        SceneObject(name, Pose((0.2 + 0.15 * k, -0.5, 0.0), quat_from_yaw(0.0)), shape)
        for k, (name, shape) in enumerate(
            (n, ITEM_SHAPES[i % len(ITEM_SHAPES)]) for i, n in enumerate(task.items)
        )
    ]
    if task.landmark:
        return Scene(
            tuple(objects),
            landmarks=(("lunchbox", fixture),),
            landmark_geometry=(("lunchbox", FIXTURE),),
        )
    return Scene((SceneObject("lunchbox", fixture, FIXTURE), *objects))
