"""SOM-Q for one trial, written step by step as in section 4 of the paper (kept for tests and readers).

This is the slow, plain version the batched, compiled learner (``somarm.learners.somq.SOMQLearner``) is tested
against: given the same seed and trial index it must produce bit-identical maps, Q-table and
actions. It draws exactly the same random numbers in exactly the same way: one row per step
from the trial's ``UniformStreams`` row, laid out as

    [explore?, random unit, tie-break, noise for each action dimension]

(two noise numbers per dimension for Gaussian noise). Sums and products are written in the
same order as the kernel so that floating point rounds the same way.

With ``periodic_actions`` the action dimensions the task declares periodic are circles: where
the paper clips an action into its bounds, it wraps round, and where it moves an action unit by
a difference, the difference is taken the shorter way round and the unit wraps back into the box.
"""

from __future__ import annotations

import math

import numpy as np

from somarm.learners.base import initial_generator
from somarm.learners.interpolation import MAX_JUMP, NEIGHBOUR_SHARE, n_basis_for
from somarm.learners.som import grid_coordinates, grid_distances, neighbourhood
from somarm.learners.somq import SOMQConfig, grid_actions, row_width
from somarm.streams import UniformStreams, trial_ids_for
from somarm.validation import check_array, check_bounds, check_periodic

__all__ = ["ReferenceSOMQ"]


def _wrapped(value: float, low: float, high: float) -> float:
    """``value`` moved by whole periods (high - low) into [low, high]; a value inside stays as it is."""
    if low <= value <= high:
        return value
    period = high - low
    value = value - period * math.floor((value - low) / period)
    return min(max(value, low), high)


def _arc(difference: float, period: float) -> float:
    """``difference`` moved by whole periods into [-period/2, period/2): the shorter way round."""
    return difference - period * math.floor(difference / period + 0.5)


def _into_box(value: float, low: float, high: float, wrap: bool) -> float:
    """The paper's "keep inside the bounds": clip, or on a circle wrap round."""
    return _wrapped(value, low, high) if wrap else min(max(value, low), high)


def _winner(weights: np.ndarray, x: np.ndarray) -> int:
    """The unit nearest to ``x`` by squared Euclidean distance (the first on a tie), as a loop."""
    best, winner = math.inf, 0
    for m in range(weights.shape[0]):
        total = 0.0
        for i in range(x.size):
            diff = x[i] - weights[m, i]
            total += diff * diff
        if total < best:
            best, winner = total, m
    return winner

def _greedy(q_row: np.ndarray, tie: float) -> int:
    """The best-Q action unit; ties broken by the uniform number ``tie`` (0 gives the lowest index)."""
    top = q_row.max()
    tied = [n for n in range(q_row.size) if q_row[n] == top]
    return tied[min(int(tie * len(tied)), len(tied) - 1)]


def exploring_unit(q_row: np.ndarray, u: float, tie: float, distances_a: np.ndarray) -> int:
    """The interpolated response's exploring unit: below NEIGHBOUR_SHARE a grid neighbour of the greedy
    unit (in index order), else a random unit, ``u`` rescaled to [0, 1)."""
    n_a = q_row.size
    if u >= NEIGHBOUR_SHARE:
        return min(int((u - NEIGHBOUR_SHARE) / (1.0 - NEIGHBOUR_SHARE) * n_a), n_a - 1)
    best = _greedy(q_row, tie)
    neighbours = [n for n in range(n_a) if 0.0 < distances_a[best, n] <= 1.0]
    if not neighbours:
        return best
    return neighbours[min(int(u / NEIGHBOUR_SHARE * len(neighbours)), len(neighbours) - 1)]


