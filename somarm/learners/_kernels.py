"""Compiled SOM-Q steps (numba), looping over trials; the random numbers come in from NumPy.

These kernels are the fast path of ``somarm.learners.somq.SOMQLearner``. They do the same arithmetic in the
same order as ``somarm.learners.reference.ReferenceSOMQ`` (no fastmath), so both give bit-identical
results. Units whose neighbourhood value is 0 are skipped: their update would add exactly 0.
They release the GIL (``nogil``), so learners stepped in different threads run side by side.

``wrap (action_dim,)`` bools mark the action dimensions treated as circles (``periodic_actions``):
there the box's low and high are one point, actions wrap round instead of being clipped, and the
action map moves along the shorter arc. Every other dimension runs the plain code, unchanged.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["all_finite", "grid_distance", "neighbourhood_row", "grid_row", "nearest_unit", "perturbation", "wrapped", "arc", "act_kernel", "learn_kernel"]

_TWO_PI = 2.0 * math.pi


@numba.njit(cache=True, nogil=True)
def all_finite(values):
    """True if no element of ``values`` (any shape) is NaN or inf; cheaper than NumPy on small arrays."""
    for value in values.flat:
        if not math.isfinite(value):
            return False
    return True


@numba.njit(cache=True, nogil=True)
def grid_distance(offsets, a, b):
    """Grid distance between units ``a`` and ``b`` of a map whose ``somarm.learners.som.grid_offsets`` are
    ``offsets (rows, cols)``; the same number as ``somarm.learners.som.grid_distances``' ``[a, b]``."""
    cols = offsets.shape[1]
    ra, rb = a // cols, b // cols
    return offsets[abs(ra - rb), abs((a - ra * cols) - (b - rb * cols))]


@numba.njit(cache=True, nogil=True)
def neighbourhood_row(offsets, centre, width, out):
    """The linear neighbourhood ``max(0, 1 - d / (width + 1))`` of every unit round ``centre`` into ``out``,
    d the grid distance read from ``offsets`` (as ``somarm.learners.som.neighbourhood``, bit for bit)."""
    grid_row(offsets, offsets.shape[0], offsets.shape[1], centre, width, out)


@numba.njit(cache=True, nogil=True)
def grid_row(offsets, rows, cols, centre, width, out):
    """``neighbourhood_row`` over the first ``rows x cols`` units of a map laid out row-major in that shape
    (a growing map's current grid), 0 beyond them; distances still read from the full map's ``offsets``."""
    w = width + 1.0
    r0 = centre // cols
    c0 = centre - r0 * cols
    m = 0
    for r in range(rows):
        dr = abs(r - r0)
        for c in range(cols):
            out[m] = max(0.0, 1.0 - offsets[dr, abs(c - c0)] / w)
            m += 1
    for n in range(m, out.shape[0]):
        out[n] = 0.0


@numba.njit(cache=True, nogil=True)
def nearest_unit(x, weights):
    """Index of the row of ``weights (n_units, dim)`` nearest ``x`` (squared distance), ties to the lowest."""
    best = np.inf
    j = 0
    for m in range(weights.shape[0]):
        total = 0.0
        for i in range(x.shape[0]):
            diff = x[i] - weights[m, i]
            total += diff * diff
        if total < best:
            best = total
            j = m
    return j


@numba.njit(cache=True, nogil=True)
def perturbation(row, i, gaussian):
    """The unit-scale noise of action dimension ``i`` from a row of uniforms: a standard normal
    (Box-Muller on ``row[3 + 2i], row[4 + 2i]``) or uniform in [-1, 1) (``row[3 + i]``)."""
    if gaussian:
        u1 = row[3 + 2 * i]
        u2 = row[4 + 2 * i]
        return math.sqrt(-2.0 * math.log1p(-u1)) * math.cos(_TWO_PI * u2)
    return 2.0 * row[3 + i] - 1.0


@numba.njit(cache=True, nogil=True)
def wrapped(value, low, high):
    """``value`` moved by whole periods ``high - low`` into [low, high]; a value inside stays as it is."""
    if low <= value <= high:
        return value
    period = high - low
    value = value - period * math.floor((value - low) / period)
    return min(max(value, low), high)  # rounding may land a hair outside


@numba.njit(cache=True, nogil=True)
def arc(difference, period):
    """``difference`` moved by whole periods into [-period/2, period/2): the shorter way round a circle."""
    return difference - period * math.floor(difference / period + 0.5)


@numba.njit(cache=True, nogil=True)
def _pull(weights, x, rate, psi):
    """The SOM update of one map towards ``x``: ``w += rate * psi * (x - w)`` where psi > 0, in place."""
    for m in range(weights.shape[0]):
        if psi[m] > 0.0:
            step = rate * psi[m]
            for i in range(x.shape[0]):
                w = weights[m, i]
                weights[m, i] = w + step * (x[i] - w)


@numba.njit(cache=True, nogil=True)
def _pull_action(weights, x, rate, psi, wrap, low, high):
    """``_pull`` of the action map: along the shorter arc, and wrapped back into the box, where ``wrap``."""
    for m in range(weights.shape[0]):
        if psi[m] > 0.0:
            step = rate * psi[m]
            for i in range(x.shape[0]):
                w = weights[m, i]
                if wrap[i]:
                    weights[m, i] = wrapped(w + step * arc(x[i] - w, high[i] - low[i]), low[i], high[i])
                else:
                    weights[m, i] = w + step * (x[i] - w)


