"""The chunked design the floor benchmark compares against: the same landings by other MuJoCo work."""

from __future__ import annotations

import numpy as np

from somarm.benchmarks import flights
from somarm.tasks import flight
from somarm.tasks.throw import RANGES


def test_the_chunked_design_lands_every_throw_where_the_staircase_does():
    rng = np.random.default_rng(4)
    for n in (1, 20, 300):
        ux, uy = rng.random((2, n))
        Fr, W, M = rng.uniform(*RANGES["Fr"], n), rng.uniform(*RANGES["W"], n), rng.uniform(*RANGES["M"], n)
        chunked = flights.plan(ux, uy, Fr, W, M)
        assert chunked.chunks[0][0] == 0 and chunked.chunks[-1][1] == n
        assert all(b == a2 for (_, b), (a2, _) in zip(chunked.chunks, chunked.chunks[1:], strict=False))
        landed = np.empty(n)
        landed[chunked.order] = flights.fly(chunked)
        np.testing.assert_array_equal(landed, flight.landing_x(ux, uy, Fr=Fr, W=W, M=M))
    assert len(chunked.chunks) > 1  # 300 throws of mixed lengths: several chunks side by side
