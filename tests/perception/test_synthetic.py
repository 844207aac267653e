"""The synthetic images' anti-aliasing (perception/synthetic.py): a block's
coverage of each pixel, sampled only along its edges, is the coverage sampling
every pixel gives — to the last bit."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception.synthetic import block_coverage


def _every_pixel_sampled(
    u: float, v: float, half: float, yaw: float, box: tuple[int, int, int, int], n: int
) -> np.ndarray:
    """Coverage with every pixel's n × n samples tested (v up)."""
    c0, c1, v0, v1 = box
    offsets = (np.arange(n) + 0.5) / n
    us = (np.arange(c0, c1)[:, None] + offsets[None, :]).reshape(-1)
    vs = (np.arange(v0, v1)[:, None] + offsets[None, :]).reshape(-1)
    uu, vv = np.meshgrid(us, vs)
    du, dv = uu - u, vv - v
    qu = math.cos(yaw) * du + math.sin(yaw) * dv
    qv = -math.sin(yaw) * du + math.cos(yaw) * dv
    inside = (np.abs(qu) <= half) & (np.abs(qv) <= half)
    coverage: np.ndarray = inside.reshape(v1 - v0, n, c1 - c0, n).mean(axis=(1, 3))
    return coverage


@settings(max_examples=100, deadline=None)  # ~160 edge pixels each
@given(
    u=st.floats(-5.0, 45.0),
    v=st.floats(-5.0, 45.0),
    half=st.floats(0.1, 25.0),
    yaw=st.floats(-math.pi, math.pi),
    n=st.sampled_from([1, 2, 3, 4, 16]),
)
def test_edge_sampling_equals_sampling_every_pixel(
    u: float, v: float, half: float, yaw: float, n: int
) -> None:
    box = (0, 40, 0, 40)
    offsets = (np.arange(n) + 0.5) / n
    fast = block_coverage(u, v, half, yaw, box, offsets)
    np.testing.assert_array_equal(fast, _every_pixel_sampled(u, v, half, yaw, box, n))
