"""A demonstration from camera frames (docs/perception.md "Demonstrations from a
camera"): "we estimate the position of each block every time a block is
moved" (Learning Task Models from Multiple Human Demonstrations, §V.B).

Every frame is looked at; the blocks are detected only when the picture has
settled:

1. **The hand.** The frame's foreground (the pixels whose chroma stands out
   from the table's, :func:`~demoplan.perception.colours.foreground`) falls
   into connected regions. A region that touches the image's border (an arm
   reaching in), or covers more than ``hand_share`` of the frame, is the
   hand; a block it touches or carries is part of it. The hand's pixels
   (grown by ``hand_margin``) are painted in the table's colour before the
   blocks are detected: what is under or against the hand is not seen in that
   frame, and a tracked block not seen while the hand is in view keeps its
   last pose — it is hidden, not missing (a block carried under the hand is
   moving, and is seen again where it is put down).
2. **The settle rule.** A frame is *still* when, compared with the frame
   before, no more than ``still_share`` of the foreground outside the hand
   changed (plus ``still_pixels``, the flicker of noise at the blocks' rims)
   and the hand, if any, is where it was (its pixels alike to the same
   share). When ``settle`` frames in a row are still (the first of them counts
   once it is like its successor) the blocks are detected in the last, once
   per still stretch, and the observation is committed to the
   :class:`~demoplan.perception.stacking.BlockTracker`.
3. **Steps.** The first observation is the blocks' initial poses. After that,
   every block whose pose the tracker changed by more than the tracker's
   ``still`` (5 mm; or its yaw by more than ``turned``, 5°) is a step: the
   block moved and was released there. Stacking comes from occlusion as the
   tracker has it: a block put down over part of another stands on it. Steps
   of one observation (several blocks moved while the camera did not see the
   picture settle) are ordered from the lowest up, then by name. A block seen
   for the first time later on is taken to have been there from the start
   (hidden by the hand at first): its pose is added to the initial poses.

Objects are named by colour as ``perceive`` names them (``red``, ``red2``;
blocks of one colour are instances of the type of that colour) and are boxes
of ``side`` (given) or of the median of the sides measured, to the millimetre.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from demoplan.budget import check_time, report_progress, reporting_progress
from demoplan.errors import InputError
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.perception.blocks import DetectedBlock, PerceptionSettings, detect_blocks
from demoplan.perception.camera import Camera
from demoplan.perception.colours import foreground
from demoplan.perception.opencv import cv2
from demoplan.perception.stacking import UNNAMED_COLOUR, BlockTracker, TrackedBlock
from demoplan.rotations import quat_from_yaw

__all__ = [
    "Frame",
    "SequenceSettings",
    "demonstration_from_frames",
    "hand_mask",
    "top_view_detector",
]

Detector = Callable[[np.ndarray], list[DetectedBlock]]
"""Blocks in a frame (the hand painted out), on the table's coordinates."""


SMALLEST_PIECE = 0.5
"""With the blocks' side known, colour regions down to this share of it are
looked at (a strip of a lower block showing beside the one on it is then a
colour of its own, not part of the upper block's region); only detections
within :data:`~demoplan.perception.images.SIDE_TOLERANCE` of the side are kept."""


def top_view_detector(camera: Camera, side: float | None = None) -> Detector:
    """The blocks of a top view (``camera``), their side ``side`` when known."""
    from demoplan.perception.images import SIDE_TOLERANCE

    if side is None:
        return lambda image: detect_blocks(image, camera)
    settings = PerceptionSettings(
        min_side=SMALLEST_PIECE * side, max_side=(1 + SIDE_TOLERANCE) * side
    )

    def detect(image: np.ndarray) -> list[DetectedBlock]:
        found = detect_blocks(image, camera, settings)
        return [d for d in found if abs(d.side - side) <= SIDE_TOLERANCE * side]

    return detect


@dataclass(frozen=True, slots=True)
class SequenceSettings:
    """The settle rule and the hand (see the module docstring)."""

    settle: int = 3
    """Still frames in a row (at least 2) before the blocks are detected and a move recorded."""
    still_share: float = 0.02
    """Share of the foreground (outside the hand) that may change in a still frame."""
    still_pixels: int = 40
    """Pixels that may change on top of ``still_share`` (noise at the rims)."""
    hand_share: float = 0.05
    """A foreground region covering more than this share of the frame is the hand."""
    hand_margin: int = 3
    """Pixels by which the hand's region is grown before it is painted out."""
    turned: float = 5.0
    """Degrees of yaw (mod 90°) by which a block that stayed in place has been turned."""


