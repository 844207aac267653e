"""Region goals (docs/learning.md, "Region goals"): a state whose placements
all lie inside one compartment of the landmark they are relative to (a bin's
compartment, declared with the landmark: docs/formats.md "Landmark") is placed
anywhere inside that compartment, not at the mean of the demonstrated points.

The paper learns a point per state (§IV.A, eq. 1: the mean of the members'
relative positions); a compartment is a region the demonstrations cannot tell
apart from a point, but the landmark's geometry can: every demonstrated
placement inside it says only "in there". The mean stays the state's value
(the target where nothing else decides).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from demoplan.model import LEVEL_TOLERANCE, Compartment, Demonstration, Pose, State
from demoplan.rotations import rotate_vectors

__all__ = ["in_compartment", "local_point", "with_regions"]

SAME_COMPARTMENT = 0.001
"""m: two demonstrations' compartments of a landmark whose bounds agree this
closely are one compartment."""


def local_point(point: Sequence[float], frame: Pose) -> np.ndarray:
    """``point`` (world) in the frame of ``frame`` (its position the origin)."""
    offset: np.ndarray = np.asarray(point, dtype=float) - np.asarray(frame.position, dtype=float)
    if frame.orientation is None:
        return offset
    x, y, z, w = frame.orientation
    inverse = np.array([[-x, -y, -z, w]], dtype=float)
    turned: np.ndarray = rotate_vectors(inverse, offset[None, :])[0]
    return turned


def in_compartment(
    local: Sequence[float] | np.ndarray, box: Compartment, margin: float = 0.0
) -> bool:
    """Whether ``local`` (the landmark's frame; an object's bottom centre) lies
    inside ``box``: within its walls (x, y, ``margin`` inside them), no lower
    than its floor (less :data:`~demoplan.model.LEVEL_TOLERANCE`) and in the
    lower half of its height — on its floor, on something on it, or leaning
    on a wall, not on top of a wall or a divider."""
    x0, y0, z0, x1, y1, z1 = box
    x, y, z = local[0], local[1], local[2]
    return (
        x0 + margin < x < x1 - margin
        and y0 + margin < y < y1 - margin
        and z0 - LEVEL_TOLERANCE <= z <= (z0 + z1) / 2
    )


def _same(a: Compartment, b: Compartment) -> bool:
    return all(abs(u - v) <= SAME_COMPARTMENT for u, v in zip(a, b, strict=True))


def _region(state: State, demonstrations: Sequence[Demonstration]) -> Compartment | None:
    """The compartment of the state's reference landmark holding every member's
    placement, the same in every member's demonstration; else None."""
    reference = state.position.reference
    found: Compartment | None = None
    for demo_index, step_index in state.members:
        demo = demonstrations[demo_index]
        landmark = demo.landmark_poses().get(reference or "")
        boxes = dict(demo.compartments).get(reference or "", ())
        if landmark is None or not boxes:
            return None
        local = local_point(demo.steps[step_index].pose.position, landmark)
        holding = [box for box in boxes if in_compartment(local, box)]
        if len(holding) != 1 or (found is not None and not _same(found, holding[0])):
            return None
        found = holding[0]
    return found


def with_regions(states: Sequence[State], demonstrations: Sequence[Demonstration]) -> list[State]:
    """``states`` with a region goal where every member lies in one compartment
    of its landmark reference (:attr:`~demoplan.model.StatePosition.region`)."""
    out = []
    for state in states:
        region = None if state.position.reference is None else _region(state, demonstrations)
        if region is not None:
            state = replace(state, position=replace(state.position, region=region))
        out.append(state)
    return out
