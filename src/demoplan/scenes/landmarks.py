"""Landmarks in a scene: where they stand, and the scene completed from the model.

A landmark is a static thing states may be relative to (a tray, a fixture).
Its pose comes from the scene. A scene may leave out only a landmark that
stood still in every demonstration recording it (within :data:`LANDMARK_STILL`):
falling back to one demonstration's pose for a landmark that moved would put
everything relative to it in the wrong place, silently. Its shape and size
(if known) come from the scene, else from the demonstrations; so do the
colours of objects and landmarks (a file's ``colour``, docs/formats.md).
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from demoplan.errors import InputError
from demoplan.model import Pose, TaskModel, demonstrated_colours, demonstrated_shapes
from demoplan.scenes.scene import Scene, complete_geometry
from demoplan.wording import did_you_mean

__all__ = [
    "LANDMARK_STILL",
    "complete_scene",
    "landmark_poses",
    "moved_landmarks",
    "referenced_landmarks",
]

logger = logging.getLogger(__name__)


def complete_scene(scene: Scene, model: TaskModel) -> Scene:
    """``scene`` with every object's geometry (:func:`complete_geometry`), every
    landmark's pose (:func:`landmark_poses`), the shape of every landmark
    the scene or the demonstrations give one for, and the colours they give
    (the scene's own first: a thing taught red stays red in a scene that
    names no colour)."""
    scene = complete_geometry(scene, model)
    poses = landmark_poses(model, scene)
    known = demonstrated_shapes(model.demonstrations)
    shapes = {name: known[name] for name in poses if name in known}
    shapes.update(scene.landmark_geometry)
    names = {*scene.names, *poses}
    taught = demonstrated_colours(model.demonstrations)
    colours = {n: c for n, c in taught.items() if n in names} | scene.given_colours
    return replace(
        scene,
        landmarks=tuple(poses.items()),
        landmark_geometry=tuple((n, shapes[n]) for n in poses if n in shapes),
        colours=tuple(colours.items()),
    )


LANDMARK_STILL = (0.005, 2.0)
"""A landmark that moved less than this between demonstrations (m, degrees; or
three times the model's precision, if larger) stood still: a scene may leave
it out. One that moved more must be given by the scene."""


def landmark_poses(model: TaskModel, scene: Scene) -> dict[str, Pose]:
    """Each landmark's pose in ``scene``: the scene's own; else, for a landmark
    that stood still in every demonstration recording it, that pose (said in
    one warning when the task refers to it). A landmark the task refers to that
    the scene lacks and that moved between the demonstrations is an InputError
    naming it (with "did you mean" for a near name in the scene): falling back
    to one demonstration's pose would put everything relative to it in the
    wrong place. A near name in the scene (``Tray``) is the error's field, and
    the model's name the "did you mean"."""
    poses = dict(scene.landmarks)
    given = set(poses) | set(scene.names)
    needed = referenced_landmarks(model)
    shapes = demonstrated_shapes(model.demonstrations)
    tolerance = _still_tolerance(model)
    recorded: dict[str, list[Pose]] = {}
    for demo in model.demonstrations:
        for name, pose in demo.landmarks:
            recorded.setdefault(name, []).append(pose)
    for name, seen in recorded.items():
        if name in given:
            continue
        moved = _movement(seen, tolerance)
        if moved is None:
            poses[name] = seen[0]
            if name in needed or name in shapes:
                x, y = seen[0].position[:2]
                logger.warning(
                    "%s: landmark %r is not in the scene; taken to stand where it stood in "
                    "%s (%.3f, %.3f)",
                    scene.source,
                    name,
                    "the demonstration" if len(seen) == 1 else f"all {len(seen)} demonstrations",
                    x,
                    y,
                )
        elif name in needed:
            # a near name in the scene is the field, the model's name the suggestion
            misspelt = next(
                (n for n in (*scene.landmark_names, *scene.names) if did_you_mean(n, [name])), None
            )
            field = "landmarks"
            hint = ""
            if misspelt is not None:
                kind = "landmarks" if misspelt in scene.landmark_names else "objects"
                field = f"{kind}.{misspelt}"
                hint = f"; the scene's {misspelt!r} is not it" + did_you_mean(misspelt, [name])
            raise InputError(
                f"landmark {name!r} is missing; it stood at different places in the "
                f"demonstrations ({moved}), so the scene must say where it is now "
                f'("landmarks": {{"{name}": {{"position": […]}}}}){hint}',
                source=scene.source,
                field=field,
            )
    return poses


def moved_landmarks(model: TaskModel) -> set[str]:
    """The landmarks that stood at different places in the demonstrations
    (beyond :data:`LANDMARK_STILL`, or three times the model's precision): the
    ones whose pose the task's placements may follow, and a scene must give."""
    recorded: dict[str, list[Pose]] = {}
    for demo in model.demonstrations:
        for name, pose in demo.landmarks:
            recorded.setdefault(name, []).append(pose)
    tolerance = _still_tolerance(model)
    return {name for name, seen in recorded.items() if _movement(seen, tolerance) is not None}


def referenced_landmarks(model: TaskModel) -> set[str]:
    """The landmarks some state's position or orientation is relative to."""
    known = {name for demo in model.demonstrations for name, _ in demo.landmarks}
    references = {
        reference
        for state in model.states
        for reference in (state.position.reference, state.orientation.reference)
        if reference is not None
    }
    return references & known


def _still_tolerance(model: TaskModel) -> tuple[float, float]:
    if model.precision is None:
        return LANDMARK_STILL
    return (
        max(LANDMARK_STILL[0], 3.0 * model.precision[0]),
        max(LANDMARK_STILL[1], 3.0 * model.precision[1]),
    )


def _movement(poses: list[Pose], tolerance: tuple[float, float]) -> str | None:
    """How far apart ``poses`` lie, in words, when beyond ``tolerance`` (m, deg); else None."""
    positions = np.array([pose.position for pose in poses], dtype=float)
    distance = float(np.max(np.linalg.norm(positions - positions[0], axis=1)))
    yaws = [pose.yaw for pose in poses if pose.orientation is not None]
    turn = 0.0  # a landmark's frame is as given: no symmetry
    if len(yaws) > 1:
        turn = max(abs((y - yaws[0] + 180.0) % 360.0 - 180.0) for y in yaws)
    if distance <= tolerance[0] and turn <= tolerance[1]:
        return None
    return f"{distance * 1000:.0f} mm and {turn:.0f}° apart"