@dataclass(frozen=True, slots=True)
class Frame:
    """One frame of the sequence: its pixels and how to name it in an error."""

    label: str
    image: np.ndarray


def hand_mask(
    image: np.ndarray,
    settings: SequenceSettings = SequenceSettings(),
    fg: np.ndarray | None = None,
) -> np.ndarray:
    """The hand's pixels in ``image``: foreground regions (``fg``, when already
    known) touching the border or larger than ``settings.hand_share`` of the
    frame, grown by ``hand_margin``."""
    mask = (foreground(image) if fg is None else fg).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    height, width = mask.shape
    hand = np.zeros(count, dtype=bool)
    for index in range(1, count):
        x, y, w, h, area = (int(v) for v in stats[index])
        touches = x == 0 or y == 0 or x + w == width or y + h == height
        hand[index] = touches or area > settings.hand_share * height * width
    found: np.ndarray = hand[labels]
    if settings.hand_margin and found.any():
        size = 2 * settings.hand_margin + 1
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))
        found = cv2.dilate(found.astype(np.uint8), kernel).astype(bool)
    return found


@dataclass
class _Recorder:
    """The state of a sequence being perceived: the tracker, what was recorded."""

    side: float | None
    settings: SequenceSettings
    tracker: BlockTracker = field(default_factory=BlockTracker)
    initial: dict[str, TrackedBlock] | None = None
    steps: list[tuple[str, TrackedBlock]] = field(default_factory=list)
    sides: dict[str, list[float]] = field(default_factory=dict)
    colours: dict[str, str] = field(default_factory=dict)

    def commit(self, detections: list[DetectedBlock], hand: bool) -> None:
        """An observation of a settled picture (``hand``: the hand in view)."""
        named = self.tracker.identify(detections)
        for d in named:
            self.sides.setdefault(d.name, []).append(d.side)
        if self.initial is None:
            if named:
                self.initial = dict(self.tracker.update(named))
                self.colours.update({d.name: d.colour for d in named})
            return
        if hand:  # hidden by the hand, not missing: where it was last seen
            seen = {d.name for d in named}
            named += [
                DetectedBlock(b.name, b.seen_as, b.x, b.y, b.yaw, b.side, (0, 0, 0), 1.0, 0.0)
                for b in self.tracker.blocks.values()
                if b.name not in seen
            ]
        before = dict(self.tracker.blocks)
        after = self.tracker.update(named)
        moved = []
        for name, block in after.items():
            self.colours.setdefault(name, block.seen_as)
            old = before.get(name)
            if old is None:
                self.initial[name] = block  # there from the start, unseen until now
            elif self._changed(old, block):
                moved.append(block)
        for block in sorted(moved, key=lambda b: (b.z, b.name)):
            self.steps.append((block.name, block))
        for name, old in before.items():  # gone from view without a cover: keep it
            self.tracker.blocks.setdefault(name, old)

    def _changed(self, old: TrackedBlock, new: TrackedBlock) -> bool:
        if math.dist((old.x, old.y, old.z), (new.x, new.y, new.z)) > self.tracker.still:
            return True
        turn = (new.yaw - old.yaw + 45.0) % 90.0 - 45.0
        return abs(turn) > self.settings.turned

    def demonstration(
        self, name: str, provenance: tuple[tuple[str, str | int | float], ...], source: str | None
    ) -> Demonstration:
        if self.initial is None:
            raise InputError(
                "no blocks seen in a still picture; a demonstration needs them", source=source
            )
        if not self.steps:
            raise InputError(
                "no block was moved and left still; a demonstration needs at least one step",
                source=source,
            )
        names = list(dict.fromkeys([*self.initial, *(n for n, _ in self.steps)]))
        objects = []
        for n in names:
            side = self.side if self.side is not None else round(float(np.median(self.sides[n])), 3)
            objects.append((n, ObjectGeometry("box", (side, side, side))))
        counts: dict[str, int] = {}
        for n in names:
            counts[self.colours[n]] = counts.get(self.colours[n], 0) + 1
        types = tuple(
            (n, self.colours[n])
            for n in names
            if counts[self.colours[n]] > 1 and self.colours[n] != UNNAMED_COLOUR
        )
        return Demonstration(
            name,
            tuple(Step(n, _pose(b)) for n, b in self.steps),
            objects=tuple(objects),
            initial=tuple((n, _pose(b)) for n, b in self.initial.items()),
            provenance=provenance,
            types=types,
        )


