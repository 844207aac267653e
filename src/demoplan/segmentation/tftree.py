"""TF trees: frames published relative to parent frames, composed to a world frame.

A ROS 2 robot publishes its frames as a tree on ``/tf`` (moving links) and
``/tf_static`` (fixed links): each transform gives a child frame's pose in its
parent frame (``map → odom → base_link → … → cup``). :class:`TransformTree`
holds each frame's link to its parent over time and composes any frame's pose
in a chosen world frame at that frame's own sample times.

Composition: a frame ``f`` with the chain ``f → p1 → … → pk → world`` gets,
at each of its sample times ``t``, ``T_world_f(t) = T_world_pk(t) ∘ … ∘
T_p1_f(t)``, where ``T_p1_f(t)`` is ``f``'s own sample and every parent link
is interpolated at ``t`` between its two neighbouring samples: linearly for
the translation, by slerp for the rotation. Outside a link's time range its
nearest sample holds (no extrapolation): its last sample after its end, its
first before its start. A static link (from ``/tf_static``) holds for all
time. When the world frame is not an ancestor of ``f`` but in the same tree,
both are composed to their closest common ancestor ``c`` and
``T_world_f = T_c_world⁻¹ ∘ T_c_f``.

The default object set (:meth:`TransformTree.object_frames`): every frame
except the world frame and the frames that have children (links such as
``odom`` or ``base_link`` are interior nodes of the tree; the objects are its
leaves). Names and glob patterns (:mod:`fnmatch`) choose others.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.budget import check_time
from demoplan.errors import InputError
from demoplan.rotations import quat_inverse, quat_multiply, quat_slerp, rotate_vectors
from demoplan.segmentation.types import FloatArray, ObjectTrack

__all__ = ["FrameLink", "TransformTree", "interpolate_link"]

logger = logging.getLogger(__name__)

Transform = tuple[FloatArray, FloatArray]  # positions (n, 3), quaternions (n, 4)


@dataclass(frozen=True, slots=True, eq=False)
class FrameLink:
    """A frame's transforms relative to its parent frame over time.

    Parameters
    ----------
    parent : str
        The parent frame (TF ``header.frame_id``).
    track : ObjectTrack
        Named after the child frame: sample times, translations ``(n, 3)`` and
        unit rotations ``(n, 4)`` (x, y, z, w) of the child in the parent.
    static : bool
        From ``/tf_static``: the last sample holds for all time.
    """

    parent: str
    track: ObjectTrack
    static: bool = False

    @property
    def name(self) -> str:
        """The child frame's name."""
        return self.track.name


def interpolate_link(link: FrameLink, times: FloatArray) -> Transform:
    """The link's transform at ``times`` ``(n,)``: linear / slerp between samples, held outside.

    Returns positions ``(n, 3)`` and quaternions ``(n, 4)``. A static link, or one
    with a single sample, is the same at every time.
    """
    track = link.track
    assert track.orientations is not None, "a TF link always has rotations"
    n, m = len(times), len(track)
    if link.static or m == 1:
        return np.tile(track.positions[-1], (n, 1)), np.tile(track.orientations[-1], (n, 1))
    lower = np.clip(np.searchsorted(track.times, times, side="right") - 1, 0, m - 2)
    t0, t1 = track.times[lower], track.times[lower + 1]
    fraction = np.clip((times - t0) / (t1 - t0), 0.0, 1.0)  # clipped: hold, not extrapolate
    s = fraction[:, None]
    positions = (1.0 - s) * track.positions[lower] + s * track.positions[lower + 1]
    quats = quat_slerp(track.orientations[lower], track.orientations[lower + 1], fraction)
    return np.asarray(positions, dtype=float), quats


def _compose(parent: Transform, child: Transform) -> Transform:
    """``parent ∘ child``: the child's pose expressed in the parent's parent."""
    (p_a, q_a), (p_b, q_b) = parent, child
    return p_a + rotate_vectors(q_a, p_b), quat_multiply(q_a, q_b)


def _inverse_compose(reference: Transform, target: Transform) -> Transform:
    """``reference⁻¹ ∘ target``: the target's pose in the reference frame."""
    (p_r, q_r), (p_t, q_t) = reference, target
    inverse = quat_inverse(q_r)
    return rotate_vectors(inverse, p_t - p_r), quat_multiply(inverse, q_t)


