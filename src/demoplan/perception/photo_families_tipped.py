"""Rows of cubes lying tipped over, for the generated photograph families: a
tower of two to four cubes of different colours fallen on its side and rolled
about its long axis, so that each cube shows two faces upwards — a lit one and
a darker strip — and its neighbours in the row are other colours: none of
those faces is a cube's top. (Made for mrhan_stacks' bottom right, labelled at
first as two such rows; its depth frame shows two standing stacks there — the
`towers` family — but rows lying so are a case a table may hold.)

A row is a convex box cut into cubes: each cube is drawn as the faces the camera
sees (outward normal towards the camera's centre), shaded by how far the face
turns up to the light (a face turned straight up as a top is, 1; an upright one
as a standing cube's sides are), the faces between two cubes of the row hidden.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from demoplan.perception.photos import PhotoRig

__all__ = ["TippedRow", "pixels_of", "tipped_faces"]

_LIGHT_ACROSS = np.array([-0.6, 0.8])
"""The horizontal direction the light comes from for an upright face's shade (as a
standing cube's sides are shaded)."""


@dataclass(frozen=True, slots=True)
class TippedRow:
    """Cubes of ``side`` (m) in a row lying on the table: the row's centre (m), the
    direction of its long axis ``yaw`` (deg), its ``roll`` about that axis (deg;
    0: lying flat, 45: on an edge) and each cube's colour name and RGB, in order."""

    x: float
    y: float
    yaw: float
    roll: float
    side: float
    colours: tuple[str, ...]
    rgbs: tuple[tuple[int, int, int], ...]

    def frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(centre, along, up-across, flat-across): the row's centre in the world (m,
        its height that of the rolled square's centre) and its three unit axes."""
        a, r = math.radians(self.yaw), math.radians(self.roll)
        along = np.array([math.cos(a), math.sin(a), 0.0])
        across = np.array([-math.sin(a), math.cos(a), 0.0])
        up = np.array([0.0, 0.0, 1.0])
        first = math.cos(r) * across + math.sin(r) * up
        second = -math.sin(r) * across + math.cos(r) * up
        lift = self.side / 2 * (abs(math.cos(r)) + abs(math.sin(r)))  # its lowest edge on the table
        return np.array([self.x, self.y, lift]), along, first, second

    def footprint(self) -> np.ndarray:
        """Its outline on the table (m), the box's corners dropped (a convex hull's points)."""
        centre, along, first, second = self.frame()
        half = self.side / 2
        length = len(self.colours) * self.side / 2
        corners = [
            centre + i * length * along + j * half * first + k * half * second
            for i in (-1, 1)
            for j in (-1, 1)
            for k in (-1, 1)
        ]
        return np.array([c[:2] for c in corners])

    def top(self) -> float:
        """The height (m) of its highest edge."""
        r = math.radians(self.roll)
        return self.side * (abs(math.cos(r)) + abs(math.sin(r)))


def tipped_faces(
    row: TippedRow, eye: np.ndarray
) -> list[tuple[float, np.ndarray, tuple[int, int, int]]]:
    """The faces of ``row`` the camera at ``eye`` (x, y, z; m) sees, each as (its
    distance to the camera, its four corners (4 × 3, m), its colour shaded): the
    two or three sides of the box turned towards the camera, cut at the cubes, and
    the row's end faces when turned towards it."""
    centre, along, first, second = row.frame()
    half = row.side / 2
    count = len(row.colours)
    faces = []
    for index, rgb in enumerate(row.rgbs):
        middle = centre + (index - (count - 1) / 2) * row.side * along
        sides = [(first, second), (-first, second), (second, first), (-second, first)]
        if index == 0:
            sides.append((-along, first))
        if index == count - 1:
            sides.append((along, first))
        for normal, tangent in sides:
            other = np.cross(normal, tangent)
            face_centre = middle + half * normal
            if normal @ (eye - face_centre) <= 0:
                continue  # turned away from the camera
            corners = np.array(
                [
                    face_centre + half * (i * tangent + j * other)
                    for i, j in ((-1, -1), (1, -1), (1, 1), (-1, 1))
                ]
            )
            # as a standing cube's: 1 turned straight up, 0.42 ± 0.18 upright
            shade = (
                0.42 + 0.58 * max(0.0, float(normal[2])) + 0.18 * float(normal[:2] @ _LIGHT_ACROSS)
            )
            colour = tuple(int(c) for c in np.clip(np.asarray(rgb, float) * shade, 0, 255))
            distance = float(np.linalg.norm(eye - face_centre))
            faces.append((distance, corners, (colour[0], colour[1], colour[2])))
    return faces


def pixels_of(rig: PhotoRig, corners: np.ndarray, supersample: int) -> np.ndarray:
    """World points (N × 3, m) → the fixed-point (4 fractional bits) canvas
    coordinates OpenCV's polygon fills take (``shift=4``), as
    :func:`~demoplan.perception.photos.canvas_points` gives them for one height."""
    n = supersample
    pixels = []
    for x, y, z in corners:
        u, v = rig.to_pixels(float(x), float(y), float(z))
        pixels.append(((u * n - 0.5) * 16, ((rig.height_px - v) * n - 0.5) * 16))
    rounded: np.ndarray = np.rint(np.array(pixels)).astype(np.int32)
    return rounded