def interpolated_response(x, input_weights, action_weights, q, tie, distances_a, n_basis, low, high, wrap=None):
    """The interpolated greedy response (``somarm.learners.interpolation``), written out plainly.

    ``wrap`` marks the periodic action dimensions (default none): there each blended action is
    taken to its copy nearest the winner's greedy action before blending, and the blend wraps round.

    Returns:
      ``(j, k, response)``: the winning input unit, its greedy action unit, the blended action.
    """
    # The n_basis + 1 nearest input units (ties: lower index first), squared distances summed in order.
    squared = []
    for m in range(input_weights.shape[0]):
        total = 0.0
        for i in range(x.size):
            diff = x[i] - input_weights[m, i]
            total += diff * diff
        squared.append(total)
    order = sorted(range(len(squared)), key=lambda m: (squared[m], m))[: n_basis + 1]
    near = [squared[m] for m in order]
    n_used = min(n_basis, len(order))
    # Tapered inverse-distance weights: 1/d_i - 1/d_(n_basis+1), normalised; a unit hit exactly wins alone.
    if near[0] == 0.0:
        beta = [1.0] + [0.0] * (n_used - 1)
    else:
        cut = 1.0 / math.sqrt(near[n_basis]) if len(order) > n_basis else 0.0
        beta = [1.0 / math.sqrt(near[i]) - cut for i in range(n_used)]
        total = 0.0
        for value in beta:
            total += value
        beta = [value / total for value in beta] if total > 0.0 else [1.0] + [0.0] * (n_used - 1)
    # Each unit's greedy action unit; one too far along the action map from the winner's is left out.
    k = _greedy(q[order[0]], tie)
    units = [k]
    kept = beta[0]
    for i in range(1, n_used):
        units.append(_greedy(q[order[i]], tie) if beta[i] > 0.0 else k)
        if beta[i] > 0.0 and distances_a[k, units[i]] > MAX_JUMP:
            beta[i] = 0.0
        kept += beta[i]
    response = np.empty(action_weights.shape[1])
    for d in range(response.size):
        periodic = wrap is not None and bool(wrap[d])
        value = 0.0
        for i in range(n_used):
            if beta[i] > 0.0:
                unit = action_weights[units[i], d]
                if periodic:  # the copy of the unit's angle nearest the winner's greedy angle
                    base = action_weights[k, d]
                    unit = base + _arc(unit - base, high[d] - low[d])
                value += (beta[i] / kept) * unit
        response[d] = _into_box(value, low[d], high[d], periodic)
    return order[0], k, response


