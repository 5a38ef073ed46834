"""Batched flights (somarm.tasks.flight): a batch as the bodies of one model, the staircase that
lets landed throws leave, and the groups shared between threads."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from somarm.tasks import ballistics, flight, launcher
from somarm.tasks.throw import RANGES


def _throws(n, seed):
    rng = np.random.default_rng(seed)
    throws = {"ux": rng.random(n), "uy": rng.random(n), "W": rng.uniform(*RANGES["W"], n),
              "Fr": rng.uniform(*RANGES["Fr"], n), "M": rng.uniform(*RANGES["M"], n)}
    # Flights of every kind side by side: none at all, drag-free (one step), and the longest.
    if n >= 3:
        throws["uy"][:3] = 0.0, 1.0, 1.0
        throws["Fr"][:3] = 0.1, 0.0, RANGES["Fr"][1]
    return throws


def _land(throws, part=slice(None), **kwargs):
    return flight.landing_x(throws["ux"][part], throws["uy"][part], G=0.05, Fr=throws["Fr"][part],
                            W=throws["W"][part], M=throws["M"][part], **kwargs)


def _alone_in_the_launcher(throws, i):
    """Throw i flown by the dm_env launcher: one projectile of models/launcher.xml, step by step."""
    physics = launcher.load_physics()
    c = {key: float(throws[key][i]) for key in ("Fr", "W", "M")}
    physics.set_conditions(**c)
    ux, uy = float(throws["ux"][i]), float(throws["uy"][i])
    physics.launch(ux, uy, step=float(flight.step_for(ux, uy, c["W"], c["Fr"] / c["M"], G=0.05)))
    return float(physics.fly()[0])


@pytest.mark.parametrize("n", [1, 100])
def test_a_batch_lands_each_throw_where_it_lands_alone_and_within_the_bound(n):
    throws = _throws(n, 10 + n)
    batch = _land(throws)
    exact = ballistics.landing_x(throws["ux"], throws["uy"], Fr=throws["Fr"], W=throws["W"], M=throws["M"])
    assert np.abs(batch - exact).max() <= 1e-6
    for i in range(n):
        assert float(_land(throws, slice(i, i + 1))[0]) == batch[i]  # a batch of one
    for i in range(0, n, 9):
        assert _alone_in_the_launcher(throws, i) == batch[i]  # another model, without the batch machinery


def test_the_batch_flies_in_one_model_that_shrinks_as_throws_land(monkeypatch):
    throws = _throws(100, 5)
    rolled = []
    roll = flight.ProjectileBatch.roll

    def recorded(self, start, nstep, rate, push):
        rolled.append((self.n, len(rate), nstep))
        return roll(self, start, nstep, rate, push)

    monkeypatch.setattr(flight.ProjectileBatch, "roll", recorded)
    landed = _land(throws, n_threads=1)
    sizes, alive, nsteps = (np.array(column) for column in zip(*rolled, strict=True))
    assert alive[0] == 100 and sizes[0] >= 100  # the whole batch starts in one model
    assert len(rolled) > 2 and (np.diff(alive) < 0).all() and (np.diff(sizes) <= 0).all()
    assert (sizes >= alive).all()
    plan = flight._plan(*(throws[key] for key in ("ux", "uy", "Fr", "W", "M")), G=0.05,
                        tolerance=flight.DEFAULT_TOLERANCE, workers=1)
    assert nsteps.sum() == plan.flat[-1].max()  # the batch is stepped once, to its longest flight
    monkeypatch.undo()
    np.testing.assert_array_equal(landed, _land(throws))


def test_a_throw_lands_at_the_same_x_with_any_cap_or_threads():
    throws = _throws(300, 3)
    reference = _land(throws)
    for cap, threads in ((1, 1), (7, 2), (256, 1), (64, 2), (300, 2)):
        np.testing.assert_array_equal(_land(throws, cap=cap, n_threads=threads), reference)
    np.testing.assert_array_equal(_land(throws, slice(40, 60)), reference[40:60])  # a training step of 20


def _staircase_cost(steps, landed_after):
    """Cost of a staircase (segments ending after the first ``landed_after[j]`` flights), as ``_stairs`` counts it."""
    cost, begin, landed = 0.0, 0.0, 0
    for stop in landed_after:
        end = steps[stop - 1]
        cost += flight._SEGMENT_COST + (end - begin) * (flight._STEP_COST + flight._model_size(len(steps) - landed))
        begin, landed = end, stop
    return cost


def test_the_staircase_is_the_cheapest_and_ends_its_segments_between_flights_of_different_lengths():
    rng = np.random.default_rng(0)
    for n in (1, 2, 5, 9, 40, 300):
        steps = np.sort(rng.integers(1, 60, n)).astype(float)
        landed, ends, cost = flight._stairs(steps)
        assert landed[-1] == n and (np.diff(landed) > 0).all() and (np.diff(ends) > 0).all()
        assert (ends == steps[landed - 1]).all()
        assert all(stop == n or steps[stop] > steps[stop - 1] for stop in landed)  # never inside a length
        assert cost == pytest.approx(_staircase_cost(steps, landed))
        if n <= 9:  # every staircase, by brute force: none is cheaper
            cuts = [i + 1 for i in range(n - 1) if steps[i + 1] > steps[i]]
            every = [_staircase_cost(steps, [*chosen, n])
                     for r in range(len(cuts) + 1) for chosen in itertools.combinations(cuts, r)]
            assert cost == pytest.approx(min(every))
    # A large batch of mixed flights lets its short flights leave early: cheaper than one segment.
    steps = np.sort(rng.integers(1, 60, 200)).astype(float)
    assert flight._stairs(steps)[2] < _staircase_cost(steps, [200])


def test_a_large_batch_is_cut_into_the_cheapest_chunks_of_similar_flights():
    rng = np.random.default_rng(0)

    def cost(steps, chunks):
        return sum(flight._SEGMENT_COST + steps[b - 1] * (flight._STEP_COST + flight._model_size(b - a))
                   for a, b in chunks)

    for n, cap in ((1, 256), (20, 256), (3000, 256), (50, 8)):
        steps = np.sort(rng.integers(1, 160, n)).astype(float)
        chunks = flight._chunks(steps, cap)
        assert chunks[0][0] == 0 and chunks[-1][1] == n
        assert all(a < b <= a + cap for a, b in chunks)
        assert all(b == a2 for (_, b), (a2, _) in zip(chunks, chunks[1:], strict=False))
    for n in (1, 5, 9):  # every cut, by brute force: none is cheaper
        steps = np.sort(rng.integers(1, 60, n)).astype(float)
        every = []
        for mask in range(2 ** (n - 1)):  # bit i set: a cut after flight i
            cuts = [0] + [i + 1 for i in range(n - 1) if mask >> i & 1] + [n]
            every.append(cost(steps, list(zip(cuts, cuts[1:], strict=False))))
        assert cost(steps, flight._chunks(steps, 256)) == pytest.approx(min(every))


def test_groups_cover_the_batch_once_within_the_cap_over_the_threads():
    rng = np.random.default_rng(3)
    for n, cap, workers in ((1, 256, 2), (20, 256, 2), (100, 256, 2), (600, 256, 1), (1000, 256, 3), (50, 8, 2)):
        steps = np.sort(rng.integers(1, 60, n)).astype(float)
        shares, longest = flight._groups(steps, cap, workers)
        assert 1 <= len(shares) <= workers
        groups = sorted(group for share in shares for group in share)
        assert groups[0][0] == 0 and groups[-1][1] == n
        assert all(b == a2 for (_, b), (a2, _) in zip(groups, groups[1:], strict=False))
        assert all(0 < b - a <= cap for a, b in groups)
        handing_over = flight._THREAD_COST if len(shares) > 1 else 0.0
        assert longest == pytest.approx(max(sum(flight._stairs(steps[a:b])[2] for a, b in share) for share in shares)
                                        + handing_over)
    # A step's few short flights stay in one thread; a large batch is shared.
    assert len(flight._groups(np.sort(rng.integers(1, 20, 10)).astype(float), 256, 2)[0]) == 1
    assert len(flight._groups(np.sort(rng.integers(1, 45, 1000)).astype(float), 256, 2)[0]) == 2


def test_a_throw_still_flying_after_its_planned_steps_is_an_error():
    throws = _throws(12, 8)
    plan = flight._plan(*(throws[key] for key in ("ux", "uy", "Fr", "W", "M")), G=0.05,
                        tolerance=flight.DEFAULT_TOLERANCE, workers=1)
    understated = (*plan.flat[:-1], np.maximum(plan.flat[-1] - 3.0, 1.0))
    with pytest.raises(RuntimeError, match="still flying after"):
        flight._fly_stairs(understated, np.empty(12), 0.05)
