"""Frames of a run in robosuite (``run --sim robosuite:ENV --frames DIR``, and
the worst runs' storyboards of ``evaluate --sim robosuite:ENV``): robosuite's
scene rendered offscreen by MuJoCo (``MUJOCO_GL=egl``) from robosuite's own
``agentview`` camera at the run's key moments — the start, after each grasp
and put-down, the end — with the captions and failure marks of
:class:`~demoplan.execution.frames.FrameWriter`. Where MuJoCo cannot render
(no EGL, ``MUJOCO_GL`` set to something that does not work here) the frames
are the writer's drawings from above and a warning says why.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from demoplan.execution.executor import RunEvent
from demoplan.execution.frames import FrameWriter
from demoplan.execution.world import Observation
from demoplan.model import Pose

__all__ = ["CAMERA", "FramedRobosuiteWorld", "SceneCamera"]

logger = logging.getLogger(__name__)

CAMERA = "agentview"
"""robosuite's camera over the table from behind the robot (every environment has it)."""
WIDTH, HEIGHT = 480, 360
"""Pixels of a frame (within robosuite's offscreen buffer, 640 × 480)."""
COLLISION_GROUP = 0
"""robosuite's collision geoms' group (its visual geoms are group 1): not drawn."""


class SceneCamera:
    """Pictures of a robosuite environment's scene, or None where MuJoCo cannot render."""

    def __init__(self, env: Any) -> None:
        self.env = env
        self.renderer: Any = None
        self.failure: str | None = None
        """Why nothing renders (set at the first picture that fails)."""

    def picture(self) -> np.ndarray | None:
        """The scene from :data:`CAMERA` (RGB, ``HEIGHT × WIDTH × 3``), or None."""
        if self.failure is not None:
            return None
        os.environ.setdefault("MUJOCO_GL", "egl")  # robosuite set it already where it ran
        import mujoco

        try:
            if self.renderer is None:
                self.renderer = mujoco.Renderer(self.env.sim.model._model, HEIGHT, WIDTH)
            options = mujoco.MjvOption()
            options.geomgroup[COLLISION_GROUP] = 0
            self.renderer.update_scene(self.env.sim.data._data, camera=CAMERA, scene_option=options)
            image: np.ndarray = self.renderer.render().copy()
        except Exception as exc:  # the GL back end's own errors vary
            self.failure = f"MuJoCo cannot render here ({type(exc).__name__}: {exc})"
            logger.warning("%s; robosuite's frames are drawn from above instead", self.failure)
            return None
        return image

    def close(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None


class FramedRobosuiteWorld:
    """A robosuite world as the executor acts on it, a frame captured after each
    grasp and put-down; :meth:`heard` takes the executor's events (the start
    frame at the first plan, failures marked)."""

    def __init__(self, world: Any, writer: FrameWriter, camera: SceneCamera) -> None:
        self._world = world
        self.writer = writer
        self.camera = camera
        self.name: str = world.name

    def heard(self, on_event: Callable[[RunEvent], object] | None) -> Callable[[RunEvent], None]:
        """What hears the run's events: the frames, then ``on_event``."""

        def hear(event: RunEvent) -> None:
            if event.kind == "plan" and not self.writer.frames:
                self.writer.targets = dict(event.targets)
                self.writer.capture(self._world.observe(), "start", self.camera.picture())
            elif event.kind == "failure":
                self.writer.mark_failure(event.text)
            if on_event is not None:
                on_event(event)

        return hear

    def capture_end(self, final: Observation) -> None:
        """The last frame and the storyboard."""
        self.writer.capture(final, "end", self.camera.picture())
        self.writer.storyboard()

    def observe(self) -> Observation:
        observation: Observation = self._world.observe()
        return observation

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        self._world.grasp(obj, axis, where)
        self._frame(f"GRASP {obj}")

    def put_down(self, obj: str, pose: Pose) -> None:
        self._world.put_down(obj, pose)
        self._frame(f"PUT_DOWN {obj}")

    def between_actions(self, upcoming: Sequence[Pose] = ()) -> None:
        self._world.between_actions(upcoming)

    @property
    def motion_failures(self) -> list[str]:  # what the robot noticed (executor.ROBOT_NOTES)
        failures: list[str] = self._world.motion_failures
        return failures

    @property
    def grasp_problems(self) -> list[str]:
        problems: list[str] = self._world.grasp_problems
        return problems

    def _frame(self, caption: str) -> None:
        self.writer.capture(
            self._world.observe(), f"{len(self.writer.frames)}: {caption}", self.camera.picture()
        )
