"""Orientation conversions and the rotation statistics state generation needs.

Names follow ``<target>_from_<source>``. Quaternions are ``(x, y, z, w)`` with
``w >= 0`` (canonical sign); Euler angles are extrinsic x-y-z (roll, pitch,
yaw) in degrees, as docs/formats.md defines ``rpy``.

Orientations are compared as rotations, never as raw Euler differences: the
deviation of a rotation from a mean is the rotation vector of
``mean⁻¹ · rotation`` (the log map), so yaw 179° and −179° are 2° apart and
gimbal lock does not distort distances.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

Quaternion = tuple[float, float, float, float]
FloatArray = NDArray[np.float64]

__all__ = [
    "UNIT_TOLERANCE",
    "Quaternion",
    "angle_between",
    "axis_modulo_flip",
    "box_symmetries",
    "canonical_quat",
    "deviations_from_mean",
    "matrices_from_quats",
    "mean_quat",
    "modulo_group",
    "modulo_symmetry",
    "quat_from_rpy",
    "quat_from_yaw",
    "quat_inverse",
    "quat_multiply",
    "quat_slerp",
    "reduce_yaw",
    "relative_quats",
    "rotate_vectors",
    "rotvecs_from_quats",
    "rpy_from_quat",
    "unit_length_expected",
    "yaws_of",
]

UNIT_TOLERANCE = 0.1
"""How far from 1 a quaternion's length may be, in every input (files, pose
streams, TF, recordings): a unit quaternion written with rounding or measured
with noise, normalised on reading. Farther, it is not a rotation but a mistake
(angles in its columns, a scaled or zero vector) and is refused."""


def unit_length_expected(length: float) -> str | None:
    """Why a quaternion of ``length`` is refused (:data:`UNIT_TOLERANCE`), or None."""
    if abs(length - 1.0) <= UNIT_TOLERANCE:
        return None
    return (
        f"a unit quaternion expected (length within {UNIT_TOLERANCE:g} of 1, docs/limits.md); "
        f"this one is {length:.6g} long"
    )


def canonical_quat(quat: Sequence[float]) -> Quaternion:
    """Return the unit quaternion with ``w >= 0`` for ``quat`` (x, y, z, w)."""
    q = np.asarray(quat, dtype=float)
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > 1e-12:  # already-unit quaternions stay bit-exact (file round trips)
        q = q / norm
    if q[3] < 0 or (q[3] == 0 and next((v for v in q[:3] if v != 0), 0.0) < 0):
        q = -q
    return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))


def quat_from_yaw(yaw_deg: float) -> Quaternion:
    """Planar orientation (rotation about world z) as a quaternion."""
    half = math.radians(yaw_deg) / 2.0
    return canonical_quat([0.0, 0.0, math.sin(half), math.cos(half)])


def quat_from_rpy(rpy_deg: Sequence[float]) -> Quaternion:
    """Extrinsic x-y-z Euler angles (roll, pitch, yaw) in degrees → quaternion.

    Extrinsic x-y-z is ``R = Rz(yaw)·Ry(pitch)·Rx(roll)``.
    """
    roll, pitch, yaw = (math.radians(v) / 2.0 for v in rpy_deg)
    qx = np.array([math.sin(roll), 0.0, 0.0, math.cos(roll)])
    qy = np.array([0.0, math.sin(pitch), 0.0, math.cos(pitch)])
    qz = np.array([0.0, 0.0, math.sin(yaw), math.cos(yaw)])
    q = quat_multiply(qz, quat_multiply(qy, qx))
    return canonical_quat([float(v) for v in q])


def rpy_from_quat(quat: Sequence[float]) -> tuple[float, float, float]:
    """Quaternion → extrinsic x-y-z Euler angles in degrees (yaw in (−180, 180]).

    At gimbal lock (pitch ±90°) only roll − yaw (or roll + yaw) is defined;
    roll is then reported as 0.
    """
    m = matrices_from_quats(np.asarray([quat], dtype=float))[0]
    cos_pitch = math.hypot(float(m[0]), float(m[3]))
    pitch = math.atan2(-float(m[6]), cos_pitch)  # atan2, not asin: exact near ±90°
    if cos_pitch < 1e-9:
        roll = 0.0
        yaw = math.atan2(-float(m[1]), float(m[4]))
    else:
        roll = math.atan2(float(m[7]), float(m[8]))
        yaw = math.atan2(float(m[3]), float(m[0]))
    return (
        _clean_angle(math.degrees(roll)),
        _clean_angle(math.degrees(pitch)),
        _clean_angle(math.degrees(yaw)),
    )


def _clean_angle(angle: float) -> float:
    wrapped = (float(angle) + 180.0) % 360.0 - 180.0
    if wrapped == -180.0:
        wrapped = 180.0
    return 0.0 if abs(wrapped) < 1e-9 else wrapped


def quat_multiply(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton product of ``(..., 4)`` quaternions (x, y, z, w): the rotation ``a·b``."""
    ax, ay, az, aw = np.moveaxis(np.asarray(a, dtype=float), -1, 0)
    bx, by, bz, bw = np.moveaxis(np.asarray(b, dtype=float), -1, 0)
    product: FloatArray = np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )
    return product


