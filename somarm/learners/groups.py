"""Input maps over groups of observed dimensions whose Q-values add, each answering with its k nearest units.

The paper's SOM-Q has one input map over every observed dimension, and one winning unit names the
state. That map's units must cover the joint space of all the dimensions that vary on their own, so
past four or so of them a map of any size resolves each coarsely. Here the state is seen instead by
G maps, one per group of dimensions (``input_groups``, read by ``somarm.learners.grouping``), as tile coding sees it through several
tilings, and each map answers with a blend of its k nearest units (``k_nearest``):

- features: in map g the ``k`` units nearest the group's part of the observation ``x_g`` get the
  tapered inverse-distance weights ``phi_i = 1/d_i - 1/d_(k+1)`` (``d`` Euclidean, ``d_(k+1)`` the
  next unit's distance), normalised to sum to 1 (``k = 1``: the winner alone, weight 1). A unit's
  weight falls to 0 before it leaves the nearest set, so the blend varies continuously.
- Q: every map keeps its own table ``(n_units, n_action_units)`` over ONE shared action map, and
  ``Q(s, a) = sum_g sum_i phi_gi Q_g(u_gi, a)``; the greedy action unit is the argmax of that sum
  (ties as the paper's: the row's tie-break number when acting, the lowest index when predicting).
- learning (steps 6 to 9): the target is ``r + gamma max_a Q(s', a)`` with the features of s' taken
  before this step's map update. Step 7 (the action map) compares the target with the summed
  ``Q(s, a_k)``. Step 8 moves each map's part of the sum: with ``R_g(a)`` the sum less map g's part,
  unit m near winner u_gi moves ``Q_g(m, a) += (alpha / G) phi_gi psi_S(m) psi_A(a) (target - R_g(a) -
  Q_g(m, a))`` over its own neighbourhood (the winning pair alone without neighbourhood Q-learning).
  alpha / G, as tile coding divides its step by the tilings: every map moves its part towards what
  the others leave unexplained, so at the winners the sum moves by alpha times the error, as one
  map's value does. With one group over every dimension in order and k = 1 these are the paper's
  steps exactly (R = 0). With ``action_gap`` (advantage learning) each action unit's target in step 8
  is lowered by ``action_gap`` times its Q's shortfall from the best at s (``_gap_targets``). Step 9 pulls each map towards its part of the observation round its
  nearest unit.
- the interpolated response: the greedy action unit's weights moved, along each axis of the action
  map's grid, to the top of the parabola through the summed Q of the unit and its two grid
  neighbours (at most half a grid step): torques between the grid's, from the values learned.

Layout, map after map: ``input_weights (n_trials, G * n_units, width)`` (width the largest group's
size; a smaller group's weights are 0 beyond its size) and ``q (n_trials, G * n_units, n_action_units)``;
map g's units are rows ``g * n_units`` to ``(g + 1) * n_units - 1``. Each table starts at ``q_init / G``,
so the sum starts at ``q_init``. Random numbers: the paper's row per step per trial.
"""

from __future__ import annotations

import numba
import numpy as np

from somarm.learners._kernels import _pull, _pull_action, grid_row, neighbourhood_row, perturbation, wrapped
from somarm.learners.growing import grow

__all__ = ["features", "features_kernel", "act_kernel", "learn_kernel", "predict_kernel", "greedy_kernel"]

@numba.njit(cache=True, nogil=True)
def features(x, weights, groups, shapes, k, units, phi, part, order, squared):
    """Each map's ``k`` nearest units to its part of ``x`` and their tapered weights, in place.

    Shapes: x ``(obs_dim,)``, weights ``(G * n_units, width)`` (one trial), groups ``(G, width)``,
    shapes ``(G, 2)`` each map's current grid (its first rows x cols places hold its units), units
    (rows of ``weights``) and phi ``(G, k)``; part ``(width,)``, order and squared ``(k + 1,)`` are scratch.
    """
    n_groups, width = groups.shape
    n_units = weights.shape[0] // n_groups
    for g in range(n_groups):
        count = shapes[g, 0] * shapes[g, 1]
        size = min(k + 1, count)
        for i in range(width):
            part[i] = x[groups[g, i]] if groups[g, i] >= 0 else 0.0
        found = 0
        worst = np.inf
        for m in range(g * n_units, g * n_units + count):
            total = 0.0
            for i in range(width):
                diff = part[i] - weights[m, i]
                total += diff * diff
            if found < size or total < worst:
                slot = found if found < size else size - 1
                while slot > 0 and squared[slot - 1] > total:  # ties keep the lower index first
                    squared[slot] = squared[slot - 1]
                    order[slot] = order[slot - 1]
                    slot -= 1
                squared[slot] = total
                order[slot] = m
                if found < size:
                    found += 1
                worst = squared[found - 1] if found == size else np.inf
        _tapered(order, squared, k, size, units[g], phi[g])


