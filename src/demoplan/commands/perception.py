"""``perceive`` and ``calibrate``: blocks found in a camera image (paper §V.B),
the demonstration camera frames show, and the image → table mapping of a
camera. A module of its own so that ``demoplan perceive`` imports perception
and nothing of learning, planning or execution (the whole command's start-up
is part of its time, docs/perception.md "Timing")."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.budget import PERCEPTION_TIMEOUT
from demoplan.errors import InputError, UsageError
from demoplan.fileio import (
    StagedOutputs,
    dump_json,
    refuse_overwriting_inputs,
    write_atomic,
    write_atomic_bytes,
)
from demoplan.perception.blocks import Rejection
from demoplan.perception.images import Sides, given_sides, one_side, perceive_top_view
from demoplan.perception.overlay import NoBlocksError, is_speck, speck_side
from demoplan.perception.stacking import TrackedBlock, scene_document

if TYPE_CHECKING:
    from demoplan.model import Demonstration
    from demoplan.perception.calibration import TableCalibration

__all__ = [
    "Calibrated",
    "Perceived",
    "PerceivedSequence",
    "calibrate",
    "perceive",
    "perceive_sequence",
]


@dataclass(frozen=True, slots=True)
class Perceived:
    """The blocks found in an image, by name, and the scene document they make
    (``demoplan/scene-1``, as ``perceive -o`` writes it); the coloured regions
    found to be no block, each with why (not in the scene)."""

    blocks: dict[str, TrackedBlock]
    document: dict[str, Any]
    rejected: tuple[Rejection, ...] = ()
    scale: str = ""
    """Where the scale came from: ``--px-per-m …``, the cube size (``--side``),
    the camera file or the markers (the scene's ``description`` says it too)."""
    specks: int = 0
    """Of the rejections, the specks the overlay counts and does not draw
    (:func:`~demoplan.perception.overlay.is_speck`); 0 without an overlay."""


def perceive(
    image: Path,
    px_per_m: float | None = None,
    origin: tuple[float, float] | None = None,
    *,
    camera: Path | None = None,
    markers: Path | None = None,
    before: Path | None = None,
    side: Sides = None,
    timeout: float = PERCEPTION_TIMEOUT,
    output: Path | None = None,
    plot: Path | None = None,
    colours: Path | None = None,
    rejections: bool = True,
) -> Perceived:
    """The blocks in ``image`` (paper §V.B: a Hough transform over x, y, θ, s):
    a top-down orthographic picture of ``px_per_m`` pixels per metre with its
    bottom-left corner at world ``origin``, or a photograph calibrated by a
    ``camera`` file or by the ``markers`` (a markers file) seen in it — then
    any view the calibration covers (docs/perception.md "Calibration"). With
    ``before`` (the picture before the last move) a block the moved one covers
    stands under it; ``output``: also write the scene there; ``plot``: the
    picture with what was found and what was rejected drawn on it (PNG; both
    files are written only when both are made); ``colours``: a palette file of
    colours to add or move (docs/formats.md); ``side``: the blocks' side (m), or
    several when the table holds blocks of several sizes (a top view with
    ``px_per_m``: one side for the scale alone, for a camera or markers file);
    ``rejections`` false: a top view with ``px_per_m`` and no ``plot`` records
    no regions rejected (``rejected`` empty; the blocks the same, the CPU of
    their outlines spared: the command without ``--plot`` shows none)."""
    from demoplan.perception.camera import encode_png

    sides = given_sides(side)
    _check_mapping(px_per_m, origin, camera, markers, sides or None, one_picture=True)
    if camera is not None or markers is not None:  # the tops' height is one side
        side = one_side(sides, "with --camera or --markers (the tops' height above the table)")
    else:
        side = sides or None
    inputs = [image, *(p for p in (before, camera, markers, colours) if p)]
    for target in (output, plot):
        if target is not None:
            refuse_overwriting_inputs(target, inputs)
    if output is not None and plot is not None and output.resolve() == plot.resolve():
        raise UsageError("-o and --plot name one file; two files expected")
    options: dict[str, Any] = {"before": before, "side": side, "timeout": timeout}
    options |= {"colours": colours, "overlay": plot is not None}
    try:
        if camera is None and markers is None:  # a top view: its scale given, or the cubes'
            options["rejections"] = rejections
            seen = perceive_top_view(image, px_per_m, origin or (0.0, 0.0), **options)
            scale = seen.scale
        else:
            # imported here: a calibration's file models (pydantic) are a tenth of a
            # second of a plain top view's start-up
            from demoplan.perception.calibrated import calibration_for, perceive_photograph
            from demoplan.perception.calibration import load_calibration, load_markers

            reference = load_calibration(camera) if camera else load_markers(markers)  # type: ignore[arg-type]
            seen = perceive_photograph(image, calibration_for(image, reference), **options)
            scale = (
                f"the camera file {camera}" if camera else f"the markers in the image ({markers})"
            )
    except NoBlocksError as exc:
        if plot is None or exc.overlay is None:
            raise
        # the regions rejected and why: the diagnosis of "no blocks", written alone
        write_atomic_bytes(plot, encode_png(exc.overlay))
        raise InputError(
            f"{exc.message}; the regions rejected, and why, are drawn in {plot}",
            source=exc.source,
        ) from None
    document = scene_document(seen.blocks)
    document["description"] = f"perceived in {image.name}; scale from {scale}"
    overlay = encode_png(seen.overlay) if seen.overlay is not None else None
    with StagedOutputs() as outputs:  # the scene and its picture, both or neither
        if output is not None:
            outputs.add(output, dump_json(document).encode("utf-8", "backslashreplace"))
        if plot is not None and overlay is not None:
            outputs.add(plot, overlay)
    specks = 0
    if plot is not None:
        side = speck_side([b.side for b in seen.blocks.values()])
        specks = sum(is_speck(r, side) for r in seen.rejected)
    return Perceived(seen.blocks, document, seen.rejected, scale, specks)


@dataclass(frozen=True, slots=True)
class PerceivedSequence:
    """The demonstration camera frames show and its file's document
    (``demoplan/demonstration-1``, as ``perceive --sequence -o`` writes it)."""

    demonstration: Demonstration
    document: dict[str, Any]
    frames: int


def perceive_sequence(
    frames: Sequence[Path],
    px_per_m: float | None = None,
    origin: tuple[float, float] | None = None,
    *,
    camera: Path | None = None,
    markers: Path | None = None,
    side: Sides = None,
    timeout: float = PERCEPTION_TIMEOUT,
    output: Path | None = None,
    name: str | None = None,
) -> PerceivedSequence:
    """The demonstration a camera filmed (docs/perception.md "Demonstrations from
    a camera"): ``frames`` are image files in order, or one video file; pixels
    map to the table as for :func:`perceive` (``markers``: calibrated from the
    first frame). A step is recorded each time a block has moved and the
    picture has settled; the hand is ignored. ``timeout``: seconds for the
    whole sequence; ``name``: the demonstration's (default: the first file's
    stem); ``output``: also write the demonstration file there."""
    from demoplan.budget import time_budget
    from demoplan.documents.demonstrations import demonstration_to_dict
    from demoplan.perception.frames import frame_source
    from demoplan.perception.sequence import demonstration_from_frames

    _check_mapping(px_per_m, origin, camera, markers)
    side = one_side(side, "for a --sequence (the tracker's)")
    source = frame_source(frames)
    if output is not None:
        refuse_overwriting_inputs(output, [*frames, *(p for p in (camera, markers) if p)])
    with time_budget(
        timeout,
        f"perceiving the frames stopped at its time budget (--timeout {timeout:g} s){{where}}; "
        "give it more time, fewer frames, or say the blocks' size (--side)",
    ):
        detect = _frame_detector(px_per_m, origin, camera, markers, side, frames[0])
        demo = demonstration_from_frames(
            source,
            detect,
            name=name or _sequence_name(frames),
            side=side,
            total=source.total,
            provenance=(("source", str(frames[0])),),
        )
    from demoplan.documents.demonstrations import check_measured_demonstration

    check_measured_demonstration(demo, str(frames[0]))
    document = demonstration_to_dict(demo)
    if output is not None:
        write_atomic(output, dump_json(document))
    count = dict(demo.provenance).get("frames", 0)
    return PerceivedSequence(demo, document, int(count))


def _sequence_name(frames: Sequence[Path]) -> str:
    """A sequence's default name: a video's stem, or the first image file's
    without a frame number."""
    import re

    stem = frames[0].stem
    return stem if len(frames) == 1 else re.sub(r"[-_. ]*\d+$", "", stem) or stem


def _check_mapping(
    px_per_m: float | None,
    origin: tuple[float, float] | None,
    camera: Path | None,
    markers: Path | None,
    side: tuple[float, ...] | None = None,
    *,
    one_picture: bool = False,
) -> None:
    """Exactly one way from pixels to the table: a scale and an origin, a camera
    file, or a markers file; for ``one_picture`` also ``side`` alone, the cubes'
    size giving the scale of a top view (its origin ``origin``, or 0 0)."""
    given = [name for name, v in (("--camera", camera), ("--markers", markers)) if v is not None]
    scale_given = px_per_m is not None or origin is not None
    if len(given) > 1 or (given and scale_given):
        raise UsageError(
            "one of --px-per-m with --origin, --camera or --markers expected, not "
            + " and ".join(given + (["--px-per-m/--origin"] if scale_given else []))
        )
    if one_picture and not given and side is not None and px_per_m is None:
        return  # the scale from the cubes' size
    if not given and (px_per_m is None or origin is None):
        cube = ", or the cubes' --side (a view straight down)" if one_picture else ""
        raise UsageError(
            "how pixels map to the table is needed: --px-per-m and --origin (a top view), "
            f"--camera FILE or --markers FILE{cube}"
        )


def _frame_detector(
    px_per_m: float | None,
    origin: tuple[float, float] | None,
    camera: Path | None,
    markers: Path | None,
    side: float | None,
    first: Path,
) -> Callable[[Any], list[Any]]:
    """The blocks in one frame (an RGB array), on the table's coordinates."""
    from demoplan.perception.camera import Camera
    from demoplan.perception.images import check_side, check_top_view
    from demoplan.perception.sequence import top_view_detector

    check_side(side)
    if px_per_m is not None and origin is not None:
        check_top_view(px_per_m, origin)
        return top_view_detector(Camera(px_per_m, origin), side)
    from demoplan.perception.calibrated import detect_in_photograph
    from demoplan.perception.calibration import (
        calibrate as calibrate_image,
    )
    from demoplan.perception.calibration import (
        check_image_size,
        load_calibration,
        load_markers,
    )
    from demoplan.perception.frames import frame_source

    if camera is not None:
        calibration = load_calibration(camera)
    else:
        picture = next(iter(frame_source([first]))).image
        calibration = calibrate_image(picture, load_markers(markers), source=str(first))  # type: ignore[arg-type]

    def detect(image: Any) -> list[Any]:
        check_image_size(calibration, image, str(first))
        return detect_in_photograph(image, calibration, side)[0]

    return detect


@dataclass(frozen=True, slots=True)
class Calibrated:
    """A calibration and the camera file's document (``demoplan/camera-1``)."""

    calibration: TableCalibration
    document: dict[str, Any]


def calibrate(
    image: Path,
    markers: Path,
    *,
    output: Path | None = None,
    plot: Path | None = None,
    intrinsics: Path | None = None,
) -> Calibrated:
    """The image → table homography from the markers of the markers file seen
    in ``image`` (docs/perception.md "Calibration"); ``output``: write the camera
    file there, ``plot``: an overlay of the markers found and the table's grid
    (both written only when both are made)."""
    from demoplan.perception.calibration import (
        calibrate as calibrate_image,
    )
    from demoplan.perception.calibration import (
        calibration_document,
        calibration_overlay,
        load_intrinsics,
        load_markers,
    )
    from demoplan.perception.camera import encode_png, load_image

    inputs = [image, markers, *([intrinsics] if intrinsics else [])]
    for target in (output, plot):
        if target is not None:
            refuse_overwriting_inputs(target, inputs)
    if output is not None and plot is not None and output.resolve() == plot.resolve():
        raise UsageError("-o and --plot name one file; two files expected")
    layout = load_markers(markers)
    camera = load_intrinsics(intrinsics) if intrinsics else None
    picture = load_image(image)
    calibration = calibrate_image(picture, layout, source=str(image), intrinsics=camera)
    document = calibration_document(calibration)
    overlay = encode_png(calibration_overlay(picture, calibration)) if plot is not None else None
    with StagedOutputs() as outputs:  # the calibration and its picture, both or neither
        if output is not None:
            outputs.add(output, dump_json(document).encode("utf-8", "backslashreplace"))
        if plot is not None and overlay is not None:
            outputs.add(plot, overlay)
    return Calibrated(calibration, document)