def quat_inverse(q: FloatArray) -> FloatArray:
    """Inverse (conjugate) of unit quaternions ``(..., 4)``."""
    inverse: FloatArray = np.asarray(q, dtype=float) * np.array([-1.0, -1.0, -1.0, 1.0])
    return inverse


def rotate_vectors(quats: FloatArray, vectors: FloatArray) -> FloatArray:
    """Rotate ``(n, 3)`` vectors by ``(n, 4)`` unit quaternions (x, y, z, w): ``R(q)·v``.

    Uses ``v + w·t + u × t`` with ``t = 2·u × v`` (``u`` the vector part), which
    leaves ``v`` unchanged bit for bit under the identity.
    """
    q = np.asarray(quats, dtype=float)
    v = np.asarray(vectors, dtype=float)
    u = q[..., :3]
    twice = 2.0 * np.cross(u, v)
    rotated: FloatArray = v + q[..., 3:4] * twice + np.cross(u, twice)
    return rotated


def quat_slerp(a: FloatArray, b: FloatArray, fraction: FloatArray) -> FloatArray:
    """Spherical linear interpolation between ``(n, 4)`` unit quaternions, row by row.

    ``fraction`` ``(n,)`` is 0 at ``a`` and 1 at ``b``; the shorter arc is taken
    (``b`` and ``−b`` are one rotation). Nearly equal rows are interpolated
    linearly and normalised (nlerp), where slerp's ``sin θ`` division loses
    precision. At fraction 0 and 1 the result is ``a`` and ``±b`` exactly.
    """
    qa = np.asarray(a, dtype=float).reshape(-1, 4)
    qb = np.asarray(b, dtype=float).reshape(-1, 4)
    s = np.asarray(fraction, dtype=float).reshape(-1, 1)
    dot = np.sum(qa * qb, axis=1, keepdims=True)
    qb = np.where(dot < 0, -qb, qb)
    theta = np.arccos(np.clip(np.abs(dot), 0.0, 1.0))
    sin_theta = np.sin(theta)
    near = sin_theta < 1e-6
    safe = np.where(near, 1.0, sin_theta)
    weight_a = np.where(near, 1.0 - s, np.sin((1.0 - s) * theta) / safe)
    weight_b = np.where(near, s, np.sin(s * theta) / safe)
    result = weight_a * qa + weight_b * qb
    partial = near[:, 0] & (s[:, 0] != 0.0) & (s[:, 0] != 1.0)
    result[partial] /= np.linalg.norm(result[partial], axis=1, keepdims=True)
    return np.asarray(result, dtype=float)


def rotvecs_from_quats(quats: FloatArray) -> FloatArray:
    """``(n, 4)`` unit quaternions → ``(n, 3)`` rotation vectors (radians, angle ≤ π)."""
    q = _canonical_rows(np.asarray(quats, dtype=float).reshape(-1, 4))
    sine = np.linalg.norm(q[:, :3], axis=1)
    angle = 2.0 * np.arctan2(sine, q[:, 3])
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(sine > 1e-12, angle / sine, 2.0)
    return np.asarray(q[:, :3] * scale[:, None], dtype=float)