@numba.njit(cache=True, nogil=True)
def _tapered(order, squared, k, size, units, phi):
    """The weights ``1/d_i - 1/d_(k+1)`` of the k nearest, normalised; the nearest alone where it sits on x."""
    n = min(k, size)
    for i in range(k):
        units[i] = order[min(i, n - 1)]
        phi[i] = 0.0
    if n == 1 or squared[0] == 0.0:
        phi[0] = 1.0
        return
    beyond = 1.0 / np.sqrt(squared[n]) if size > n else 0.0
    total = 0.0
    for i in range(n):
        phi[i] = 1.0 / np.sqrt(squared[i]) - beyond
        total += phi[i]
    if total <= 0.0:  # the k nearest and the next all equally far: the nearest alone
        for i in range(n):
            phi[i] = 0.0
        phi[0] = 1.0
        return
    for i in range(n):
        phi[i] /= total


@numba.njit(cache=True, nogil=True)
def _summed(q, units, phi, values):
    """``values[a] = sum_g sum_i phi_gi q[u_gi, a]`` for every action unit a (one trial's q)."""
    for a in range(q.shape[1]):
        values[a] = 0.0
    for g in range(units.shape[0]):
        for i in range(units.shape[1]):
            if phi[g, i] != 0.0:
                for a in range(q.shape[1]):
                    values[a] += phi[g, i] * q[units[g, i], a]


@numba.njit(cache=True, nogil=True)
def deviation(x, weights, group, mid, span, out):
    """The observation's place round one unit, each dimension over its box's span: ``(x_d - c_d) / span_d``
    into ``out (obs_dim,)``, ``c_d`` the unit's weight in the dimensions its map sees (``group``, -1 padded)
    and the box's middle ``mid`` in the others. Returns ``|out|^2``."""
    for d in range(out.shape[0]):
        out[d] = (x[d] - mid[d]) / span[d]
    for i in range(group.shape[0]):
        d = group[i]
        if d >= 0:
            out[d] = (x[d] - weights[i]) / span[d]
    total = 0.0
    for d in range(out.shape[0]):
        total += out[d] * out[d]
    return total


@numba.njit(cache=True, nogil=True)
def _summed_linear(q, slopes, places, units, phi, x, weights, groups, mid, span, z, scale, values):
    """``_summed`` with local linear units: unit u answers ``q[u, a] + scale slopes[u, a] . z_u`` (``deviation``;
    ``slopes[u, 0]`` for every a where the slopes are shared, one column; ``scale`` 1, or one over the action
    grid's axes where a factored table shares its slopes, so that the expanded sum holds them once)."""
    for a in range(q.shape[1]):
        values[a] = 0.0
    one = _one_term(slopes[0], places)
    for g in range(units.shape[0]):
        for i in range(units.shape[1]):
            if phi[g, i] != 0.0:
                u = units[g, i]
                deviation(x, weights[u], groups[g], mid, span, z)
                common = _slope_term(slopes[u], 0, z, places) if one else 0.0
                for a in range(q.shape[1]):
                    total = q[u, a] + scale * (common if one else _slope_term(slopes[u], a, z, places))
                    values[a] += phi[g, i] * total


@numba.njit(cache=True, nogil=True)
def _shared(slopes, places):
    """Whether a unit's slopes ``(rows, obs_dim)`` are shared by every column: one row, or with action slopes
    (``places`` with columns) one row beside one per action axis."""
    return slopes.shape[0] == 1 or places.shape[1] > 0


@numba.njit(cache=True, nogil=True)
def _one_term(slopes, places):
    """Whether every column's slope term is one number (one slope vector shared by every column, no action
    slopes), so a unit's ``_slope_term`` is computed once rather than once per column."""
    return slopes.shape[0] == 1 and places.shape[1] == 0


