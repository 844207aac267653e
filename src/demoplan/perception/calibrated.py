"""Perceiving blocks in a photograph of the table calibrated by a camera file or
by markers (docs/perception.md "Calibration"): the photograph is rectified to a
top view of the table (:func:`~demoplan.perception.calibration.rectify`), the
detector of :mod:`demoplan.perception.blocks` finds the blocks there, and each
block's top face is moved down to the table (the height correction of
:func:`~demoplan.perception.calibration.top_face_on_table`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

import numpy as np

from demoplan.budget import PERCEPTION_TIMEOUT, time_budget
from demoplan.perception.blocks import DetectedBlock, PerceptionSettings, Rejection, detect_blocks
from demoplan.perception.calibration import (
    MarkerLayout,
    TableCalibration,
    calibrate,
    check_image_size,
    edge_colour,
    rectify,
    table_to_photo,
    top_face_on_table,
)
from demoplan.perception.camera import Camera, load_image
from demoplan.perception.colours import load_palette
from demoplan.perception.images import SIDE_TOLERANCE, Perception, check_side, seen_now
from demoplan.perception.overlay import Drawn, NoBlocksError, draw_overlay, speck_side
from demoplan.perception.stacking import BlockTracker, TrackedBlock

__all__ = [
    "calibration_for",
    "detect_in_photograph",
    "perceive_calibrated",
    "perceive_photograph",
    "top_faces_view",
]

RECTIFIED_PX_PER_M = 1000.0
"""The rectified top view's resolution: 1 px = 1 mm (a 4 cm cube is 40 px across)."""


def calibration_for(
    image: Path, calibration: TableCalibration | MarkerLayout, source: str | None = None
) -> TableCalibration:
    """The calibration to read ``image`` with: the given one (its image size
    checked), or one made from the markers of a layout found in it."""
    picture = load_image(image)
    if isinstance(calibration, MarkerLayout):
        return calibrate(picture, calibration, source=source or str(image))
    check_image_size(calibration, picture, str(image))
    return calibration


def _detected(
    image: Path,
    calibration: TableCalibration,
    side: float | None,
    rejected: list[Rejection] | None = None,
    palette: Mapping[str, tuple[float, float, float]] | None = None,
) -> tuple[list[DetectedBlock], float]:
    """:func:`detect_in_photograph` on the photograph file ``image``."""
    picture = load_image(image)
    check_image_size(calibration, picture, str(image))
    return detect_in_photograph(picture, calibration, side, rejected, palette)


def detect_in_photograph(
    picture: np.ndarray,
    calibration: TableCalibration,
    side: float | None,
    rejected: list[Rejection] | None = None,
    palette: Mapping[str, tuple[float, float, float]] | None = None,
) -> tuple[list[DetectedBlock], float]:
    """The blocks in ``picture`` (a photograph of the calibration's size) on the
    table's coordinates, each block's top face brought down to the table, and
    the height of the plane the view they were found on shows (the top faces',
    or the table's); ``rejected`` gets the regions that view's detector rejected."""
    centre = calibration.centre
    rectified, camera = rectify(picture, calibration, RECTIFIED_PX_PER_M)
    settings = PerceptionSettings(colours=palette or {})
    if side is not None:
        settings = replace(
            settings, min_side=(1 - SIDE_TOLERANCE) * side, max_side=(1 + SIDE_TOLERANCE) * side
        )
    if centre is not None and side is None:
        # the cubes' side from the table's view (side faces make it a little
        # large), then measured again on the top faces' view made with it
        sides = [
            top_face_on_table(b.x, b.y, b.side, centre, None)[2]
            for b in detect_blocks(rectified, camera, settings)
        ]
        if sides:
            height = float(np.median(sides))
            if centre.position[2] > 2 * height:
                # within 30 % of the estimate (it is that close: side faces are thin)
                near = replace(settings, min_side=0.7 * height, max_side=1.3 * height)
                top_faces, camera = top_faces_view(picture, calibration, height)
                found = detect_blocks(top_faces, camera, near)
                if found:
                    height = float(np.median([b.side for b in found]))
                    top_faces, camera = top_faces_view(picture, calibration, height)
                    return detect_blocks(top_faces, camera, near, rejected), height
    if side is not None and centre is not None and centre.position[2] > 2 * side:
        top_faces, camera = top_faces_view(picture, calibration, side)
        return detect_blocks(top_faces, camera, settings, rejected), side
    found = []
    for block in detect_blocks(rectified, camera, settings, rejected):
        x, y, cube, _ = top_face_on_table(block.x, block.y, block.side, centre, side)
        found.append(replace(block, x=x, y=y, side=cube))
    return found, 0.0