def matrices_from_quats(quats: FloatArray) -> FloatArray:
    """``(n, 4)`` quaternions → ``(n, 9)`` flattened rotation matrices.

    The flattened matrix is the chordal embedding of SO(3): Euclidean
    distance there is ``2√2·sin(θ/2)`` for a relative rotation angle θ, so
    K-means can run on it directly without the q / −q ambiguity.
    """
    x, y, z, w = np.asarray(quats, dtype=float).reshape(-1, 4).T
    return np.stack(
        [
            1 - 2 * (y * y + z * z),
            2 * (x * y - z * w),
            2 * (x * z + y * w),
            2 * (x * y + z * w),
            1 - 2 * (x * x + z * z),
            2 * (y * z - x * w),
            2 * (x * z - y * w),
            2 * (y * z + x * w),
            1 - 2 * (x * x + y * y),
        ],
        axis=1,
    )


def relative_quats(reference: FloatArray, target: FloatArray) -> FloatArray:
    """Orientation of each ``target`` in the frame of ``reference``: ``R_ref⁻¹ · R_target``."""
    return _canonical_rows(quat_multiply(quat_inverse(reference), target))


def mean_quat(quats: FloatArray) -> Quaternion:
    """Chordal L2 mean rotation of ``(n, 4)`` quaternions.

    The eigenvector of the largest eigenvalue of ``Σ q·qᵀ`` (Markley et al.,
    "Averaging Quaternions", 2007), as scipy's ``Rotation.mean``; q and −q
    count alike.
    """
    q = np.asarray(quats, dtype=float).reshape(-1, 4)
    _, vectors = np.linalg.eigh(q.T @ q)
    return canonical_quat([float(v) for v in vectors[:, -1]])


def deviations_from_mean(quats: FloatArray, mean: Sequence[float]) -> FloatArray:
    """Rotation vectors (degrees) of ``mean⁻¹ · q`` for each row: ``(n, 3)``."""
    relative = quat_multiply(quat_inverse(np.asarray(mean, dtype=float)), quats)
    return np.asarray(np.degrees(rotvecs_from_quats(relative)), dtype=float)


def angle_between(a: Sequence[float], b: Sequence[float]) -> float:
    """Geodesic angle in degrees between two orientations."""
    relative = quat_multiply(quat_inverse(np.asarray(a, dtype=float)), np.asarray(b, dtype=float))
    # atan2 rather than arccos(|w|): exact near 0°, where arccos loses half the digits.
    return float(np.degrees(2.0 * np.arctan2(np.linalg.norm(relative[:3]), abs(relative[3]))))


def _canonical_rows(quats: FloatArray) -> FloatArray:
    flip = quats[:, 3] < 0
    quats = quats.copy()
    quats[flip] *= -1.0
    return quats


def _about_z(angles_rad: FloatArray) -> FloatArray:
    half = np.asarray(angles_rad, dtype=float) / 2.0
    zeros = np.zeros_like(half)
    return np.stack([zeros, zeros, np.sin(half), np.cos(half)], axis=-1)


def yaws_of(quats: FloatArray) -> FloatArray:
    """Yaw (rad) of each ``(n, 4)`` quaternion: the heading of its x axis in the xy plane."""
    x, y, z, w = np.asarray(quats, dtype=float).reshape(-1, 4).T
    return np.asarray(np.arctan2(2 * (x * y + z * w), 1 - 2 * (y * y + z * z)), dtype=float)


def _axis_only(quats: FloatArray) -> FloatArray:
    """For an object the same after any turn about its own z axis: the shortest turn
    from upright to where its axis points (the axis is all that can be seen)."""
    axis = rotate_vectors(quats, np.tile([0.0, 0.0, 1.0], (len(quats), 1)))
    up = np.array([0.0, 0.0, 1.0])
    cross = np.cross(np.tile(up, (len(quats), 1)), axis)
    w = 1.0 + axis[:, 2]
    out = np.concatenate([cross, w[:, None]], axis=1)
    flipped = w < 1e-9  # upside down: any horizontal axis will do
    out[flipped] = [1.0, 0.0, 0.0, 0.0]
    return _canonical_rows(out / np.linalg.norm(out, axis=1, keepdims=True))


