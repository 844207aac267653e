"""Our NumPy quaternion maths against scipy's Rotation (the oracle)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from demoplan import rotations

seeds = st.integers(0, 2**32 - 2)


def _random_quats(seed: int, n: int) -> np.ndarray:
    return np.asarray(Rotation.random(n, random_state=seed).as_quat(), dtype=float)


@given(seeds, st.integers(1, 12))
@settings(max_examples=50, deadline=None)
def test_relative_quats_and_matrices_match_scipy(seed: int, n: int) -> None:
    a, b = _random_quats(seed, n), _random_quats(seed + 1, n)
    ours = rotations.relative_quats(a, b)
    theirs = (Rotation.from_quat(a).inv() * Rotation.from_quat(b)).as_matrix()
    assert np.allclose(rotations.matrices_from_quats(ours).reshape(n, 3, 3), theirs, atol=1e-12)
    assert (ours[:, 3] >= 0).all()


@given(seeds, st.integers(1, 12), st.floats(0.0, 40.0))
@settings(max_examples=50, deadline=None)
def test_mean_and_deviations_match_scipy(seed: int, n: int, scatter_deg: float) -> None:
    rng = np.random.default_rng(seed)
    centre = Rotation.random(random_state=seed)
    noise = Rotation.from_rotvec(np.radians(rng.normal(0, scatter_deg, (n, 3))))
    quats = (centre * noise).as_quat()
    quats[rng.random(n) < 0.5] *= -1  # q and −q are one rotation
    mean = rotations.mean_quat(quats)
    expected = Rotation.from_quat(quats).mean()
    assert rotations.angle_between(mean, expected.as_quat()) < 1e-6
    deviations = rotations.deviations_from_mean(quats, mean)
    oracle = np.degrees((Rotation.from_quat(mean).inv() * Rotation.from_quat(quats)).as_rotvec())
    assert np.allclose(deviations, oracle, atol=1e-8)


@pytest.mark.parametrize(
    ("a", "b", "angle"), [(179.0, -179.0, 2.0), (0.0, 90.0, 90.0), (10.0, 10.0, 0.0)]
)
def test_angles_between_yaws_wrap(a: float, b: float, angle: float) -> None:
    qa, qb = rotations.quat_from_yaw(a), rotations.quat_from_yaw(b)
    assert rotations.angle_between(qa, qb) == pytest.approx(angle, abs=1e-6)


def test_rpy_round_trip_and_canonical_sign() -> None:
    q = rotations.quat_from_rpy([10.0, -20.0, 170.0])
    assert q[3] >= 0
    assert rotations.rpy_from_quat(q) == pytest.approx((10.0, -20.0, 170.0))
    assert rotations.canonical_quat([0.0, 0.0, -0.6, -0.8]) == pytest.approx((0.0, 0.0, 0.6, 0.8))


angles = st.floats(-179.9, 179.9)


@given(angles, st.floats(-89.0, 89.0), angles)
@settings(max_examples=100, deadline=None)
def test_euler_conversions_match_scipy_extrinsic_xyz(roll: float, pitch: float, yaw: float) -> None:
    ours = rotations.quat_from_rpy([roll, pitch, yaw])
    theirs = Rotation.from_euler("xyz", [roll, pitch, yaw], degrees=True).as_quat()
    assert rotations.angle_between(ours, theirs) < 1e-6
    assert rotations.rpy_from_quat(ours) == pytest.approx((roll, pitch, yaw), abs=1e-6)


@given(angles, st.sampled_from([90.0, -90.0]), angles)
@settings(max_examples=50, deadline=None)
def test_euler_at_gimbal_lock_gives_the_same_rotation(
    roll: float, pitch: float, yaw: float
) -> None:
    q = rotations.quat_from_rpy([roll, pitch, yaw])
    again = rotations.quat_from_rpy(rotations.rpy_from_quat(q))
    assert rotations.angle_between(q, again) < 1e-6


@settings(max_examples=200, deadline=None)
@given(
    yaws=st.lists(st.floats(-180.0, 180.0), min_size=2, max_size=5),
    offset=st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5)).filter(
        lambda xy: np.hypot(*xy) >= 1e-4 or xy == (0.0, 0.0)
    ),
    period=st.sampled_from([90.0, 120.0, 180.0]),
    data=st.data(),
)
def test_frames_agreeing_do_not_depend_on_the_order_of_the_frames(
    yaws: list[float], offset: tuple[float, float], period: float, data: st.DataObject
) -> None:
    """A symmetric reference put down at several yaws (each frame as given
    or turned by periods) with the same thing at the same place on it (given
    in world axes): the frame copies chosen for
    each placement are the same whichever placement comes first — a tie
    between equally tight arrangements is broken by the frames, not by the
    first of them."""
    quats = Rotation.from_euler("z", np.array(yaws)[:, None], degrees=True).as_quat()
    turns = data.draw(st.lists(st.integers(0, 3), min_size=len(yaws), max_size=len(yaws)))
    seen_at = [y + t * period for y, t in zip(yaws, turns, strict=True)]
    offsets = Rotation.from_euler("z", np.array(seen_at)[:, None], degrees=True).apply(
        [offset[0], offset[1], 0.0]
    )
    order = data.draw(st.permutations(range(len(yaws))))
    chosen = rotations.frames_agreeing(quats, offsets, period)
    permuted = rotations.frames_agreeing(quats[order], offsets[order], period)
    for row, original in enumerate(order):
        assert abs(float(permuted[row] @ chosen[original])) == pytest.approx(1.0, abs=1e-9)