@numba.njit(cache=True, nogil=True)
def _slope_term(slopes, a, z, places):
    """``slopes[a] . z``, or ``slopes[0] . z`` where one slope vector is shared by every column; with action
    slopes (``places (n_actions, J)`` the action units' places in the grid's box, J > 0) ``(slopes[0] +
    sum_j places[a, j] slopes[1 + j]) . z``."""
    if places.shape[1] > 0:
        total = 0.0
        for d in range(z.shape[0]):
            slope = slopes[0, d]
            for j in range(places.shape[1]):
                slope += places[a, j] * slopes[1 + j, d]
            total += slope * z[d]
        return total
    column = 0 if slopes.shape[0] == 1 else a
    total = 0.0
    for d in range(z.shape[0]):
        total += slopes[column, d] * z[d]
    return total


@numba.njit(cache=True, nogil=True)
def _slope_scale(slopes, places, factored, action_shape):
    """How much of a unit's slope term each table column holds: one over the grid's axes where a factored
    table shares one slope vector (each action adds one column per axis, so the sum holds it once), else 1
    (``slopes`` one trial's, ``(units, rows, obs_dim)``)."""
    return 1.0 / action_shape.shape[0] if factored and _shared(slopes[0], places) else 1.0


@numba.njit(cache=True, nogil=True)
def expand(columns, action_shape, values):
    """A factored table's action values: ``values[a] = columns[i] + columns[rows + j]`` for the action unit
    ``a = (i, j)`` of a ``rows x cols`` grid (a line: ``columns[a]``)."""
    if action_shape.shape[0] == 1:
        for a in range(values.shape[0]):
            values[a] = columns[a]
        return
    rows, cols = action_shape[0], action_shape[1]
    for i in range(rows):
        for j in range(cols):
            values[i * cols + j] = columns[i] + columns[rows + j]


@numba.njit(cache=True, nogil=True)
def _summed_any(q, slopes, places, linear, units, phi, x, weights, groups, mid, span, z, factored, action_shape,
                columns, values):
    """``_summed`` or, with ``linear``, ``_summed_linear``; with ``factored`` the sum over the table's columns
    (into ``columns``) expanded to every action unit (``expand``)."""
    out = columns if factored else values
    if linear:
        _summed_linear(q, slopes, places, units, phi, x, weights, groups, mid, span, z,
                       _slope_scale(slopes, places, factored, action_shape), out)
    else:
        _summed(q, units, phi, out)
    if factored:
        expand(columns, action_shape, values)


