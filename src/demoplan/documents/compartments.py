"""The compartments of a landmark — the open spaces its walls enclose all
round (a bin's) — from the boxes it is made of, as demonstration files record
them (docs/formats.md, a landmark's ``compartments``) and region goals use
them (docs/learning.md, "Region goals")."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from demoplan.model import Compartment

__all__ = ["WALL_HEIGHT", "compartments"]

WALL_HEIGHT = 0.5
"""A landmark's part rising above this share of its height is a wall (or a
divider); lower ones are its floor."""
NARROWEST = 0.01
"""m: a compartment is at least this wide and deep."""


def compartments(
    boxes: Sequence[tuple[Sequence[float], Sequence[float]]],
) -> tuple[Compartment, ...]:
    """The compartments of a landmark made of ``boxes`` ((low, high) corners,
    its frame from its position): the rectangular spaces its walls enclose
    all round (walls: the parts higher than :data:`WALL_HEIGHT` of the whole),
    from the top of its floor (its lower parts) to the top of its walls. A
    solid thing, or walls that leave a side open, has none.

    The walls' edges cut the plan into cells; a compartment is a set of
    connected cells no wall covers, none on the outer ring, that fills its
    bounding rectangle."""
    lows = np.array([b[0] for b in boxes], dtype=float).reshape(-1, 3)
    highs = np.array([b[1] for b in boxes], dtype=float).reshape(-1, 3)
    if not len(lows):
        return ()
    bottom, top = float(lows[:, 2].min()), float(highs[:, 2].max())
    wall = highs[:, 2] > bottom + WALL_HEIGHT * (top - bottom)
    if not wall.any():
        return ()
    floor = float(highs[~wall, 2].max()) if (~wall).any() else bottom
    rim = float(highs[wall, 2].max())
    xs = np.unique(np.concatenate([lows[wall, 0], highs[wall, 0]]))
    ys = np.unique(np.concatenate([lows[wall, 1], highs[wall, 1]]))
    free = np.array(
        [
            [
                not any(
                    lo[0] <= (xs[i] + xs[i + 1]) / 2 <= hi[0]
                    and lo[1] <= (ys[j] + ys[j + 1]) / 2 <= hi[1]
                    for lo, hi in zip(lows[wall], highs[wall], strict=True)
                )
                for j in range(len(ys) - 1)
            ]
            for i in range(len(xs) - 1)
        ],
        dtype=bool,
    ).reshape(len(xs) - 1, len(ys) - 1)
    out = []
    seen = np.zeros_like(free)
    for start in zip(*np.nonzero(free), strict=True):
        if seen[start]:
            continue
        cells, todo = [], [start]
        seen[start] = True
        while todo:
            i, j = todo.pop()
            cells.append((i, j))
            for n in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
                inside = 0 <= n[0] < free.shape[0] and 0 <= n[1] < free.shape[1]
                if inside and free[n] and not seen[n]:
                    seen[n] = True
                    todo.append(n)
        rows, columns = [c[0] for c in cells], [c[1] for c in cells]
        i0, i1, j0, j1 = min(rows), max(rows), min(columns), max(columns)
        ring = i0 == 0 or j0 == 0 or i1 == free.shape[0] - 1 or j1 == free.shape[1] - 1
        full = len(cells) == (i1 - i0 + 1) * (j1 - j0 + 1)
        x0, x1, y0, y1 = float(xs[i0]), float(xs[i1 + 1]), float(ys[j0]), float(ys[j1 + 1])
        if ring or not full or min(x1 - x0, y1 - y0) < NARROWEST:
            continue
        x0, y0, z0, x1, y1, z1 = (round(v, 6) for v in (x0, y0, floor, x1, y1, rim))
        out.append((x0, y0, z0, x1, y1, z1))
    return tuple(sorted(out))