class ReferenceSOMQ:
    """One SOM-Q agent, step by step. Same constructor keywords as ``SOMQLearner`` but a single trial.

    Args:
      config: the learner's parameters.
      observation_low, observation_high: the observation box ``(obs_dim,)``.
      action_low, action_high: the action box ``(action_dim,)``; perturbed actions are kept inside.
      seed: the run's seed.
      trial_id: which trial of the run this agent is (its random stream).
      action_periodic: which action dimensions are angles (default none); circles if the config's
        ``periodic_actions`` says so.
    """

    def __init__(self, config: SOMQConfig, *, observation_low, observation_high, action_low, action_high,
                 seed: int = 0, trial_id: int = 0, action_periodic=None):
        self.config = config
        self.observation_low, self.observation_high = check_bounds("observation", observation_low,
                                                                   observation_high)
        self.action_low, self.action_high = check_bounds("action", action_low, action_high)
        periodic = check_periodic(action_periodic, self.action_low.size)
        self.wrap = [bool(periodic[i]) and config.periodic_actions for i in range(periodic.size)]
        ids = trial_ids_for(1, [trial_id])
        self.streams = UniformStreams(seed, ids, "learner", row_width(config, self.action_low.size))
        self.distances_s = grid_distances(grid_coordinates(config.input_shape))
        self.distances_a = grid_distances(grid_coordinates(config.action_shape))
        n_s, n_a = self.distances_s.shape[0], self.distances_a.shape[0]
        # Table 1: Q zero, action weights evenly in the action bounds, input weights in a range.
        rng = initial_generator(seed, int(ids[0]))
        low, high = self.observation_low, self.observation_high
        if config.input_init is not None:
            low, high = np.full_like(low, config.input_init[0]), np.full_like(high, config.input_init[1])
        self.input_weights = low + (high - low) * rng.random((n_s, low.size))
        if config.action_init == "grid":
            self.action_weights = grid_actions(config.action_shape, self.action_low, self.action_high, config.grid_span)
        else:
            span = self.action_high - self.action_low
            self.action_weights = self.action_low + span * rng.random((n_a, self.action_low.size))
        self.q = np.full((n_s, n_a), float(config.q_init))
        self.t = 0

    def act(self, observation) -> np.ndarray:
        """Steps 1 to 5 for one observation ``(obs_dim,)``; returns the perturbed action."""
        cfg, t = self.config, self.t
        x = check_array("observation", observation, (self.observation_low.size,))
        row = self.streams.next()[0]
        # Step 1: the input unit nearest to the observation (squared Euclidean distance).
        j = _winner(self.input_weights, x)
        # Step 2: a random action unit with probability p, else the best Q for s_j (ties at random).
        n_a = self.q.shape[1]
        explored = bool(row[0] < cfg.p.value(t))
        if explored and cfg.response == "interpolated":
            k = exploring_unit(self.q[j], row[1], row[2], self.distances_a)
        elif explored:
            k = min(int(row[1] * n_a), n_a - 1)
        else:
            top = self.q[j].max()
            tied = [n for n in range(n_a) if self.q[j, n] == top]
            k = tied[min(int(row[2] * len(tied)), len(tied) - 1)]
        # Step 3: the proposed action is a COPY of unit a_k's weights.
        proposed = self.action_weights[k].copy()
        if cfg.response == "interpolated" and not explored:
            # ... or, interpolated, the blend of the nearest input units' greedy actions.
            j, k, proposed = interpolated_response(x, self.input_weights, self.action_weights, self.q, row[2],
                                                   self.distances_a, n_basis_for(cfg.input_shape),
                                                   self.action_low, self.action_high, self.wrap)
        # Step 4: perturb each element by random(-1, 1) * epsilon (or Gaussian * epsilon) and keep
        # the result inside the action bounds (clipped, or wrapped round a periodic dimension).
        epsilon = cfg.epsilon.value(t)
        span = self.action_high - self.action_low
        perturbed = np.empty_like(proposed)
        for i in range(proposed.size):
            if cfg.noise == "gaussian":
                u1, u2 = row[3 + 2 * i], row[4 + 2 * i]
                noise = math.sqrt(-2.0 * math.log1p(-u1)) * math.cos(2.0 * math.pi * u2)
            else:
                noise = 2.0 * row[3 + i] - 1.0
            scale = epsilon * span[i] if cfg.epsilon_relative else epsilon
            value = proposed[i] + noise * scale
            perturbed[i] = _into_box(value, self.action_low[i], self.action_high[i], self.wrap[i])
        # Step 7's target for unit a_k: where u_k would have to be for the proposal to have been the
        # perturbed action (the perturbed action itself when the proposal is u_k).
        target = np.empty_like(perturbed)
        for i in range(perturbed.size):
            offset = self.action_weights[k, i] - proposed[i]
            if self.wrap[i]:
                offset = _arc(offset, self.action_high[i] - self.action_low[i])
            target[i] = _into_box(perturbed[i] + offset, self.action_low[i], self.action_high[i], self.wrap[i])
        if cfg.response == "winner":
            target = perturbed
        self._last = (x, j, k, target, explored)
        # Step 5: output the perturbed action.
        return perturbed.copy()

    def learn(self, reward: float, next_observation=None, terminal: bool = True) -> None:
        """Steps 6 to 10 for the reward that followed the last ``act``."""
        cfg, t = self.config, self.t
        x, j, k, target_k, explored = self._last
        # Step 6 (the reward) and the corrected return r + gamma * max_i Q(s'_j, a_i).
        target = float(reward)
        if cfg.gamma > 0.0 and not terminal:
            x_next = check_array("next_observation", next_observation, (x.size,))
            j_next = _winner(self.input_weights, x_next)
            target = target + cfg.gamma * self.q[j_next].max()
        # Step 7: move the action map towards the perturbed action only if it looks better. After an
        # interpolated greedy proposal the neighbourhood of a_k is shifted by unit a_k's step instead
        # of pulled towards one point, so that neighbours keep their own places.
        if target > self.q[j, k]:
            rates = cfg.lambda_a.value(t) * neighbourhood(self.distances_a[k], cfg.n_a.value(t))
            shift = cfg.response == "interpolated" and not explored
            for i in range(target_k.size):
                low, high, period = self.action_low[i], self.action_high[i], self.action_high[i] - self.action_low[i]
                column = self.action_weights[:, i]  # a view: changed in place
                if not self.wrap[i] and shift:
                    column[:] = np.clip(column + rates * (target_k[i] - column[k]), low, high)
                elif not self.wrap[i]:
                    column += rates * (target_k[i] - column)
                elif shift:  # on a circle: unit a_k's step the shorter way round, every unit wrapped
                    delta = _arc(target_k[i] - column[k], period)
                    column[:] = [_wrapped(w + rate * delta, low, high) for w, rate in zip(column, rates, strict=True)]
                else:
                    column[:] = [_wrapped(w + rate * _arc(target_k[i] - w, period), low, high)
                                 for w, rate in zip(column, rates, strict=True)]
        # Step 8: neighbourhood Q-learning (or only the winning pair, -NL).
        alpha = cfg.alpha.value(t)
        psi_s = neighbourhood(self.distances_s[j], cfg.n_s.value(t))
        if cfg.neighbourhood_q:
            psi_a = neighbourhood(self.distances_a[k], cfg.n_a.value(t))
            self.q += (alpha * psi_s)[:, None] * psi_a[None, :] * (target - self.q)
        else:
            self.q[j, k] = self.q[j, k] + alpha * (target - self.q[j, k])
        # Step 9: move the input map towards the observation.
        rates = cfg.lambda_s.value(t) * psi_s
        self.input_weights += rates[:, None] * (x - self.input_weights)
        # Step 10: the next step.
        self.t += 1
