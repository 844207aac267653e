"""An independent check of a scene plan: replay it on the scene's geometry.

Shares no code with demoplan.scenes: footprints, targets and the order of
reached states are recomputed here from the files (plan JSON, scene, model).
"""

from __future__ import annotations

import math
from typing import Any

import shapely

from demoplan.model import TaskModel

TOUCH = 0.002  # m: footprints may touch
LEVEL = 0.005  # m: heights that meet


def _footprint(shape: str, size: list[float], x: float, y: float, yaw: float) -> Any:
    if shape != "box":
        return shapely.Point(x, y).buffer(max(size[0], size[1]) / 2)
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    hx, hy = size[0] / 2, size[1] / 2
    return shapely.Polygon(
        [
            (x + c * a - s * b, y + s * a + c * b)
            for a, b in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))
        ]
    )


def check_scene_plan(
    plan: dict[str, Any],
    scene: dict[str, Any],
    model: TaskModel,
    sizes: dict[str, tuple[str, list[float]]],
) -> None:
    """Assert the plan is physically sound in the scene and ends in the chosen goal.

    ``scene`` is the scene file's JSON (metres, yaw in degrees); ``sizes`` maps
    each object to (shape, size).
    """
    poses = {
        name: (
            *entry["position"][:2],
            entry["position"][2] if len(entry["position"]) > 2 else 0.0,
            entry.get("yaw", 0.0),
        )
        for name, entry in scene["objects"].items()
    }
    locations = plan["locations"]

    def body(name: str, pose: tuple[float, float, float, float]) -> Any:
        shape, size = sizes[name]
        return _footprint(shape, size, pose[0], pose[1], pose[3]).buffer(-TOUCH)

    def overlapping(name: str, pose: tuple[float, float, float, float]) -> list[str]:
        mine = body(name, pose)
        low, high = pose[2], pose[2] + sizes[name][1][2]
        hits = []
        for other, p in poses.items():
            if other == name:
                continue
            o_low, o_high = p[2], p[2] + sizes[other][1][2]
            if min(high, o_high) - max(low, o_low) > LEVEL and mine.intersects(body(other, p)):
                hits.append(other)
        return hits

    def on_top_of(name: str) -> list[str]:
        pose = poses[name]
        top = pose[2] + sizes[name][1][2]
        return [
            other
            for other, p in poses.items()
            if other != name
            and abs(p[2] - top) <= LEVEL
            and body(name, pose).intersects(body(other, p))
        ]

    held = None
    put_times: dict[str, list[tuple[int, tuple[float, float, float, float]]]] = {}
    for step, (kind, obj, loc, _grasp) in enumerate(plan["actions"]):
        where = f"step {step + 1} ({kind} {obj} {loc})"
        place = locations[loc]
        x, y, z = place["position"]
        if kind == "GRASP":
            assert held is None, f"{where}: hand not empty"
            px, py, pz, _ = poses[obj]
            assert math.dist((px, py, pz), (x, y, z)) < 0.011, f"{where}: {obj} is at {poses[obj]}"
            above = on_top_of(obj)
            assert not above, f"{where}: {above} stand on {obj}"
            held = obj
            del poses[obj]
        else:
            assert held == obj, f"{where}: {obj} is not held"
            yaw = place["yaw"] if loc.startswith("loc") else 0.0
            pose = (x, y, z, yaw)
            hits = overlapping(obj, pose)
            assert not hits, f"{where}: {obj} would overlap {hits}"
            if z > LEVEL:
                under = [
                    o
                    for o, p in poses.items()
                    if abs(p[2] + sizes[o][1][2] - z) <= LEVEL
                    and body(obj, pose).intersects(body(o, p))
                ]
                assert under, f"{where}: {obj} would stand on nothing at z = {z}"
            poses[obj] = pose
            put_times.setdefault(obj, []).append((step, pose))
            held = None
    assert held is None, "the plan ends holding an object"

    # The goal, recomputed: each final state's pose through its reference.
    states = {s.id: s for s in model.states}
    sequence = model.sequences[plan["goal"]]
    final = {states[s].object: states[s] for s in sequence}
    for obj, state in final.items():
        ref = state.position.reference
        base = (0.0, 0.0, 0.0) if ref is None else poses[ref][:3]
        expected = [b + v for b, v in zip(base, state.position.value, strict=True)]
        assert math.dist(poses[obj][:3], expected) < 0.002, (obj, poses[obj], expected)
    # Precedences: the time each final state is reached (its object put at its
    # final place after every state constrained before it is reached).
    reached: dict[str, int] = {}
    final_ids = {s.id for s in final.values()}
    before = {
        y: {x for x, y2 in model.constraints if y2 == y and x in final_ids} for y in final_ids
    }
    for _ in final_ids:
        for obj, state in final.items():
            if state.id in reached or not before[state.id] <= set(reached):
                continue
            start = max((reached[x] for x in before[state.id]), default=-1)
            times = [
                t
                for t, p in put_times.get(obj, [])
                if t > start and math.dist(p[:3], poses[obj][:3]) < 0.002
            ]
            initially_there = start < 0 and obj not in put_times
            if times:
                reached[state.id] = times[0]
            elif initially_there:
                reached[state.id] = -1
    assert set(reached) == final_ids, (
        f"states never reached in order: {sorted(final_ids - set(reached))}"
    )
