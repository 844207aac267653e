"""The arm's contact checks read MuJoCo's contacts as arrays (8bc4f99, 51a578d): on
random sets of touching, nearly touching and apart geoms in a small MuJoCo model,
each finds exactly what the per-contact loop it replaced found (that loop, as it
was, is the oracle here)."""

from __future__ import annotations

import types
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

mujoco = pytest.importorskip("mujoco")

from demoplan.execution.arm import ArmWorld  # noqa: E402
from demoplan.execution.arm_motion import (  # noqa: E402
    PENETRATION,
    ArmMotion,
    Load,
    arm_contacts,
)
from demoplan.execution.arm_moves import ArmMoves  # noqa: E402

_GEOM = st.tuples(
    st.sampled_from(("box", "sphere", "capsule")),
    st.floats(0.01, 0.04),  # size
    st.tuples(*(st.floats(-0.03, 0.03) for _ in range(3))),  # offset in its body
)
_BODY = st.tuples(
    st.lists(_GEOM, min_size=1, max_size=3),
    st.tuples(*(st.floats(-0.06, 0.06) for _ in range(3))),  # position
    st.sampled_from((0.0, 0.02)),  # margin: contacts found this far apart
    st.sampled_from((0.0, 0.015)),  # gap: within it, only closer than margin - gap active
)


def _model(bodies: list[Any]) -> Any:
    """Free bodies of one to three geoms each, crowded into a 12 cm cube: some
    geoms overlap, some lie within their margin, some apart."""
    parts = []
    for index, (geoms, position, margin, gap) in enumerate(bodies):
        shapes = []
        for kind, size, offset in geoms:
            sizes = {
                "box": f"{size} {size} {size}",
                "sphere": f"{size}",
                "capsule": f"{size} {size}",
            }
            shapes.append(
                f'<geom type="{kind}" size="{sizes[kind]}" pos="{" ".join(map(str, offset))}" '
                f'margin="{margin}" gap="{gap}"/>'
            )
        parts.append(
            f'<body name="b{index}" pos="{" ".join(map(str, position))}">'
            f"<freejoint/>{''.join(shapes)}</body>"
        )
    xml = f"<mujoco><worldbody>{''.join(parts)}</worldbody></mujoco>"
    return mujoco.MjModel.from_xml_string(xml)


@st.composite
def _scenes(draw: st.DrawFn) -> tuple[Any, Any, set[int], int, int]:
    """A model with its contacts computed, the bodies that are the arm, a held
    body (or -1) and an allowed one (or -2)."""
    bodies = draw(st.lists(_BODY, min_size=2, max_size=6))
    model = _model(bodies)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    ids = list(range(1, model.nbody))
    arm = set(draw(st.lists(st.sampled_from(ids), unique=True, max_size=len(ids))))
    held = draw(st.sampled_from([-1, *ids]))
    allowed = draw(st.sampled_from([-2, *ids]))
    return model, data, arm, held, allowed


def _label(body: int) -> str:
    return f"body {body}"


@settings(max_examples=60, deadline=None)
@given(scene=_scenes())
def test_the_watch_records_the_collisions_the_per_contact_loop_recorded(
    scene: tuple[Any, Any, set[int], int, int],
) -> None:
    model, data, arm, held, allowed = scene
    expected: list[str] = []
    for contact in data.contact[: data.ncon]:  # the loop of ArmMoves._watch before 8bc4f99
        if contact.dist >= contact.includemargin:
            continue
        first = int(model.geom_bodyid[contact.geom1])
        second = int(model.geom_bodyid[contact.geom2])
        for mine, other in ((first, second), (second, first)):
            if mine in arm and other not in arm and other not in (held, allowed):
                label = f"the arm touched {_label(other)} at 0.00 s"
                if not expected or expected[-1] != label:
                    expected.append(label)
    world = types.SimpleNamespace(
        data=data,
        model=model,
        arm_bodies=arm,
        arm_geoms=np.isin(model.geom_bodyid, sorted(arm)),
        held="held" if held >= 0 else None,
        allowed="allowed",
        _body=lambda name: held if name == "held" else allowed,
        _body_label=_label,
        simulated=0.0,
        collisions=[],
    )
    ArmMoves._watch(world)  # type: ignore[arg-type]
    assert world.collisions == expected


@settings(max_examples=60, deadline=None)
@given(scene=_scenes(), lands=st.booleans())
def test_the_motion_check_finds_the_collision_the_per_contact_loop_found(
    scene: tuple[Any, Any, set[int], int, int], lands: bool
) -> None:
    model, data, arm, held, allowed = scene
    motion = types.SimpleNamespace(
        model=model, arm_bodies=arm, arm_geoms=np.isin(model.geom_bodyid, sorted(arm))
    )
    load = Load("load", held, np.eye(4)) if held >= 0 else None

    def offending(first: int, second: int) -> str | None:
        return ArmMotion._offending(motion, first, second, load, allowed, lands, _label)  # type: ignore[arg-type]

    expected = None
    for contact in data.contact[: data.ncon]:  # the loop of ArmMotion before 51a578d
        if contact.dist > contact.includemargin - PENETRATION:
            continue
        found = offending(
            int(model.geom_bodyid[contact.geom1]), int(model.geom_bodyid[contact.geom2])
        )
        if found is not None:
            expected = found
            break
    pairs = ArmMotion._arm_or_load_contacts(motion, data, load)  # type: ignore[arg-type]
    actual = next((f for f in (offending(a, b) for a, b in pairs) if f is not None), None)
    assert actual == expected


@settings(max_examples=60, deadline=None)
@given(scene=_scenes())
def test_the_simulated_collision_facts_see_the_contacts_the_per_contact_loop_saw(
    scene: tuple[Any, Any, set[int], int, int],
) -> None:
    model, data, arm, _, _ = scene
    expected = set()
    for contact in data.contact[: data.ncon]:  # collision_simulation's loop before 51a578d
        if contact.dist >= contact.includemargin:
            continue
        first = int(model.geom_bodyid[contact.geom1])
        second = int(model.geom_bodyid[contact.geom2])
        for mine, other in ((first, second), (second, first)):
            if mine in arm and other not in arm:
                expected.add(other)
    on_arm = np.isin(model.geom_bodyid, sorted(arm))
    actual = {
        second if first in arm else first for first, second in arm_contacts(data, model, on_arm)
    }
    assert actual == expected


@settings(max_examples=60, deadline=None)
@given(scene=_scenes(), data_draw=st.data())
def test_the_tool_touches_what_the_per_contact_loop_said_it_touched(
    scene: tuple[Any, Any, set[int], int, int], data_draw: st.DataObject
) -> None:
    model, data, _, _, _ = scene
    tool = set(data_draw.draw(st.lists(st.integers(0, model.ngeom - 1), min_size=1, unique=True)))
    body = data_draw.draw(st.integers(1, model.nbody - 1))
    touching = set()
    for contact in data.contact[: data.ncon]:  # ArmWorld._touching's loop before 51a578d
        pair = (int(contact.geom1), int(contact.geom2))
        for geom, other in (pair, pair[::-1]):
            if (
                geom in tool
                and int(model.geom_bodyid[other]) == body
                and contact.dist < contact.includemargin
            ):
                touching.add(geom)
    world = types.SimpleNamespace(
        data=data,
        model=model,
        tool="fingers",
        pad=-1,
        finger_geoms=tool,
        finger_joints=[0],  # a free joint's x: the fingers counted as open
        _body=lambda name: body,
    )
    data.qpos[0] = 1.0
    assert ArmWorld._touching(world, "obj") == bool(touching)  # type: ignore[arg-type]