@numba.njit(cache=True, nogil=True)
def _shift(weights, k, target, rate, psi, low, high, wrap):
    """Move every unit by ``rate * psi * (target - w_k)`` where psi > 0, kept inside [low, high]: the
    neighbourhood of unit k shifted by unit k's own SOM step, not pulled towards one point, in place.
    Where ``wrap``: the step along the shorter arc, wrapped back into the box instead of clipped."""
    for i in range(target.shape[0]):
        if wrap[i]:
            delta = arc(target[i] - weights[k, i], high[i] - low[i])
            for m in range(weights.shape[0]):
                if psi[m] > 0.0:
                    weights[m, i] = wrapped(weights[m, i] + rate * psi[m] * delta, low[i], high[i])
            continue
        delta = target[i] - weights[k, i]
        for m in range(weights.shape[0]):
            if psi[m] > 0.0:
                weights[m, i] = min(max(weights[m, i] + rate * psi[m] * delta, low[i]), high[i])


@numba.njit(cache=True, nogil=True)
def act_kernel(observations, input_weights, action_weights, q, rows, p, epsilon, low, high, wrap,
               gaussian, winners, units, actions):
    """Steps 1 to 5 for every trial; fills ``winners``, ``units`` and ``actions`` in place.

    Shapes: observations ``(n_trials, obs_dim)``, input_weights ``(n_trials, n_s, obs_dim)``,
    action_weights ``(n_trials, n_a, action_dim)``, q ``(n_trials, n_s, n_a)``, rows
    ``(n_trials, width)``, epsilon/low/high/wrap ``(action_dim,)`` (epsilon per action dimension),
    winners/units ``(n_trials,)``, actions
    ``(n_trials, action_dim)``.
    """
    n_a = q.shape[2]
    for trial in range(observations.shape[0]):
        row = rows[trial]
        j = nearest_unit(observations[trial], input_weights[trial])
        if row[0] < p:
            k = min(int(row[1] * n_a), n_a - 1)
        else:
            top = q[trial, j, 0]
            for n in range(1, n_a):
                if q[trial, j, n] > top:
                    top = q[trial, j, n]
            n_tied = 0
            for n in range(n_a):
                if q[trial, j, n] == top:
                    n_tied += 1
            pick = min(int(row[2] * n_tied), n_tied - 1)
            k = 0
            for n in range(n_a):
                if q[trial, j, n] == top:
                    if pick == 0:
                        k = n
                        break
                    pick -= 1
        for i in range(actions.shape[1]):
            noise = perturbation(row, i, gaussian)
            value = action_weights[trial, k, i] + noise * epsilon[i]
            if wrap[i]:
                actions[trial, i] = wrapped(value, low[i], high[i])
            else:
                actions[trial, i] = min(max(value, low[i]), high[i])
        winners[trial] = j
        units[trial] = k


@numba.njit(cache=True, nogil=True)
def learn_kernel(rewards, next_observations, bootstrap, gamma, observations, winners, units, actions,
                 input_weights, action_weights, q, alpha, lambda_s, lambda_a, n_s, n_a,
                 offsets_s, offsets_a, neighbourhood_q, shifted, low, high, wrap):
    """Steps 6 to 9 for every trial, in place on the maps and the Q-table.

    ``bootstrap[trial]`` says whether to add ``gamma * max_i Q(s'_j, a_i)`` (s'_j the winner of
    ``next_observations[trial]`` before this step's input-map update). Step 7 pulls the action
    map towards ``actions[trial]``, or (``shifted[trial]``, an interpolated greedy step) moves
    unit k's neighbourhood by unit k's step towards it, kept inside the action bounds ``low``,
    ``high`` (``somarm.learners.interpolation``; a shift, unlike a pull, could leave them). Dimensions
    marked in ``wrap`` move along the shorter arc and wrap round.
    """
    n_units_s = q.shape[1]
    n_units_a = q.shape[2]
    psi_s = np.empty(n_units_s)
    psi_a = np.empty(n_units_a)
    wrapping = False
    for i in range(wrap.shape[0]):
        wrapping = wrapping or wrap[i]
    for trial in range(rewards.shape[0]):
        j = winners[trial]
        k = units[trial]
        target = rewards[trial]
        if bootstrap[trial]:
            j_next = nearest_unit(next_observations[trial], input_weights[trial])
            top = q[trial, j_next, 0]
            for n in range(1, n_units_a):
                if q[trial, j_next, n] > top:
                    top = q[trial, j_next, n]
            target = target + gamma * top
        neighbourhood_row(offsets_s, j, n_s, psi_s)
        neighbourhood_row(offsets_a, k, n_a, psi_a)
        # Step 7: the action map learns only if the perturbed action looks like an improvement.
        if target > q[trial, j, k]:
            if shifted[trial]:
                _shift(action_weights[trial], k, actions[trial], lambda_a, psi_a, low, high, wrap)
            elif wrapping:
                _pull_action(action_weights[trial], actions[trial], lambda_a, psi_a, wrap, low, high)
            else:
                _pull(action_weights[trial], actions[trial], lambda_a, psi_a)
        # Step 8: neighbourhood Q-learning, or the winning pair alone.
        if neighbourhood_q:
            for m in range(n_units_s):
                if psi_s[m] > 0.0:
                    a_m = alpha * psi_s[m]
                    for n in range(n_units_a):
                        if psi_a[n] > 0.0:
                            value = q[trial, m, n]
                            q[trial, m, n] = value + a_m * psi_a[n] * (target - value)
        else:
            value = q[trial, j, k]
            q[trial, j, k] = value + alpha * (target - value)
        # Step 9: the input map moves towards the observation.
        _pull(input_weights[trial], observations[trial], lambda_s, psi_s)