def reduce_yaw(quats: FloatArray, period_deg: float) -> FloatArray:
    """Each orientation turned about its own z axis by a multiple of ``period_deg`` so
    that its yaw lies within half a period of 0: the frame of a symmetric object
    (a square box: 90°) chosen the same way wherever it stands. A period of 0
    (a cylinder) drops the turn about its axis altogether; 360 keeps the
    orientations as they are."""
    q = np.asarray(quats, dtype=float).reshape(-1, 4)
    if period_deg >= 360.0:
        return q
    if period_deg <= 0.0:
        return _axis_only(q)
    period = math.radians(period_deg)
    turn = -period * np.round(yaws_of(q) / period)
    return _canonical_rows(quat_multiply(q, _about_z(turn)))


def modulo_symmetry(quats: FloatArray, period_deg: float) -> FloatArray:
    """``(n, 4)`` orientations of one object, each turned about the object's own z axis
    by a multiple of ``period_deg`` to lie as close as possible to the others, so
    that a square box put down at 3° and at 92° reads as one orientation — also
    when the object lies on its side (a knife on its edge): each copy is chosen
    by its angle to a common representative (the first, then their mean, twice
    over). Period 0 (a cylinder) keeps only the direction of the axis; 360
    changes nothing."""
    q = np.asarray(quats, dtype=float).reshape(-1, 4)
    if period_deg >= 360.0 or len(q) == 0:
        return q
    if period_deg <= 0.0:
        return _axis_only(q)
    turns = np.radians(period_deg) * np.arange(round(360.0 / period_deg))
    group = np.stack([_about_z(np.array(t)) for t in turns])
    return modulo_group(q, group)


CENTRED = 1e-5
"""Offsets (m) within this of a symmetric reference's axis lie on it: no copy of
its frame is better than another, so :func:`frames_agreeing` keeps each as given."""


def frames_agreeing(quats: FloatArray, offsets: FloatArray, period_deg: float) -> FloatArray:
    """``(n, 4)`` frames of one symmetric reference, each turned about its own
    z axis by a multiple of ``period_deg`` so that ``offsets`` (``(n, 3)``,
    world axes) expressed in them agree best: a kit tray, the same after half
    a turn, put down at 10° and at 170° is one frame for what lies on it only
    if the copy is chosen by where the contents lie — the copies nearest each
    other (:func:`modulo_symmetry`) would turn the contents of one by half a
    turn. Each copy of the first frame seeds a choice (every other frame's
    copy nearest it, then nearest the mean, thrice); the tightest wins. A
    period of 0 or 360, or a single frame: :func:`modulo_symmetry`."""
    q = np.asarray(quats, dtype=float).reshape(-1, 4)
    if period_deg <= 0.0 or period_deg >= 360.0 or len(q) < 2:
        return modulo_symmetry(q, period_deg)
    d = np.asarray(offsets, dtype=float).reshape(-1, 3)
    if float(np.hypot(d[:, 0], d[:, 1]).max()) < CENTRED:
        return _canonical_rows(q)  # on the axis of symmetry: every copy agrees; as given
    turns = np.radians(period_deg) * np.arange(round(360.0 / period_deg))
    copies = np.stack([quat_multiply(q, _about_z(np.full(len(q), t))) for t in turns])
    local = np.stack([rotate_vectors(quat_inverse(c), d) for c in copies])  # (copies, n, 3)
    rows = np.arange(len(q))
    best: tuple[float, np.ndarray] | None = None
    for seed in range(len(turns)):
        anchor = local[seed, 0]
        choice = np.argmin(np.linalg.norm(local - anchor, axis=2), axis=0)
        for _ in range(3):
            mean = local[choice, rows].mean(axis=0)
            choice = np.argmin(np.linalg.norm(local - mean, axis=2), axis=0)
        spread = float(((local[choice, rows] - local[choice, rows].mean(axis=0)) ** 2).sum())
        if best is None or spread < best[0] - 1e-12:
            best = (spread, choice)
    assert best is not None
    return _canonical_rows(copies[_as_given_most(best[1], local), rows])