class TransformTree:
    """Frames linked child → parent, checked to form a forest (no cycles).

    Parameters
    ----------
    links : sequence of FrameLink
        One link per child frame, in order of first appearance.
    source : str or None
        The file, for error messages.

    Raises :class:`~demoplan.errors.InputError` when the links form a cycle.
    """

    def __init__(self, links: Sequence[FrameLink], source: str | None = None) -> None:
        self.source = source
        self.links = {link.name: link for link in links}
        names: dict[str, None] = {}
        for link in links:
            names.setdefault(link.parent)
            names.setdefault(link.name)
        #: Every frame, children and parents, in order of first appearance.
        self.frames: tuple[str, ...] = tuple(names)
        self._check_acyclic()
        self.parents_with_children = frozenset(link.parent for link in links)
        #: Frames without a parent, in order of first appearance.
        self.roots: tuple[str, ...] = tuple(f for f in self.frames if f not in self.links)
        # Poses in an ancestor composed at one set of sample times (_relative_to_ancestor).
        self._composed_key: tuple[int, int] | None = None
        self._composed: dict[tuple[str, str], Transform] = {}

    def _check_acyclic(self) -> None:
        done: set[str] = set()
        for start in self.links:
            path: list[str] = []
            on_path: set[str] = set()  # path's frames: a deep chain is walked once
            frame: str | None = start
            while frame is not None and frame not in done:
                if frame in on_path:
                    cycle = [*path[path.index(frame) :], frame]
                    raise InputError(
                        f"the TF frames form a cycle {' → '.join(cycle)}; a tree expected",
                        source=self.source,
                        field=f"frame {frame}",
                    )
                path.append(frame)
                on_path.add(frame)
                link = self.links.get(frame)
                frame = link.parent if link is not None else None
            done.update(path)

    def chain(self, frame: str) -> list[str]:
        """``frame`` and its ancestors up to its root, in that order."""
        chain = [frame]
        while chain[-1] in self.links:
            chain.append(self.links[chain[-1]].parent)
        return chain

    def world_frame(self, frame: str | None = None) -> str:
        """The world frame: ``frame`` if given (it must be a frame of the tree), else the root.

        Raises :class:`~demoplan.errors.InputError` for an unknown ``frame`` and,
        without ``frame``, when the tree has several roots (naming them).
        """
        if frame is not None:
            if frame not in self.frames:
                raise InputError(
                    f"unknown world frame {frame!r}; the TF frames are {', '.join(self.frames)}",
                    source=self.source,
                    field="frame",
                )
            return frame
        if len(self.roots) > 1:
            raise InputError(
                f"the TF tree has several roots ({', '.join(self.roots)}); "
                "choose the world frame with --frame",
                source=self.source,
                field="frame",
            )
        return self.roots[0]

    def object_frames(self, world: str) -> list[str]:
        """The default objects: frames other than ``world`` that have no children (leaves)."""
        return [f for f in self.frames if f != world and f not in self.parents_with_children]

    def connected(self, frame: str, world: str) -> bool:
        """Whether ``frame`` and ``world`` are in one tree (have the same root)."""
        return self.chain(frame)[-1] == self.chain(world)[-1]

    def _relative_to_ancestor(
        self, chain: list[str], times: FloatArray, own: Transform | None
    ) -> Transform:
        """Compose the links of ``chain[:-1]`` (child first) at ``times``: pose in ``chain[-1]``.

        ``own`` replaces the first link's interpolation (a frame's own samples).
        The poses composed on the way are kept for the next call at the same
        times (TF frames are mostly published together): a chain of d frames,
        each an object, costs d compositions rather than d²/2. Only the poses at
        one set of times are kept, so memory stays that of the frames composed.
        """
        n = len(times)
        if len(chain) == 1:
            return np.zeros((n, 3)), np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        key = (n, hash(np.ascontiguousarray(times).tobytes()))
        if self._composed_key != key:
            self._composed_key, self._composed = key, {}
        ancestor = chain[-1]
        where = f" composing frame {chain[0]!r} through {len(chain) - 1} TF links"
        # The nearest ancestor of chain[0] whose pose in ``ancestor`` is known at these times.
        top, pose = len(chain) - 1, None
        for k in range(1, len(chain) - 1):
            known = self._composed.get((chain[k], ancestor))
            if known is not None:
                top, pose = k, known
                break
        for k in range(top - 1, 0, -1):
            check_time(where)  # a budget set by the caller (demoplan.budget), if any
            link = interpolate_link(self.links[chain[k]], times)
            pose = link if pose is None else _compose(pose, link)
            self._composed[(chain[k], ancestor)] = pose
        first = own if own is not None else interpolate_link(self.links[chain[0]], times)
        pose = first if pose is None else _compose(pose, first)
        self._composed[(chain[0], ancestor)] = pose
        return pose

    def track_in(self, frame: str, world: str) -> ObjectTrack | None:
        """``frame``'s poses in ``world`` at its own sample times; ``None`` if not connected.

        A frame directly under ``world`` keeps its samples exactly as read.
        """
        link = self.links.get(frame)
        if link is None or not self.connected(frame, world):
            return None
        track = link.track
        assert track.orientations is not None, "a TF link always has rotations"
        if link.parent == world:
            return track
        up, across = self.chain(frame), self.chain(world)
        ancestors = set(across)
        common = next(f for f in up if f in ancestors)
        own = (track.positions, track.orientations)
        pose = self._relative_to_ancestor(up[: up.index(common) + 1], track.times, own)
        if common != world:
            reference = self._relative_to_ancestor(
                across[: across.index(common) + 1], track.times, None
            )
            pose = _inverse_compose(reference, pose)
        positions, quats = pose
        return ObjectTrack(
            frame,
            track.times,
            np.ascontiguousarray(positions, dtype=float),
            np.ascontiguousarray(quats, dtype=float),
        )

    def tracks_in(self, frames: Sequence[str], world: str) -> dict[str, ObjectTrack]:
        """Tracks of ``frames`` in ``world``; frames not connected to it are left out (logged)."""
        tracks: dict[str, ObjectTrack] = {}
        for frame in frames:
            check_time(f" composing the TF tree's {len(frames)} frames in {world!r}")
            if frame not in self.links:
                logger.warning(
                    "%s: frame %r is a root of the TF tree, with no transforms of its own; "
                    "left out",
                    self.source or "TF tree",
                    frame,
                )
                continue
            track = self.track_in(frame, world)
            if track is None:
                logger.warning(
                    "%s: frame %r is not connected to the world frame %r (its root is %r); "
                    "left out",
                    self.source or "TF tree",
                    frame,
                    world,
                    self.chain(frame)[-1],
                )
                continue
            tracks[frame] = track
        return tracks
