"""Figures written to files: the image formats, a figure's bytes with its
labels placed (:func:`~demoplan.plotting.labels.place_labels`) at the
resolution written, atomic saving, failures as one-line input errors, and
observers of every figure written (the tests' check that no label overlaps)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.errors import InputError
from demoplan.plotting.labels import figure_renderer, place_labels

if TYPE_CHECKING:
    from matplotlib.backend_bases import RendererBase
    from matplotlib.figure import Figure

__all__ = [
    "FIGURE_FORMATS",
    "check_figure_path",
    "figure_bytes",
    "figure_errors",
    "observing_saved_figures",
    "save_figure",
]

logger = logging.getLogger(__name__)

_SAVE_OBSERVERS: list[Callable[[Figure, RendererBase, Path], object]] = []


@contextmanager
def observing_saved_figures(
    observer: Callable[[Figure, RendererBase, Path], object],
) -> Iterator[None]:
    """Within the block, call ``observer(figure, renderer, path)`` for every
    figure written by :func:`save_figure` or :func:`figure_bytes`, just before
    it is encoded: its labels placed, at the dpi it is written at, ``renderer``
    the one they were measured with."""
    _SAVE_OBSERVERS.append(observer)
    try:
        yield
    finally:
        _SAVE_OBSERVERS.remove(observer)


FIGURE_FORMATS = frozenset(
    {"png", "pdf", "svg", "svgz", "jpg", "jpeg", "tif", "tiff", "webp", "eps", "ps", "gif"}
)
"""Image formats a figure can be written in, by file extension."""


@contextmanager
def figure_errors(path: Path) -> Iterator[None]:
    """A figure's failures as one-line input errors: matplotlib missing, or the
    file that cannot be written."""
    try:
        yield
    except ImportError:
        raise InputError(
            "matplotlib is not installed; pip install 'demoplan[plot]'", field="--plot"
        ) from None
    except InputError:  # the atomic write's own one line, naming the file
        raise
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot write the plot ({exc})", source=str(path)) from None


def check_figure_path(path: Path, option: str) -> None:
    """One InputError, before any work, if ``path`` cannot take a figure: a
    folder, or an extension that names no image format."""
    from demoplan.fileio import display_path, output_target

    if path.is_dir():
        raise InputError(
            "is a folder; an image file name expected", source=display_path(path), field=option
        )
    output_target(path)  # a socket or a block device: refused before any work
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in FIGURE_FORMATS:
        raise InputError(
            f"'.{suffix}' is not an image format; one of "
            f"{', '.join('.' + f for f in sorted(FIGURE_FORMATS))} expected",
            source=display_path(path),
            field=option,
        )


def figure_bytes(figure: Any, path: Path, dpi: int = 110) -> bytes:
    """``figure`` encoded in the image format of ``path``'s extension, its
    labels placed (:func:`place_labels`) at that ``dpi`` first."""
    import io

    check_figure_path(path, "figure")
    original = figure.dpi
    figure.set_dpi(dpi)
    try:
        crowded = place_labels(figure)
        if crowded:
            logger.warning(
                "%s: no free place for the label(s) %s; they overlap others",
                path.name,
                ", ".join(repr(t.get_text()) for t in crowded),
            )
        if _SAVE_OBSERVERS:
            figure.draw_without_rendering()
            renderer = figure_renderer(figure)
            for observer in list(_SAVE_OBSERVERS):
                observer(figure, renderer, path)
        buffer = io.BytesIO()
        figure.savefig(buffer, format=path.suffix.lower().lstrip("."), dpi=dpi)
    finally:
        figure.set_dpi(original)
    return buffer.getvalue()


def save_figure(figure: Any, path: Path, dpi: int = 110) -> None:
    """Write ``figure`` to ``path`` atomically (a temporary file, then a rename)."""
    from demoplan.fileio import write_atomic_bytes

    write_atomic_bytes(path, figure_bytes(figure, path, dpi))
