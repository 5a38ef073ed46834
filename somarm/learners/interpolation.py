"""The interpolated SOM-Q response (the paper's section 6 extension), compiled with numba.

The paper's greedy response is the weight vector of one action unit: the best one for the one
winning input unit, so it changes in jumps between the maps' units. The interpolated response
blends the greedy actions of the ``n_basis`` input units nearest to the observation:

- basis over the input map: the ``n_basis`` nearest units (``len(input_shape) + 1``: 2 on a
  line, 3 on a rectangle) get the tapered inverse-distance weights
  ``v_i = 1/d_i - 1/d_(n_basis+1)`` (``d`` Euclidean, ``d_(n_basis+1)`` the next unit's
  distance), normalised to sum to 1. A unit's weight falls to 0 before it leaves the nearest
  set, so the weights vary continuously with the observation, and an observation on a unit
  gets that unit's action alone. Between two units far from the others they are linear.
- basis over the action map: each of those units contributes the weights of its own greedy
  action unit (the best Q in its row). A unit whose greedy action unit lies more than
  ``MAX_JUMP`` grid steps from the winner's greedy action unit is left out: there the learned
  mapping jumps (a many-to-one or discontiguous mapping, e.g. four_goals' quadrants), and a
  blend of two far-apart actions would serve neither side.
- exploring steps (probability p) propose one action unit's weights, uninterpolated, as the paper;
  but half of them (``NEIGHBOUR_SHARE``) try a grid neighbour of the winner's greedy action unit
  instead of a random unit. Input units that share one greedy action unit (a third of them on
  reach2) can only learn that the next unit serves them better by trying it; a random unit out
  of 50 is almost never the next one.

Learning (steps 7 to 9, in ``somarm.learners._kernels.learn_kernel``): the winning pair is the winner j
and its greedy action unit k (the unit explored, on an exploring step), so steps 7 and 8 are
as well defined as in the paper, and steps 8 (neighbourhood Q-learning towards the reward) and 9
(the input map) are the paper's. Step 7, when the return beats Q(s_j, a_k):

- its target is the *corrected target* ``u_k + (a' - a)``: where u_k would have to be for the
  blended response a to have been the perturbed action a' (a' itself when a = u_k). Pulling
  u_k to a' instead would drag it towards the blend's errors at observations away from w_j.
- after a greedy (blended) step, the units around k are *shifted* by lambda_A psi_A (target - u_k),
  not pulled towards the target. The paper's pull also contracts the neighbourhood towards u_k
  (psi_A at one grid step is still 0.28 at 50,000 steps under Table 1), which holds every unit
  off its own solution; a shift keeps the neighbours' own places, so a map whose units all sit
  on their solutions is a fixed point. Measured on reach2 (Table 1, 10 trials, 50,000 steps):
  greedy error 0.029 with the pull, 0.017 with the shift. Exploring steps keep the paper's pull,
  which orders the map while it forms. Shifted units stay inside the action bounds.

Periodic action dimensions (``wrap``, the task's joint angles with ``periodic_actions``): each
blended unit's action is first taken to the copy (whole turns apart) nearest the winner's greedy
action, so a blend across the box's edge stays between the two, and the result, the perturbed
action and the corrected target wrap round into the box instead of being clipped.

Random numbers: the same row as the winner response, ``[explore?, random unit, tie-break,
noise...]``; every greedy choice here breaks ties with the row's tie-break number.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from somarm.learners._kernels import arc, grid_distance, nearest_unit, perturbation, wrapped

__all__ = ["MAX_JUMP", "NEIGHBOUR_SHARE", "n_basis_for", "act_kernel", "predict_kernel"]

#: Largest action-map grid distance between the winner's greedy action unit and a blended one.
MAX_JUMP = 1.0
#: Share of the exploring steps that try a map neighbour of the winner's greedy action unit.
NEIGHBOUR_SHARE = 0.5


def n_basis_for(input_shape: tuple[int, ...]) -> int:
    """How many nearest input units the response blends: grid dimensions + 1, at most the units."""
    return min(len(input_shape) + 1, int(np.prod(input_shape)))


@numba.njit(cache=True, nogil=True)
def _nearest(x, weights, trial, order, squared):
    """Fill ``order``/``squared`` with the ``len(order)`` units of ``weights[trial]`` nearest ``x``,
    ascending (ties: lower index)."""
    count = 0
    size = order.shape[0]
    # The distance a unit must beat to enter the list, in a local (the arrays are written in the
    # loop, so a bound read from them each time would be reloaded from memory: twice the cost).
    worst = np.inf
    for m in range(weights.shape[1]):
        total = 0.0
        for i in range(x.shape[0]):
            diff = x[i] - weights[trial, m, i]
            total += diff * diff
        if count < size:
            count += 1
        elif not total < worst:
            continue
        place = count - 1
        while place > 0 and total < squared[place - 1]:
            order[place] = order[place - 1]
            squared[place] = squared[place - 1]
            place -= 1
        order[place] = m
        squared[place] = total
        if count == size:
            worst = squared[size - 1]


@numba.njit(cache=True, nogil=True)
def _greedy(q, trial, j, tie):
    """The action unit with the best ``q[trial, j]``; ties broken by the uniform number ``tie`` (0:
    lowest index).

    One pass finds the first best unit and counts its ties; a second runs only if there are ties.
    (The kernels index whole arrays by trial instead of slicing a view per trial: each view costs
    numba reference counting.)
    """
    top = q[trial, j, 0]
    best = 0
    n_tied = 1
    for n in range(1, q.shape[2]):
        value = q[trial, j, n]
        if value > top:
            top = value
            best = n
            n_tied = 1
        elif value == top:
            n_tied += 1
    if n_tied == 1:
        return best
    pick = min(int(tie * n_tied), n_tied - 1)
    for n in range(best, q.shape[2]):
        if q[trial, j, n] == top:
            if pick == 0:
                return n
            pick -= 1
    return best


@numba.njit(cache=True, nogil=True)
def _exploring_unit(q, trial, j, u, tie, offsets_a):
    """Step 2 when exploring: with probability NEIGHBOUR_SHARE (``u`` below it) a grid neighbour of the
    greedy unit, else (``u`` rescaled) a random unit as in the paper."""
    n_a = q.shape[2]
    if u >= NEIGHBOUR_SHARE:
        return min(int((u - NEIGHBOUR_SHARE) / (1.0 - NEIGHBOUR_SHARE) * n_a), n_a - 1)
    best = _greedy(q, trial, j, tie)
    count = 0
    for n in range(n_a):
        if 0.0 < grid_distance(offsets_a, best, n) <= 1.0:
            count += 1
    if count == 0:  # a one-unit map
        return best
    pick = min(int(u / NEIGHBOUR_SHARE * count), count - 1)
    for n in range(n_a):
        if 0.0 < grid_distance(offsets_a, best, n) <= 1.0:
            if pick == 0:
                return n
            pick -= 1
    return best


@numba.njit(cache=True, nogil=True)
def _response(x, trial, input_weights, action_weights, q, tie, offsets_a, n_basis, low, high, wrap, order,
              squared, beta, units, out):
    """The blended greedy action of trial ``trial`` for ``x`` into ``out``; returns (winner j, its greedy unit k)."""
    _nearest(x, input_weights, trial, order, squared)
    n_found = order.shape[0]
    n_used = min(n_basis, n_found)
    for i in range(n_used):
        beta[i] = 0.0
    if squared[0] == 0.0:
        beta[0] = 1.0
    else:
        cut = 1.0 / math.sqrt(squared[n_basis]) if n_found > n_basis else 0.0
        total = 0.0
        for i in range(n_used):
            beta[i] = 1.0 / math.sqrt(squared[i]) - cut
            total += beta[i]
        if total > 0.0:
            for i in range(n_used):
                beta[i] = beta[i] / total
        else:  # all equally far: the winner alone
            beta[0] = 1.0
            for i in range(1, n_used):
                beta[i] = 0.0
    k = _greedy(q, trial, order[0], tie)
    units[0] = k
    kept = beta[0]
    for i in range(1, n_used):
        units[i] = _greedy(q, trial, order[i], tie) if beta[i] > 0.0 else k
        if beta[i] > 0.0 and grid_distance(offsets_a, k, units[i]) > MAX_JUMP:
            beta[i] = 0.0
        kept += beta[i]
    for d in range(out.shape[0]):
        value = 0.0
        if wrap[d]:
            base = action_weights[trial, k, d]
            period = high[d] - low[d]
            for i in range(n_used):
                if beta[i] > 0.0:
                    value += (beta[i] / kept) * (base + arc(action_weights[trial, units[i], d] - base, period))
            out[d] = wrapped(value, low[d], high[d])
            continue
        for i in range(n_used):
            if beta[i] > 0.0:
                value += (beta[i] / kept) * action_weights[trial, units[i], d]
        out[d] = min(max(value, low[d]), high[d])  # a blend of units in the bounds, up to rounding
    return order[0], k


@numba.njit(cache=True, nogil=True)
def act_kernel(observations, input_weights, action_weights, q, rows, p, epsilon, low, high, wrap, gaussian,
               offsets_a, n_basis, winners, units, actions, targets, shifted):
    """Steps 1 to 5 with the interpolated response, for every trial, in place.

    Shapes as ``somarm.learners._kernels.act_kernel``, plus the action map's ``offsets_a`` (``som.grid_offsets``) and ``targets
    (n_trials, action_dim)``: ``actions`` receives the perturbed actions a' (the output) and
    ``targets`` the corrected step-7 targets ``u_k + (a' - a)``, both inside the bounds (wrapped
    round where ``wrap``).
    """
    size = min(n_basis + 1, input_weights.shape[1])
    order = np.empty(size, dtype=np.int64)
    squared = np.empty(size)
    beta = np.empty(size)
    blended_units = np.empty(size, dtype=np.int64)
    proposal = np.empty(actions.shape[1])
    for trial in range(observations.shape[0]):
        row = rows[trial]
        shifted[trial] = not row[0] < p
        if row[0] < p:
            # Exploring: the paper's random action unit, its weights unblended.
            j = nearest_unit(observations[trial], input_weights[trial])
            k = _exploring_unit(q, trial, j, row[1], row[2], offsets_a)
            for i in range(proposal.shape[0]):
                proposal[i] = action_weights[trial, k, i]
        else:
            j, k = _response(observations[trial], trial, input_weights, action_weights, q, row[2], offsets_a,
                             n_basis, low, high, wrap, order, squared, beta, blended_units, proposal)
        for i in range(actions.shape[1]):
            noise = perturbation(row, i, gaussian)
            if wrap[i]:
                value = wrapped(proposal[i] + noise * epsilon[i], low[i], high[i])
                actions[trial, i] = value
                target = value + arc(action_weights[trial, k, i] - proposal[i], high[i] - low[i])
                targets[trial, i] = wrapped(target, low[i], high[i])
                continue
            value = min(max(proposal[i] + noise * epsilon[i], low[i]), high[i])
            actions[trial, i] = value
            target = value + (action_weights[trial, k, i] - proposal[i])
            targets[trial, i] = min(max(target, low[i]), high[i])
        winners[trial] = j
        units[trial] = k


@numba.njit(cache=True, nogil=True)
def predict_kernel(observations, input_weights, action_weights, q, offsets_a, n_basis, low, high, wrap, out):
    """Greedy interpolated responses, ties to the lowest index: observations ``(n_trials, n_obs,
    obs_dim)`` -> ``out (n_trials, n_obs, action_dim)``."""
    size = min(n_basis + 1, input_weights.shape[1])
    order = np.empty(size, dtype=np.int64)
    squared = np.empty(size)
    beta = np.empty(size)
    blended_units = np.empty(size, dtype=np.int64)
    for trial in range(observations.shape[0]):
        for o in range(observations.shape[1]):
            _response(observations[trial, o], trial, input_weights, action_weights, q, 0.0, offsets_a, n_basis,
                      low, high, wrap, order, squared, beta, blended_units, out[trial, o])

