"""Frames of a run and a storyboard of them (like the paper's Fig. 4).

A simulator that renders (MuJoCo) gives its own picture. Otherwise a frame
draws the objects from above where the world says they stand (a held object is
in the air and left out), the targets of the chosen goal as dashed outlines,
and a caption with the action just done.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from demoplan.errors import InputError
from demoplan.execution.world import Observation
from demoplan.model import ObjectGeometry, Pose
from demoplan.scenes.scene import Scene

__all__ = ["FrameWriter"]

FAILED_COLOUR = "#b00020"
"""The caption colour of a frame that shows a failure."""

FRAME_INCHES = (4.5, 4.0)
"""A frame's size before its caption's extra lines."""

MARGINS = ("left", "bottom", "right", "top", "wspace", "hspace")
"""A figure's subplot parameters (its layout sets them)."""


@dataclass
class _Frame:
    """The figure a run's frames are drawn on, one after the other: its axes,
    the look its unmoving parts were drawn for (top view and the targets'
    colours, or a picture's size), its margins before any layout, and the ids
    of the artists of the frame drawn last."""

    figure: Any
    ax: Any
    look: tuple[object, ...]
    margins: dict[str, float]
    moving: set[int]


class FrameWriter:
    """Writes ``frame-0000.png``… into ``folder`` and ``storyboard.png`` at the end."""

    def __init__(
        self, folder: Path, targets: dict[str, Pose] | None = None, scene: Scene | None = None
    ):
        try:
            from demoplan.plotting.backend import use_agg

            use_agg()
        except ImportError:
            raise InputError(
                "matplotlib is not installed; pip install 'demoplan[plot]'", field="--frames"
            ) from None
        self.folder = Path(folder)
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"cannot create the folder ({exc})", source=str(folder)) from None
        self.targets = targets or {}
        self.scene = scene  # its landmarks are drawn under every frame
        self.frames: list[tuple[Observation, str]] = []
        self.failed: set[int] = set()  # frames after which a failure was seen
        self.images: list[Any] = []
        self.written: list[Path] = []
        self._limits: tuple[float, float, float, float] | None = None
        self._frame: _Frame | None = None  # the figure the frames are drawn on, reused

    def capture(self, observation: Observation, caption: str, image: Any = None) -> None:
        """A frame: the simulator's own picture when it renders one, else a top view."""
        self.frames.append((observation, caption))
        self.images.append(image)
        path = self.folder / f"frame-{len(self.frames) - 1:04d}.png"
        from demoplan.plotting.backend import tight_layout
        from demoplan.plotting.captions import grow_for_titles
        from demoplan.plotting.colours import assign_colours, object_colour
        from demoplan.plotting.output import save_figure

        failed = len(self.frames) - 1 in self.failed
        look: tuple[object, ...]
        if image is None:
            given = self.scene.given_colours if self.scene is not None else {}
            assign_colours(
                [*self.targets, *observation.poses], given
            )  # as every figure of the task
            look = ("top view", *(object_colour(name) for name in self.targets))
            figure, ax = self._frame_axes(look, lambda ax: self._draw_still(ax, observation))
            before = {id(artist) for artist in ax.get_children()}
            self._draw_moving(ax, observation, caption, failed)
        else:
            shape = getattr(image, "shape", None)  # an array's; anything else: a new figure
            look = ("picture", shape, str(image.dtype)) if shape is not None else (object(),)
            figure, ax = self._frame_axes(look, lambda ax: None)
            before = {id(artist) for artist in ax.get_children()}
            self._draw_picture(ax, image, caption, failed)
        assert self._frame is not None
        self._frame.moving = {id(a) for a in ax.get_children() if id(a) not in before}
        grow_for_titles(figure, [[ax]])
        tight_layout(figure)
        save_figure(figure, path, dpi=90)
        self.written.append(path)

    def _frame_axes(
        self, look: tuple[object, ...], draw_still: Callable[[Any], None]
    ) -> tuple[Any, Any]:
        """The figure the frames are drawn on, ``draw_still`` (what every frame
        of this ``look`` shows alike) drawn on it: made for the first frame,
        reused by the next ones of the same look (the targets' colours, the
        picture's size), the moving parts of the last frame taken away, its
        size and margins a new figure's again. A fresh figure per frame drew
        the same picture, its axes, ticks and unmoving parts made again each
        time."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        from demoplan.plotting.labels import remove_leaders

        frame = self._frame
        if frame is not None and frame.look == look:
            remove_leaders(frame.ax)
            for artist in [*frame.ax.get_children()]:
                if id(artist) in frame.moving:
                    artist.remove()
            frame.moving = set()
            frame.figure.set_size_inches(*FRAME_INCHES)
            frame.figure.subplots_adjust(**frame.margins)  # laid out from where a new one starts
            return frame.figure, frame.ax
        figure = Figure(figsize=FRAME_INCHES)
        FigureCanvasAgg(figure)
        ax = figure.subplots()
        params = figure.subplotpars
        margins = {side: getattr(params, side) for side in MARGINS}
        draw_still(ax)
        self._frame = _Frame(figure, ax, look, margins, set())
        return figure, ax

    def mark_failure(self, text: str) -> None:
        """The last frame shows a failure (``text``: what was seen): it is kept in
        the storyboard and its caption says so."""
        if self.frames:
            index = len(self.frames) - 1
            observation, caption = self.frames[index]
            self.frames[index] = (observation, f"{caption}\nFAILED: {text}")
            self.failed.add(index)

    def storyboard_frames(self, max_panels: int = 12) -> list[int]:
        """The frames a storyboard shows: the first, the last and every one that
        shows a failure, then frames evenly between, up to ``max_panels``."""
        n = len(self.frames)
        if n == 0:
            return []
        chosen = {0, n - 1, *sorted(self.failed)[: max(0, max_panels - 2)]}
        spare = max_panels - len(chosen)
        if spare > 0:
            chosen |= {round(k * (n - 1) / (spare + 1)) for k in range(1, spare + 1)}
        return sorted(chosen)[:max_panels]

    def storyboard(self, max_panels: int = 12) -> Path | None:
        """:meth:`storyboard_frames` in one image (``storyboard.png``)."""
        if not self.frames:
            return None
        import matplotlib.pyplot as plt

        from demoplan.plotting.output import save_figure

        figure = self.storyboard_figure(max_panels)
        path = self.folder / "storyboard.png"
        save_figure(figure, path, dpi=90)
        plt.close(figure)
        self.written.append(path)
        return path

    def storyboard_figure(self, max_panels: int = 12) -> Any:
        """The storyboard's figure: :meth:`storyboard_frames` in rows of four,
        laid out (the caller closes it)."""
        import matplotlib.pyplot as plt

        from demoplan.plotting.backend import tight_layout
        from demoplan.plotting.captions import grow_for_titles

        picks = self.storyboard_frames(max_panels)
        columns = min(4, len(picks))
        rows = math.ceil(len(picks) / columns)
        figure, axes = plt.subplots(
            rows, columns, figsize=(3.6 * columns, 3.3 * rows), squeeze=False
        )
        for ax in axes.flat:
            ax.set_visible(False)
        for ax, index in zip(axes.flat, picks, strict=False):
            ax.set_visible(True)
            self._panel(ax, index)
        grow_for_titles(figure, [list(row) for row in axes])
        tight_layout(figure)
        return figure

    def _panel(self, ax: Any, index: int) -> None:
        observation, caption = self.frames[index]
        image = self.images[index]
        if image is None:
            self._draw(ax, observation, caption, index in self.failed)
        else:
            self._draw_picture(ax, image, caption, index in self.failed)

    def _draw_picture(self, ax: Any, image: Any, caption: str, failed: bool) -> None:
        """The simulator's own picture, with its caption."""
        ax.imshow(image)
        ax.set_axis_off()
        self._caption(ax, caption, failed)

    def _draw(self, ax: Any, observation: Observation, caption: str, failed: bool) -> None:
        from demoplan.plotting.colours import assign_colours

        given = self.scene.given_colours if self.scene is not None else {}
        assign_colours([*self.targets, *observation.poses], given)  # as every figure of the task
        self._draw_still(ax, observation)
        self._draw_moving(ax, observation, caption, failed)

    def _draw_still(self, ax: Any, observation: Observation) -> None:
        """What every top view of the run shows alike: the landmarks, the
        targets as dashed outlines, the run's limits (the colours assigned)."""
        from demoplan.plotting.colours import ink, object_colour
        from demoplan.plotting.patches import draw_landmarks, object_patch

        if self.scene is not None:
            draw_landmarks(ax, self.scene)
        for name, pose in self.targets.items():
            shape = observation.geometry.get(name)
            patch = object_patch(pose, shape, "none", 1.0)
            patch.set_linestyle("--")
            patch.set_edgecolor(ink(object_colour(name)))  # a white mug's seen on white
            ax.add_patch(patch)
        if self._limits is None:
            points = [p.position for p in observation.poses.values()] + [
                p.position for p in self.targets.values()
            ]
            if self.scene is not None:  # a landmark whole: its corners' circle
                shapes = dict(self.scene.landmark_geometry)
                for name, pose in self.scene.landmarks:
                    reach = math.hypot(*shapes[name].size[:2]) / 2 if name in shapes else 0.0
                    x, y, z = pose.position
                    points += [(x - reach, y - reach, z), (x + reach, y + reach, z)]
            xs, ys = [p[0] for p in points], [p[1] for p in points]
            margin = 0.08
            self._limits = (min(xs) - margin, max(xs) + margin, min(ys) - margin, max(ys) + margin)
        x0, x1, y0, y1 = self._limits
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)

    def _draw_moving(self, ax: Any, observation: Observation, caption: str, failed: bool) -> None:
        """What a top view shows of its moment: the objects where they stand
        (lowest first), each named, the held one named, the caption."""
        from demoplan.plotting.colours import object_colour
        from demoplan.plotting.labels import add_label
        from demoplan.plotting.patches import object_patch

        for name, pose in sorted(observation.poses.items(), key=lambda item: item[1].position[2]):
            geometry: ObjectGeometry | None = observation.geometry.get(name)
            ax.add_patch(object_patch(pose, geometry, object_colour(name), 0.85))
            add_label(ax, name, (pose.position[0], pose.position[1]), fontsize=6)
        if observation.held:
            ax.text(
                0.02, 0.02, f"in the hand: {observation.held}", transform=ax.transAxes, fontsize=7
            )
        self._caption(ax, caption, failed)

    @staticmethod
    def _caption(ax: Any, caption: str, failed: bool) -> None:
        """The frame's caption over it, its lines broken to fit the frame's
        cell (a failure's reason is long), red where it shows a failure."""
        from demoplan.plotting.captions import fit_title

        fit_title(ax, caption, fontsize=7, color=FAILED_COLOUR if failed else "black")
