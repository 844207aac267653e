"""``demoplan run --sim mujoco --perception camera``: the loop on vision.

The executor sees the simulated world only through the orthographic top
camera: after every action the hand is parked beside the table, the picture
is taken, the blocks are found in it (:mod:`demoplan.perception.blocks`) and
their heights are tracked from occlusion (:mod:`demoplan.perception.stacking`).
What the hand holds comes from the gripper itself (a robot feels that). The
grasps go where perception says the object is. The start's stacking comes
from the scene: a camera above cannot see what is under a block it never saw
being covered.

Blocks are told apart by colour: every object's type (its name, when it
declares none) must be a colour the camera names, and a scene may not give a
block another colour than its type's (the camera would see that one). Several blocks of one colour
(``red`` and ``red2``, both of type ``red``) look alike; each keeps its
identity from picture to picture by proximity — to where it was last seen, or,
for the block just put down, to where it was put (:meth:`BlockTracker.identify
<demoplan.perception.stacking.BlockTracker.identify>`).
"""

from __future__ import annotations

from collections.abc import Sequence

from demoplan.errors import UsageError
from demoplan.execution.faults import InjectedFault
from demoplan.execution.physics import MujocoWorld
from demoplan.execution.world import Observation
from demoplan.model import ObjectGeometry, Pose
from demoplan.perception.blocks import PerceptionSettings, detect_blocks
from demoplan.perception.stacking import BlockTracker, TrackedBlock
from demoplan.plotting.colours import NAMED
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.scene import Scene

PERCEIVED_COLOURS = ("red", "green", "blue", "yellow", "wood")
"""The block colours the top camera tells apart (as in demoplan.plotting.colours)."""

__all__ = ["CameraWorld"]


class CameraWorld:
    """A MuJoCo world observed through its top camera (see the module docstring)."""

    name = "mujoco+camera"

    def __init__(
        self, world: MujocoWorld, scene: Scene, settings: PerceptionSettings | None = None
    ):
        plain = [o.name for o in scene.objects if o.kind not in PERCEIVED_COLOURS]
        if plain:
            colours = ", ".join(sorted(PERCEIVED_COLOURS))
            raise UsageError(
                "--perception camera tells blocks apart by colour: an object's type (its "
                f"name, when it declares none) must be one of {colours}; "
                f"{', '.join(plain)} {'is' if len(plain) == 1 else 'are'} not"
            )
        given = scene.given_colours
        recoloured = [o for o in scene.objects if given.get(o.name, NAMED[o.kind]) != NAMED[o.kind]]
        if recoloured:  # the first, named as every bad field is: file, field, what was expected
            block = recoloured[0]
            where = ": ".join(p for p in (scene.source, f"objects.{block.name}.colour") if p)
            raise UsageError(
                f"{where}: {given[block.name]} is another colour than its type {block.kind}'s "
                f"({NAMED[block.kind]}), by which --perception camera tells blocks apart; "
                "that colour or none expected (or run with --perception state)"
            )
        self.world = world
        sides = [o.geometry.size[0] for o in scene.objects if o.geometry is not None] or [0.04]
        # The blocks' sizes are known: a strip of a covered block is not a small block.
        self.settings = settings or PerceptionSettings(
            min_side=0.85 * min(sides), max_side=1.15 * max(sides)
        )
        _refuse_block_sized_landmarks(scene, self.settings)
        self.tracker = BlockTracker(
            TrackedBlock(
                o.name,
                o.pose.position[0],
                o.pose.position[1],
                o.pose.position[2],
                ((o.pose.yaw + 45.0) % 90.0) - 45.0,
                o.geometry.size[0] if o.geometry else 0.04,
                o.kind,
            )
            for o in scene.objects
        )
        self.geometry = {o.name: o.geometry for o in scene.objects if o.geometry is not None}
        self.pictures = 0
        self.placed: dict[str, tuple[float, float]] = {}
        """Blocks put down since the last picture, and where (x, y)."""

    def observe(self) -> Observation:
        held = self.world.observe().held  # the gripper's own sense
        image = self.world.top_image()
        self.pictures += 1
        detected = detect_blocks(image, self.world.top_camera, self.settings)
        blocks = self.tracker.update(detected, held, self.placed)
        self.placed = {}
        poses = {n: Pose((b.x, b.y, b.z), quat_from_yaw(b.yaw)) for n, b in blocks.items()}
        geometry = dict(self.geometry)
        for n, b in blocks.items():
            geometry.setdefault(n, ObjectGeometry("box", (b.side, b.side, b.side)))
        return Observation(poses, held, geometry)

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        self.world.grasp(obj, axis, where)

    def put_down(self, obj: str, pose: Pose) -> None:
        self.placed[obj] = (pose.position[0], pose.position[1])
        self.world.put_down(obj, pose)

    def between_actions(self, upcoming: Sequence[Pose] = ()) -> None:
        self.world.between_actions(upcoming)

    def why_not_graspable(self, obj: str) -> str | None:
        return self.world.why_not_graspable(obj)

    def why_not_reachable(self, obj: str, pose: Pose) -> str | None:
        check = getattr(self.world, "why_not_reachable", None)
        return None if check is None else check(obj, pose)

    def why_not_reachable_together(self, places: Sequence[tuple[str, Pose]]) -> str | None:
        check = getattr(self.world, "why_not_reachable_together", None)
        return None if check is None else check(places)

    @property
    def injected(self) -> list[InjectedFault]:
        """The faults the simulated world injected (the camera does not see them)."""
        return self.world.injected

    @property
    def motion_failures(self) -> list[str]:
        """What the robot noticed (executor.ROBOT_NOTES): the motions it refused."""
        return list(getattr(self.world, "motion_failures", ()))

    @property
    def grasp_problems(self) -> list[str]:
        """The grasps the robot felt fail (its own sensing, not the camera's)."""
        return list(getattr(self.world, "grasp_problems", ()))

    def render(self) -> object:
        return self.world.render()

    def close(self) -> None:
        self.world.close()


def _refuse_block_sized_landmarks(scene: Scene, settings: PerceptionSettings) -> None:
    """Refuse, in one line naming the file and the field (exit 2), a landmark whose
    footprint is a square of a block's size: from above the top camera sees it as
    one more block (a 4 × 4 cm mat was taken for a block and the run ended blaming
    a block's position the file never gave). A landmark larger or longer than a
    block (a tray, a caddy) is told apart by its size."""
    for name, geometry in scene.landmark_geometry:
        width, depth = geometry.size[0], geometry.size[1]
        square = geometry.shape == "box" and min(width, depth) >= 0.8 * max(width, depth)
        if square and settings.min_side <= max(width, depth) <= settings.max_side:
            where = ": ".join(p for p in (scene.source, f"landmarks.{name}.size") if p)
            raise UsageError(
                f"{where}: {width * 100:.1f} × {depth * 100:.1f} cm is a block's size "
                f"({settings.min_side * 100:.1f}–{settings.max_side * 100:.1f} cm across), "
                "which --perception camera would see as one more block; a landmark "
                "larger or longer than the blocks expected (or run with --perception state)"
            )