def _as_given_most(choice: np.ndarray, local: FloatArray) -> np.ndarray:
    """Of the equally tight choices ``(choice + k) mod copies`` (the whole
    arrangement turned by ``k`` periods), the one that takes the most frames as
    given; on a tie, the one whose mean offset lies nearest the frame's +x
    axis (+y before -y). These ignore the order of the frames, so the learned value
    does not depend on which demonstration came first."""
    count = local.shape[0]
    rows = np.arange(local.shape[1])

    def preference(turn: int) -> tuple[int, float, float]:
        shifted = (choice + turn) % count
        mean = local[shifted, rows].mean(axis=0)
        angle = math.degrees(math.atan2(float(mean[1]), float(mean[0])))
        return (-int(np.count_nonzero(shifted == 0)), round(abs(angle), 6), round(angle % 360, 6))

    turned: np.ndarray = (choice + min(range(count), key=preference)) % count
    return turned


def _turn(axis: int, degrees: float) -> FloatArray:
    q = np.zeros(4)
    q[axis] = math.sin(math.radians(degrees) / 2.0)
    q[3] = math.cos(math.radians(degrees) / 2.0)
    return q


def box_symmetries(size: Sequence[float], tolerance: float = 0.001) -> FloatArray:
    """The rotations ``(k, 4)`` that map a box of extents ``size`` onto itself: the
    four half turns about its axes; the eight of a square prism where two
    extents agree (within ``tolerance``); the 24 of a cube."""
    group = [np.array([0.0, 0.0, 0.0, 1.0])]
    generators = [_turn(0, 180.0), _turn(1, 180.0), _turn(2, 180.0)]
    x, y, z = size
    if abs(x - y) <= tolerance:
        generators.append(_turn(2, 90.0))
    if abs(x - z) <= tolerance:
        generators.append(_turn(1, 90.0))
    if abs(y - z) <= tolerance:
        generators.append(_turn(0, 90.0))
    frontier = list(group)
    while frontier:  # close the set under multiplication
        grown = []
        for a in frontier:
            for g in generators:
                q = _canonical_rows(quat_multiply(a, g)[None, :])[0]
                if all(abs(float(q @ h)) < 1.0 - 1e-9 for h in group):
                    group.append(q)
                    grown.append(q)
        frontier = grown
    return np.asarray(group, dtype=float)


def modulo_group(quats: FloatArray, group: FloatArray) -> FloatArray:
    """``(n, 4)`` orientations of one object, each replaced by the copy ``q·g`` (``g``
    in the object's symmetry ``group``) closest to a common representative (the
    first, then the copies' mean, three times) — and then, of the group's copies of
    that arrangement, the one whose mean is nearest the identity, so that the
    result does not depend on the order: a box lying on either side, a square
    box turned by 90°, read as one orientation."""
    q = np.asarray(quats, dtype=float).reshape(-1, 4)
    if len(q) == 0 or len(group) <= 1:
        return q
    copies = np.stack([quat_multiply(q, np.tile(g, (len(q), 1))) for g in group], axis=1)
    representative = q[0]
    chosen = q
    for _ in range(3):
        closeness = np.abs(copies @ np.asarray(representative))
        chosen = copies[np.arange(len(q)), closeness.argmax(axis=1)]
        representative = np.asarray(mean_quat(chosen))
    # The same set whatever the order the orientations came in: of the group's
    # copies of the whole arrangement, the one whose mean is nearest the identity.
    shifted = [quat_multiply(representative, g) for g in group]
    best = group[int(np.argmax([abs(float(m[3])) for m in shifted]))]
    return _canonical_rows(quat_multiply(chosen, np.tile(best, (len(q), 1))))


def axis_modulo_flip(quats: FloatArray) -> FloatArray:
    """For a cylinder (the same after any turn about its axis and upside down): the
    shortest turn from upright to its axis, the axis taken pointing up."""
    q = np.asarray(quats, dtype=float).reshape(-1, 4)
    axis = rotate_vectors(q, np.tile([0.0, 0.0, 1.0], (len(q), 1)))
    flip = axis[:, 2] < 0
    q = q.copy()
    q[flip] = quat_multiply(q[flip], np.tile(_turn(0, 180.0), (int(flip.sum()), 1)))
    return _axis_only(q)