def top_faces_view(
    picture: np.ndarray, calibration: TableCalibration, side: float
) -> tuple[np.ndarray, Camera]:
    """A top view of the cubes' top faces alone, at their true place and size.

    The photograph is rectified twice over one grid: on the plane of the top
    faces (``side`` above the table: a top face is where it is; the side faces
    trail from it towards the camera's foot) and on the table (a cube's base
    is where it is; its faces trail away from the camera's foot). A cube's
    footprint is block in both; each trail is block in one view and table in
    the other. So each pixel is taken from the view in which it looks more
    like the table (nearer the colour of the photograph's edge): what is left
    is the footprints, coloured as the top faces."""
    top, camera = rectify(picture, calibration, RECTIFIED_PX_PER_M, above=side)
    base, _ = rectify(picture, calibration, RECTIFIED_PX_PER_M)
    table = np.array(edge_colour(picture), dtype=float)
    top_distance = np.linalg.norm(top.astype(float) - table, axis=2)
    base_distance = np.linalg.norm(base.astype(float) - table, axis=2)
    combined: np.ndarray = np.where((top_distance <= base_distance)[..., None], top, base)
    return combined, camera


def perceive_calibrated(
    image: Path,
    calibration: TableCalibration,
    *,
    before: Path | None = None,
    side: float | None = None,
    timeout: float = PERCEPTION_TIMEOUT,
    colours: Path | None = None,
) -> dict[str, TrackedBlock]:
    """The blocks in ``image``, by name: :func:`perceive_photograph`'s."""
    return perceive_photograph(
        image, calibration, before=before, side=side, timeout=timeout, colours=colours
    ).blocks


def perceive_photograph(
    image: Path,
    calibration: TableCalibration,
    *,
    before: Path | None = None,
    side: float | None = None,
    timeout: float = PERCEPTION_TIMEOUT,
    colours: Path | None = None,
    overlay: bool = False,
) -> Perception:
    """The blocks in ``image`` (a photograph of the table, any view the
    calibration covers), by name, on the table's coordinates; with ``before``
    (the picture before the last move, same camera) a block the moved one now
    covers stands under it; ``colours`` a palette file of colours to add; the
    regions rejected; with ``overlay``, both drawn on the photograph, mapped
    back from the rectified view through the calibration. An input error when
    there is no block."""
    check_side(side)
    palette = load_palette(colours) if colours is not None else {}
    tracker = BlockTracker()
    with time_budget(
        timeout,
        f"perception stopped at its time budget (--timeout {timeout:g} s){{where}}: many "
        "small regions or a large image; give it more time, or say the blocks' size (--side)",
    ):
        if before is not None:
            tracker = BlockTracker(
                TrackedBlock(b.name, b.x, b.y, 0.0, b.yaw, b.side, b.colour)
                for b in _detected(before, calibration, side, palette=palette)[0]
            )
        rejected: list[Rejection] = []
        detected, plane = _detected(image, calibration, side, rejected, palette)
        blocks = tracker.update(detected)
    if not blocks:
        raise NoBlocksError(
            "no blocks found; a scene needs at least one (--side too strict?)",
            source=str(image),
            overlay=draw_overlay(
                load_image(image),
                [],
                [(r, plane) for r in rejected],
                lambda points, at: table_to_photo(calibration, points, at),
            )
            if overlay
            else None,
        )
    seen, left = seen_now(blocks, detected)
    rejected += left
    drawn = None
    if overlay:
        # a top face where it shows: on its plane, where the camera's centre is known
        lifted = calibration.centre is not None
        found = [Drawn(b.name, b.x, b.y, b.yaw, b.side, b.side if lifted else 0.0) for b in seen]
        drawn = draw_overlay(
            load_image(image),
            found,
            [(r, plane) for r in rejected],
            lambda points, at: table_to_photo(calibration, points, at),
            speck_side([b.side for b in blocks.values()]),
        )
    return Perception(blocks, tuple(rejected), drawn)
