"""Region goals (docs/learning.md, "Region goals"): a landmark's compartments
found from its parts, a placement the demonstrations put inside one learned as
"anywhere inside it", and its target at run time — where the object stands
when it is inside, else a point inside within the robot's reach.

Generated families: bins of 1–3 × 1–3 compartments, of varied sizes and wall
thicknesses, standing anywhere at any yaw.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.documents.compartments import compartments
from demoplan.learning import learn
from demoplan.learning.modelfile import model_from_dict, model_to_dict
from demoplan.learning.regions import in_compartment, local_point
from demoplan.model import Compartment, Demonstration, ObjectGeometry, Pose, Step
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.regions import WALL_CLEARANCE
from demoplan.scenes.scene import Scene, SceneObject
from demoplan.scenes.targets import candidate_goals

CAN = ObjectGeometry("cylinder", (0.06, 0.06, 0.12))
BIN_PLACES = ((-0.8, 0.0), (0.8, 0.2), (0.0, 0.9))
Box = tuple[tuple[float, float, float], tuple[float, float, float]]


@dataclass(frozen=True)
class Bin:
    """A bin's parts (its frame, from its bottom centre) and its compartments' bounds."""

    parts: tuple[Box, ...]
    cells: tuple[Compartment, ...]
    """The compartments as built: inside the walls and between the dividers."""


@st.composite
def bins(draw: st.DrawFn) -> Bin:
    """A floor, four walls round it and dividers cutting it into nx × ny compartments."""
    nx, ny = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    width = draw(st.floats(0.15, 0.25)) * nx  # each compartment 15–25 cm wide inside
    depth = draw(st.floats(0.15, 0.25)) * ny
    wall = draw(st.floats(0.004, 0.02))  # half thickness
    floor, height = draw(st.floats(0.01, 0.03)), draw(st.floats(0.06, 0.15))
    hx, hy = width / 2, depth / 2
    parts: list[Box] = [((-hx, -hy, 0.0), (hx, hy, floor))]
    top = floor + height
    parts += [
        ((-hx - 2 * wall, -hy, 0.0), (-hx, hy, top)),
        ((hx, -hy, 0.0), (hx + 2 * wall, hy, top)),
        ((-hx - 2 * wall, -hy - 2 * wall, 0.0), (hx + 2 * wall, -hy, top)),
        ((-hx - 2 * wall, hy, 0.0), (hx + 2 * wall, hy + 2 * wall, top)),
    ]
    xs = [-hx + k * width / nx for k in range(nx + 1)]
    ys = [-hy + k * depth / ny for k in range(ny + 1)]
    parts += [((x - wall, -hy, floor), (x + wall, hy, top)) for x in xs[1:-1]]
    parts += [((-hx, y - wall, floor), (hx, y + wall, top)) for y in ys[1:-1]]
    cells = []
    for i in range(nx):
        for j in range(ny):
            x0 = xs[i] + (wall if i else 0.0)
            x1 = xs[i + 1] - (wall if i < nx - 1 else 0.0)
            y0 = ys[j] + (wall if j else 0.0)
            y1 = ys[j + 1] - (wall if j < ny - 1 else 0.0)
            cells.append((x0, y0, floor, x1, y1, top))
    return Bin(tuple(parts), tuple(sorted(cells)))


def _close(a: Compartment, b: Compartment) -> bool:
    return all(abs(u - v) < 1e-5 for u, v in zip(a, b, strict=True))


@settings(max_examples=40, deadline=None)
@given(bins())
def test_a_bins_compartments_are_the_spaces_its_walls_and_dividers_enclose(bin_: Bin) -> None:
    found = compartments(bin_.parts)
    assert len(found) == len(bin_.cells)
    assert all(_close(f, c) for f, c in zip(found, bin_.cells, strict=True))


@settings(max_examples=25, deadline=None)
@given(bins())
def test_a_compartment_left_open_on_one_side_is_none(bin_: Bin) -> None:
    """Without its wall at high x, the compartments along that side are open."""
    without = tuple(p for p in bin_.parts if p is not bin_.parts[2])
    side = max(c[3] for c in bin_.cells)
    found = compartments(without)
    assert all(f[3] < side - 1e-6 for f in found)
    assert len(found) == sum(1 for c in bin_.cells if c[3] < side - 1e-6)


def test_a_solid_block_has_no_compartment() -> None:
    assert compartments([((-0.1, -0.1, 0.0), (0.1, 0.1, 0.1))]) == ()


@st.composite
def tasks(draw: st.DrawFn) -> tuple[Bin, int, list[Pose], list[tuple[float, float]]]:
    """A bin, one of its compartments, where the bin stood in three
    demonstrations (far apart, any yaw), and where in the compartment the can was put in each
    (anywhere inside, the can within its walls)."""
    bin_ = draw(bins())
    chosen = draw(st.integers(0, len(bin_.cells) - 1))
    x0, y0, _, x1, y1, _ = bin_.cells[chosen]
    poses, points = [], []
    for bx, by in BIN_PLACES:  # the bin far apart in each: its own reference, not the table
        x, y = bx + draw(st.floats(-0.1, 0.1)), by + draw(st.floats(-0.1, 0.1))
        yaw = draw(st.floats(-180, 180))
        poses.append(Pose((x, y, 0.0), quat_from_yaw(yaw)))
        fx, fy = draw(st.floats(0.0, 1.0)), draw(st.floats(0.0, 1.0))
        points.append((x0 + 0.04 + fx * (x1 - x0 - 0.08), y0 + 0.04 + fy * (y1 - y0 - 0.08)))
    return bin_, chosen, poses, points


def _world(frame: Pose, local: tuple[float, float, float]) -> tuple[float, float, float]:
    yaw = 2 * math.atan2(frame.orientation[2], frame.orientation[3]) if frame.orientation else 0.0
    c, s = math.cos(yaw), math.sin(yaw)
    x, y, z = frame.position
    return (x + c * local[0] - s * local[1], y + s * local[0] + c * local[1], z + local[2])


def _demonstrations(
    bin_: Bin, poses: list[Pose], points: list[tuple[float, float]]
) -> list[Demonstration]:
    floor = bin_.cells[0][2]
    return [
        Demonstration(
            name=f"d{k}",
            steps=(Step("can", Pose(_world(at, (px, py, floor)))),),
            objects=(("can", CAN),),
            landmarks=(("bin", at),),
            initial=(("can", Pose((1.0, 1.0, 0.0))),),
            compartments=(("bin", bin_.cells),),
        )
        for k, (at, (px, py)) in enumerate(zip(poses, points, strict=True))
    ]


@settings(max_examples=20, deadline=None)
@given(tasks())
def test_a_placement_anywhere_in_one_compartment_is_learned_as_that_compartment(
    task: tuple[Bin, int, list[Pose], list[tuple[float, float]]],
) -> None:
    bin_, chosen, poses, points = task
    model = model_from_dict(model_to_dict(learn(_demonstrations(bin_, poses, points))), "model")
    can = [s for s in model.states if s.object == "can"]
    assert can and all(s.position.reference == "bin" for s in can)
    assert all(s.position.region is not None for s in can)
    assert all(_close(s.position.region, bin_.cells[chosen]) for s in can if s.position.region)


@settings(max_examples=15, deadline=None)
@given(tasks(), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(-180, 180))
def test_a_region_goal_holds_anywhere_inside_and_else_targets_a_point_inside(
    task: tuple[Bin, int, list[Pose], list[tuple[float, float]]],
    fx: float,
    fy: float,
    yaw: float,
) -> None:
    bin_, chosen, poses, points = task
    model = learn(_demonstrations(bin_, poses, points))
    at = Pose((0.5, -0.2, 0.0), quat_from_yaw(yaw))  # the bin where no demonstration had it
    x0, y0, floor, x1, y1, _ = bin_.cells[chosen]
    inside = _world(
        at, (x0 + 0.03 + fx * (x1 - x0 - 0.06), y0 + 0.03 + fy * (y1 - y0 - 0.06), floor)
    )
    rim = bin_.cells[chosen][5]
    on_top = (inside[0], inside[1], inside[2] - floor + rim)  # up at the rim: not in it
    for start, stays in ((inside, True), ((2.0, 2.0, 0.0), False), (on_top, False)):
        scene = Scene(objects=(SceneObject("can", Pose(start), CAN),), landmarks=(("bin", at),))
        (goal,) = {c.subtasks[-1].pose.position for c in candidate_goals(model, scene)}
        if stays:
            assert goal == start
        else:
            margin = CAN.size[0] / 2 + WALL_CLEARANCE
            assert in_compartment(local_point(goal, at), bin_.cells[chosen], margin - 1e-6)


@settings(max_examples=15, deadline=None)
@given(tasks(), st.floats(0.05, 0.95))
def test_a_region_goals_target_lies_within_the_robots_reach_where_part_of_it_does(
    task: tuple[Bin, int, list[Pose], list[tuple[float, float]]], share: float
) -> None:
    """The robot stands 1 m from the compartment's middle along x and reaches
    a share of the compartment: the target is inside it and within reach."""
    bin_, chosen, poses, points = task
    model = learn(_demonstrations(bin_, poses, points))
    at = Pose((0.0, 0.0, 0.0))
    x0, y0, _floor, x1, y1, _ = bin_.cells[chosen]
    inset = CAN.size[0] / 2 + WALL_CLEARANCE
    near, far = x0 + inset, x1 - inset
    robot = (near - 1.0, (y0 + y1) / 2)
    reach = 1.0 + share * (far - near)
    scene = Scene(
        objects=(SceneObject("can", Pose((2.0, 2.0, 0.0)), CAN),),
        landmarks=(("bin", at),),
        robot=(robot[0], robot[1], 0.0),
        reach=reach,
    )
    (goal,) = {c.subtasks[-1].pose.position for c in candidate_goals(model, scene)}
    assert in_compartment(goal, bin_.cells[chosen], inset - 1e-6)
    assert float(np.hypot(goal[0] - robot[0], goal[1] - robot[1])) <= reach + 1e-6


def test_placements_in_two_compartments_are_no_region() -> None:
    """The can put in one compartment twice and in the next once: no region
    holds all three (each cluster of the same compartment would)."""
    cells = ((-0.2, -0.1, 0.02, 0.0, 0.1, 0.1), (0.0, -0.1, 0.02, 0.2, 0.1, 0.1))
    demos = [
        Demonstration(
            name=f"d{k}",
            steps=(Step("can", Pose((x, 0.0, 0.02))),),
            objects=(("can", CAN),),
            landmarks=(("bin", Pose((0.0, 0.0, 0.0))),),
            initial=(("can", Pose((1.0, 1.0, 0.0))),),
            compartments=(("bin", cells),),
        )
        for k, x in enumerate((-0.09, -0.1, -0.01 + 0.02))
    ]
    model = learn(demos)
    for state in model.states:
        members = {d for d, _ in state.members}
        if members == {0, 1, 2}:
            assert state.position.region is None


def test_the_scenes_shape_keeps_the_target_clear_of_the_walls() -> None:
    """Demonstrations without geometry (robosuite's mesh objects): the scene's
    shape of the can keeps its target's footprint 1 cm from the walls, even
    when the robot reaches only the compartment's corner (then: nearest the mean)."""
    cells = ((0.0, 0.0, 0.02, 0.2, 0.2, 0.1),)
    demos = [
        Demonstration(
            name=f"d{k}",
            steps=(Step("can", Pose((bx + 0.1 + dx, 0.1, 0.02))),),
            landmarks=(("bin", Pose((bx, 0.0, 0.0))),),
            initial=(("can", Pose((1.0, 1.0, 0.0))),),
            compartments=(("bin", cells),),
        )
        for k, (bx, dx) in enumerate(((-0.8, 0.0), (0.8, 0.01), (0.0, -0.01)))
    ]
    model = learn(demos)
    scene = Scene(
        objects=(SceneObject("can", Pose((2.0, 2.0, 0.0)), CAN),),
        landmarks=(("bin", Pose((0.0, 0.0, 0.0))),),
        robot=(-0.5, -0.5, 0.0),
        reach=math.hypot(0.535, 0.535),  # within 3.5 cm of the corner only
    )
    (goal,) = {c.subtasks[-1].pose.position for c in candidate_goals(model, scene)}
    inset = CAN.size[0] / 2 + WALL_CLEARANCE
    assert in_compartment(goal, cells[0], inset - 1e-6)