@numba.njit(cache=True, nogil=True)
def _parabola_shift(values, unit, shape, weights, out):
    """Add to ``out`` the shift of action unit ``unit`` to the top of the parabola through the summed Q
    of it and its two grid neighbours, along each axis of the action grid ``shape`` (at most half a step)."""
    cols = shape[1] if shape.shape[0] == 2 else 1
    index = (unit // cols, unit - (unit // cols) * cols)
    for axis in range(shape.shape[0]):
        stride = cols if axis == 0 else 1
        place = index[axis]
        if place == 0 or place == shape[axis] - 1:
            continue  # an edge unit: no parabola
        low, high = values[unit - stride], values[unit + stride]
        curve = low - 2.0 * values[unit] + high
        if curve >= 0.0:
            continue
        f = min(max(0.5 * (low - high) / curve, -0.5), 0.5)
        for i in range(out.shape[0]):
            out[i] += 0.5 * f * (weights[unit + stride, i] - weights[unit - stride, i])


@numba.njit(cache=True, nogil=True)
def _greedy(values, tie):
    """The best action unit; among equals the one ``tie`` in [0, 1) picks (-1: the lowest index)."""
    top = values[0]
    for a in range(1, values.shape[0]):
        if values[a] > top:
            top = values[a]
    if tie < 0.0:
        for a in range(values.shape[0]):
            if values[a] == top:
                return a
    n_tied = 0
    for a in range(values.shape[0]):
        if values[a] == top:
            n_tied += 1
    pick = min(int(tie * n_tied), n_tied - 1)
    for a in range(values.shape[0]):
        if values[a] == top:
            if pick == 0:
                return a
            pick -= 1
    return 0


@numba.njit(cache=True, nogil=True)
def act_kernel(observations, input_weights, action_weights, q, slopes, places, linear, factored, mid, span, groups,
               shapes, k, rows, p, epsilon, low, high, wrap, gaussian, interpolated, action_shape, units, phi, chosen, actions):
    """Steps 1 to 5 for every trial: fills ``units``/``phi`` ``(n_trials, G, k)``, ``chosen`` ``(n_trials,)``
    and ``actions`` ``(n_trials, action_dim)`` in place (shapes as the module docstring; ``slopes``
    ``(n_trials, G * n_units, columns, obs_dim)`` and ``places (n_trials, n_action_units, J)`` read only with
    ``linear``)."""
    n_a = action_weights.shape[1]
    values = np.empty(n_a)
    columns = np.empty(q.shape[2])
    z = np.empty(observations.shape[1])
    part = np.empty(groups.shape[1])
    order = np.empty(k + 1, dtype=np.int64)
    squared = np.empty(k + 1)
    for trial in range(observations.shape[0]):
        row = rows[trial]
        features(observations[trial], input_weights[trial], groups, shapes[trial], k, units[trial], phi[trial], part, order, squared)
        exploring = row[0] < p
        if exploring:
            unit = min(int(row[1] * n_a), n_a - 1)
        else:
            _summed_any(q[trial], slopes[trial], places[trial], linear, units[trial], phi[trial], observations[trial],
                        input_weights[trial], groups, mid, span, z, factored, action_shape, columns, values)
            unit = _greedy(values, row[2])
        out = actions[trial]
        for i in range(out.shape[0]):
            out[i] = action_weights[trial, unit, i]
        if interpolated and not exploring:
            _parabola_shift(values, unit, action_shape, action_weights[trial], out)
        for i in range(out.shape[0]):
            value = out[i] + perturbation(row, i, gaussian) * epsilon[i]
            out[i] = wrapped(value, low[i], high[i]) if wrap[i] else min(max(value, low[i]), high[i])
        chosen[trial] = unit


@numba.njit(cache=True, nogil=True)
def learn_kernel(rewards, next_observations, discounts, active, observations, units, phi, chosen, actions,
                 input_weights, action_weights, q, slopes, places, linear, factored, action_shape, mid, span, groups,
                 shapes, k, alpha, lambda_s, lambda_a, n_s, n_a, offsets_s, offsets_a, neighbourhood_q, low, high, wrap, errors,
                 grow_now, gap):
    """Steps 6 to 9 for every ``active`` trial, in place on the maps and the tables (the rules of the module
    docstring; the target is ``rewards + discounts max_a Q(next_observations, a)``, a trial whose discount is 0
    not bootstrapping; with ``linear`` each moved unit's constant and slopes take the normalised step of its own
    answer; with ``gap`` > 0 step 8 moves action unit a towards ``target - gap (max_b Q(s, b) - Q(s, a))``)."""
    n_groups, width = groups.shape
    n_units = q.shape[1] // n_groups
    n_actions = action_weights.shape[1]
    n_columns = q.shape[2]  # n_actions, or with factored the grid's rows + cols
    values = np.empty(n_actions)
    parts = np.zeros((n_groups, n_columns))
    columns = np.zeros(n_columns)
    psi_c = np.zeros(n_columns)
    swap = np.zeros(n_columns, dtype=np.int64)
    targets = np.empty(n_actions)
    psi_s = np.empty(n_units)
    psi_a = np.empty(n_actions)
    part = np.empty(width)
    order = np.empty(k + 1, dtype=np.int64)
    squared = np.empty(k + 1)
    next_units = np.empty((n_groups, k), dtype=np.int64)
    next_phi = np.empty((n_groups, k))
    z = np.empty(observations.shape[1])
    step = alpha / n_groups if not factored else alpha / (n_groups * action_shape.shape[0])
    scale = _slope_scale(slopes[0], places[0], factored, action_shape)
    one = _one_term(slopes[0, 0], places[0])  # every column's slope term one number: computed once a unit
    wrapping = False
    for i in range(wrap.shape[0]):
        wrapping = wrapping or wrap[i]
    for trial in range(rewards.shape[0]):
        if not active[trial]:
            continue
        table = q[trial]
        a_k = chosen[trial]
        target = rewards[trial]
        if discounts[trial] != 0.0:
            features(next_observations[trial], input_weights[trial], groups, shapes[trial], k, next_units, next_phi, part, order,
                     squared)
            _summed_any(table, slopes[trial], places[trial], linear, next_units, next_phi, next_observations[trial],
                        input_weights[trial], groups, mid, span, z, factored, action_shape, columns, values)
            top = values[0]
            for a in range(1, n_actions):
                if values[a] > top:
                    top = values[a]
            target = target + discounts[trial] * top
        # Each map's part of the sum at every action unit, and the sum.
        sums = columns if factored else values
        for a in range(n_columns):
            sums[a] = 0.0
        for g in range(n_groups):
            for a in range(n_columns):
                parts[g, a] = 0.0
            for i in range(k):
                if phi[trial, g, i] != 0.0:
                    u = units[trial, g, i]
                    if linear:
                        deviation(observations[trial], input_weights[trial, u], groups[g], mid, span, z)
                        common = _slope_term(slopes[trial, u], 0, z, places[trial]) if one else 0.0
                        for a in range(n_columns):
                            term = common if one else _slope_term(slopes[trial, u], a, z, places[trial])
                            parts[g, a] += phi[trial, g, i] * (table[u, a] + scale * term)
                        continue
                    for a in range(n_columns):
                        parts[g, a] += phi[trial, g, i] * table[u, a]
            for a in range(n_columns):
                sums[a] += parts[g, a]
        if factored:
            expand(columns, action_shape, values)
            _factored_reach(a_k, action_shape, n_a, neighbourhood_q, psi_c, swap)
        neighbourhood_row(offsets_a, a_k, n_a, psi_a)
        _gap_targets(target, gap, values, targets)
        # Step 7: the shared action map learns only if the perturbed action looks like an improvement.
        if target > values[a_k]:
            if wrapping:
                _pull_action(action_weights[trial], actions[trial], lambda_a, psi_a, wrap, low, high)
            else:
                _pull(action_weights[trial], actions[trial], lambda_a, psi_a)
        # Step 8: each map moves its part towards what the other maps leave unexplained.
        for g in range(n_groups):
            first = g * n_units
            for i in range(k):
                weight = phi[trial, g, i]
                if weight == 0.0:
                    continue
                centre = units[trial, g, i]
                if factored:
                    _move_factored(table, slopes[trial], places[trial], linear, observations[trial], input_weights[trial],
                                   groups[g], mid, span, z, centre, first, shapes[trial, g, 0], shapes[trial, g, 1],
                                   neighbourhood_q, n_s, offsets_s, step * weight, psi_c, swap, a_k, scale, targets,
                                   values, parts[g])
                    continue
                if linear:
                    _move_linear(table, slopes[trial], places[trial], observations[trial], input_weights[trial], groups[g],
                                 mid, span, z, centre, first, shapes[trial, g, 0], shapes[trial, g, 1], neighbourhood_q, n_s,
                                 offsets_s, step * weight, psi_a, a_k, targets, values, parts[g])
                    continue
                if not neighbourhood_q:
                    value = table[centre, a_k]
                    rest = values[a_k] - parts[g, a_k]
                    table[centre, a_k] = value + step * weight * (targets[a_k] - rest - value)
                    continue
                # Only the units within the neighbourhood's reach (grid distance < n_s + 1) can move;
                # each entry moves on its own, so the order of the units does not matter.
                rows, cols = shapes[trial, g, 0], shapes[trial, g, 1]
                r0 = (centre - first) // cols
                c0 = (centre - first) - r0 * cols
                reach = int(n_s + 1.0)
                for r in range(max(0, r0 - reach), min(rows, r0 + reach + 1)):
                    for c in range(max(0, c0 - reach), min(cols, c0 + reach + 1)):
                        psi = max(0.0, 1.0 - offsets_s[abs(r - r0), abs(c - c0)] / (n_s + 1.0))
                        if psi > 0.0:
                            m = first + r * cols + c
                            a_m = step * weight * psi
                            for a in range(n_actions):
                                if psi_a[a] > 0.0:
                                    value = table[m, a]
                                    rest = values[a] - parts[g, a]
                                    table[m, a] = value + a_m * psi_a[a] * (targets[a] - rest - value)
        # Step 9: each map moves towards its part of the observation round its nearest unit; a growing
        # map adds the winner's squared distance to its sum first, and grows when it is time.
        for g in range(n_groups):
            first = g * n_units
            winner = units[trial, g, 0]
            total = 0.0
            for i in range(width):
                part[i] = observations[trial, groups[g, i]] if groups[g, i] >= 0 else 0.0
                diff = part[i] - input_weights[trial, winner, i]
                total += diff * diff
            errors[trial, winner] += total
            grid_row(offsets_s, shapes[trial, g, 0], shapes[trial, g, 1], winner - first, n_s, psi_s)
            _pull(input_weights[trial, first:first + n_units], part, lambda_s, psi_s)
            if grow_now:
                grow(input_weights[trial, first:first + n_units], table[first:first + n_units],
                     errors[trial, first:first + n_units], shapes[trial, g], offsets_s.shape[0], offsets_s.shape[1])


@numba.njit(cache=True, nogil=True)
def _gap_targets(target, gap, values, targets):
    """Each action unit's target for step 8 into ``targets``: ``target`` itself, or with ``gap`` > 0 the
    advantage-learning target ``target - gap (max_b values[b] - values[a])`` (``values`` the summed Q at s)."""
    if gap == 0.0:
        for a in range(values.shape[0]):
            targets[a] = target
        return
    top = values[0]
    for a in range(1, values.shape[0]):
        if values[a] > top:
            top = values[a]
    for a in range(values.shape[0]):
        targets[a] = target - gap * (top - values[a])


@numba.njit(cache=True, nogil=True)
def _move_linear(table, slopes, places, x, weights, group, mid, span, z, centre, first, rows, cols, neighbourhood_q,
                 n_s, offsets_s, rate, psi_a, a_k, targets, values, parts):
    """Step 8 for one of a map's k nearest units (``centre``, its weight folded into ``rate``) when units are
    local linear: each unit m within reach moves its constant and slopes by ``rate psi_S(m) psi_A(a) e z /
    (1 + |z|^2)``, ``e`` the error of its own answer at x (``target`` less the other maps' part less
    ``q[m, a] + slopes[m, a] . z``), so that answer moves by the step a constant unit's value would. Shared
    slopes (one column, or with action slopes one per action axis beside it) move with the tried unit a_k's
    change alone, after every constant has moved (``_move_shared``)."""
    shared = _shared(slopes[0], places)
    one = _one_term(slopes[0], places)
    if not neighbourhood_q:
        norm = _norm(deviation(x, weights[centre], group, mid, span, z), places, a_k)
        answer = table[centre, a_k] + _slope_term(slopes[centre], a_k, z, places)
        change = rate * (targets[a_k] - (values[a_k] - parts[a_k]) - answer) / norm
        table[centre, a_k] += change
        if shared:
            _move_shared(slopes[centre], change, z, places, a_k)
            return
        for d in range(z.shape[0]):
            slopes[centre, a_k, d] += change * z[d]
        return
    r0 = (centre - first) // cols
    c0 = (centre - first) - r0 * cols
    reach = int(n_s + 1.0)
    for r in range(max(0, r0 - reach), min(rows, r0 + reach + 1)):
        for c in range(max(0, c0 - reach), min(cols, c0 + reach + 1)):
            psi = max(0.0, 1.0 - offsets_s[abs(r - r0), abs(c - c0)] / (n_s + 1.0))
            if psi > 0.0:
                m = first + r * cols + c
                norm = _norm(deviation(x, weights[m], group, mid, span, z), places, a_k)
                tried = 0.0
                common = _slope_term(slopes[m], 0, z, places) if one else 0.0
                for a in range(table.shape[1]):
                    if psi_a[a] > 0.0:
                        answer = table[m, a] + (common if one else _slope_term(slopes[m], a, z, places))
                        change = rate * psi * psi_a[a] * (targets[a] - (values[a] - parts[a]) - answer) / norm
                        table[m, a] += change
                        if shared:
                            tried = change if a == a_k else tried
                            continue
                        for d in range(z.shape[0]):
                            slopes[m, a, d] += change * z[d]
                if shared:
                    _move_shared(slopes[m], tried, z, places, a_k)


@numba.njit(cache=True, nogil=True)
def _norm(squared, places, a_k):
    """The normalising ``1 + |features|^2`` of a local linear unit's answer for the tried unit a_k: ``1 + |z|^2``,
    and with action slopes ``1 + |z|^2 (1 + |places[a_k]|^2)`` (the action slopes' features are
    ``places[a_k, j] z``)."""
    extra = 0.0
    for j in range(places.shape[1]):
        extra += places[a_k, j] * places[a_k, j]
    return 1.0 + squared * (1.0 + extra)


@numba.njit(cache=True, nogil=True)
def _move_shared(slopes, change, z, places, a_k):
    """A unit's shared slopes after its tried constant moved by ``change``: ``slopes[0] += change z``, and with
    action slopes ``slopes[1 + j] += change places[a_k, j] z``."""
    for d in range(z.shape[0]):
        slopes[0, d] += change * z[d]
        for j in range(places.shape[1]):
            slopes[1 + j, d] += change * places[a_k, j] * z[d]


@numba.njit(cache=True, nogil=True)
def _factored_reach(a_k, action_shape, n_a, neighbourhood_q, psi_c, swap):
    """For a factored table and the tried action unit ``a_k``: each column's neighbourhood along its axis
    (``max(0, 1 - d / (n_a + 1))``, d the steps from a_k's place on that axis; a_k's own columns alone
    without neighbourhood Q-learning) into ``psi_c``, and in ``swap`` the action unit that is a_k with its
    place on the column's axis moved to the column's."""
    axes = action_shape.shape[0]
    cols = action_shape[1] if axes == 2 else 1
    place = (a_k // cols, a_k - (a_k // cols) * cols)
    first = 0
    for axis in range(axes):
        for i in range(action_shape[axis]):
            d = abs(i - place[axis])
            if neighbourhood_q:
                psi_c[first + i] = max(0.0, 1.0 - d / (n_a + 1.0))
            else:
                psi_c[first + i] = 1.0 if d == 0 else 0.0
            swap[first + i] = i * cols + place[1] if axis == 0 else place[0] * cols + i
        first += action_shape[axis]


@numba.njit(cache=True, nogil=True)
def _move_factored(table, slopes, places, linear, x, weights, group, mid, span, z, centre, first, rows, cols,
                   neighbourhood_q, n_s, offsets_s, rate, psi_c, swap, a_k, scale, targets, values, parts):
    """Step 8 for one of a map's k nearest units with a factored table: each unit m within reach (``centre``
    alone without neighbourhood Q-learning) moves each column c with ``psi_c[c] > 0`` towards what the rest
    leaves of the target of the action unit ``swap[c]``, by ``rate psi_S(m) psi_c[c]`` (local linear units:
    the normalised step of ``_move_linear``; shared slopes, ``scale`` of them in each column, move with the
    changes of the tried unit a_k's own columns, after every column has moved)."""
    shared = _shared(slopes[0], places)
    one = _one_term(slopes[0], places)
    r0 = (centre - first) // cols
    c0 = (centre - first) - r0 * cols
    reach = int(n_s + 1.0) if neighbourhood_q else 0
    for r in range(max(0, r0 - reach), min(rows, r0 + reach + 1)):
        for c in range(max(0, c0 - reach), min(cols, c0 + reach + 1)):
            psi = max(0.0, 1.0 - offsets_s[abs(r - r0), abs(c - c0)] / (n_s + 1.0)) if neighbourhood_q else 1.0
            if psi > 0.0:
                m = first + r * cols + c
                norm = 1.0 + deviation(x, weights[m], group, mid, span, z) if linear else 1.0
                tried = 0.0
                common = _slope_term(slopes[m], 0, z, places) if linear and one else 0.0
                for col in range(table.shape[1]):
                    if psi_c[col] > 0.0:
                        answer = table[m, col]
                        if linear:
                            answer += scale * (common if one else _slope_term(slopes[m], col, z, places))
                        change = rate * psi * psi_c[col] * (targets[swap[col]] - (values[swap[col]] - parts[col]) - answer) / norm
                        table[m, col] += change
                        if linear and shared:
                            tried += change if swap[col] == a_k else 0.0
                        elif linear:
                            for d in range(z.shape[0]):
                                slopes[m, col, d] += change * z[d]
                if linear and shared:
                    _move_shared(slopes[m], tried, z, places, a_k)


@numba.njit(cache=True, nogil=True)
def _scratch(n_groups, width, k, n_actions, obs_dim, n_columns):
    """The per-call scratch of the greedy kernels: ``values``, ``part``, ``order``, ``squared``, ``units``, ``phi``,
    ``z``, ``columns``."""
    return (np.empty(n_actions), np.empty(width), np.empty(k + 1, dtype=np.int64), np.empty(k + 1),
            np.empty((n_groups, k), dtype=np.int64), np.empty((n_groups, k)), np.empty(obs_dim), np.empty(n_columns))


@numba.njit(cache=True, nogil=True)
def _greedy_of(x, input_weights, q, slopes, places, linear, factored, action_shape, mid, span, groups, shapes, k,
               scratch):
    """The greedy action unit of one observation (ties to the lowest index); leaves the summed Q in
    ``scratch[0]`` and each map's nearest units in ``scratch[4]``."""
    values, part, order, squared, units, phi, z, columns = scratch
    features(x, input_weights, groups, shapes, k, units, phi, part, order, squared)
    _summed_any(q, slopes, places, linear, units, phi, x, input_weights, groups, mid, span, z, factored, action_shape,
                columns, values)
    return _greedy(values, -1.0)


@numba.njit(cache=True, nogil=True)
def predict_kernel(observations, input_weights, action_weights, q, slopes, places, linear, factored, mid, span, groups,
                   shapes, k, interpolated, action_shape, low, high, wrap, out):
    """Greedy actions of ``observations (n_trials, n_obs, obs_dim)`` into ``out (n_trials, n_obs, action_dim)``:
    the best summed Q, ties to the lowest index, the parabola's shift with the interpolated response."""
    scratch = _scratch(groups.shape[0], groups.shape[1], k, action_weights.shape[1], observations.shape[2], q.shape[2])
    for trial in range(observations.shape[0]):
        for n in range(observations.shape[1]):
            unit = _greedy_of(observations[trial, n], input_weights[trial], q[trial], slopes[trial], places[trial], linear,
                              factored, action_shape, mid, span, groups, shapes[trial], k, scratch)
            action = out[trial, n]
            for i in range(action.shape[0]):
                action[i] = action_weights[trial, unit, i]
            if interpolated:
                _parabola_shift(scratch[0], unit, action_shape, action_weights[trial], action)
                for i in range(action.shape[0]):
                    value = action[i]
                    action[i] = wrapped(value, low[i], high[i]) if wrap[i] else min(max(value, low[i]), high[i])


@numba.njit(cache=True, nogil=True)
def greedy_kernel(observations, input_weights, q, slopes, places, linear, factored, action_shape, n_actions, mid, span,
                  groups, shapes, k, units_out, first_out):
    """The greedy action unit (ties to the lowest index) and the first map's nearest unit of
    ``observations (n_trials, n_obs, obs_dim)``, into ``units_out``/``first_out`` ``(n_trials, n_obs)``."""
    scratch = _scratch(groups.shape[0], groups.shape[1], k, n_actions, observations.shape[2], q.shape[2])
    for trial in range(observations.shape[0]):
        for n in range(observations.shape[1]):
            units_out[trial, n] = _greedy_of(observations[trial, n], input_weights[trial], q[trial], slopes[trial],
                                             places[trial], linear, factored, action_shape, mid, span, groups,
                                             shapes[trial], k, scratch)
            first_out[trial, n] = scratch[4][0, 0]


@numba.njit(cache=True, nogil=True)
def features_kernel(observations, input_weights, groups, shapes, k, active, units, phi):
    """Each ``active`` trial's nearest units and their weights for ``observations (n_trials, obs_dim)``, into
    ``units``/``phi`` ``(n_trials, G, k)`` (what ``act_kernel`` finds, with nothing chosen or drawn)."""
    part = np.empty(groups.shape[1])
    order = np.empty(k + 1, dtype=np.int64)
    squared = np.empty(k + 1)
    for trial in range(observations.shape[0]):
        if active[trial]:
            features(observations[trial], input_weights[trial], groups, shapes[trial], k, units[trial], phi[trial], part,
                     order, squared)