def _pose(block: TrackedBlock) -> Pose:
    position = (round(float(block.x), 6), round(float(block.y), 6), round(float(block.z), 6))
    return Pose(position, quat_from_yaw(round(float(block.yaw), 3)))


def _still(
    previous: tuple[np.ndarray, np.ndarray],
    current: tuple[np.ndarray, np.ndarray],
    settings: SequenceSettings,
) -> bool:
    """Is the frame (foreground, hand) like the one before it (the settle rule)?"""
    (fg0, hand0), (fg1, hand1) = previous, current
    hands = hand0 | hand1
    changed = int(np.count_nonzero((fg0 ^ fg1) & ~hands))
    allowed = settings.still_share * int(np.count_nonzero(fg1 & ~hands)) + settings.still_pixels
    if changed > allowed:
        return False
    hand_changed = int(np.count_nonzero(hand0 ^ hand1))
    return (
        hand_changed <= settings.still_share * int(np.count_nonzero(hands)) + settings.still_pixels
    )


def _painted(image: np.ndarray, hand: np.ndarray, fg: np.ndarray) -> np.ndarray:
    """``image`` with the hand's pixels in the table's colour (the median of the rest)."""
    if not hand.any():
        return image
    table = np.median(image[~(hand | fg)][::7], axis=0) if (~(hand | fg)).any() else 0
    painted = image.copy()
    painted[hand] = np.asarray(table, dtype=image.dtype)
    return painted


def demonstration_from_frames(
    frames: Iterable[Frame],
    detect: Detector,
    *,
    name: str,
    side: float | None = None,
    settings: SequenceSettings = SequenceSettings(),
    total: int | None = None,
    provenance: tuple[tuple[str, str | int | float], ...] = (),
) -> Demonstration:
    """The demonstration ``frames`` show (see the module docstring): ``detect``
    finds the blocks in a frame; ``side``: the blocks' side when known (else
    measured); ``total``: the number of frames, for the progress report. Each
    frame must have the first one's size. An :class:`InputError` when no
    block was seen in a still picture, or none was moved."""
    recorder = _Recorder(side, settings)
    previous: tuple[np.ndarray, np.ndarray] | None = None
    shape: tuple[int, ...] | None = None
    first = ""
    run = 0  # still frames in a row, the first of the stretch included
    count = 0
    for count, frame in enumerate(_checked(frames), start=1):
        check_time(f" at frame {count} ({frame.label})")
        report_progress("frames", count, total or 0)
        image = frame.image
        if shape is None:
            shape, first = image.shape, frame.label
        elif image.shape != shape:
            raise InputError(
                f"frame {count} is {image.shape[1]} × {image.shape[0]} pixels; every frame of a "
                f"sequence the size of the first ({first}: {shape[1]} × {shape[0]}) expected",
                source=frame.label,
            )
        fg = foreground(image)
        hand = hand_mask(image, settings, fg) if fg.any() else np.zeros_like(fg)
        current = (fg, hand)
        run = (
            (run + 1 if run else 2)
            if previous is not None and _still(previous, current, settings)
            else 0
        )
        if run == max(settings.settle, 2):
            with reporting_progress(None):  # the frames' progress, not each frame's regions
                detections = detect(_painted(image, hand, fg))
            if side is not None:  # the side as known, not as measured
                detections = [replace(d, side=side) for d in detections]
            recorder.commit(detections, bool(hand.any()))
        previous = current
    if count == 0:
        raise InputError("no frames; a sequence of at least one frame expected")
    source = str(dict(provenance).get("source", first)) or None
    return recorder.demonstration(name, (*provenance, ("frames", count)), source)


def _checked(frames: Iterable[Frame]) -> Iterator[Frame]:
    for frame in frames:
        image = np.asarray(frame.image)
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise InputError("not an RGB frame (H × W × 3, 8 bits expected)", source=frame.label)
        yield replace(frame, image=image)
