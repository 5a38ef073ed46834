"""SOM-Q (Smith 2002, section 4): an input SOM, an action SOM and a Q-table between them.

Batched over independent trials: ``input_weights (n_trials, n_input_units, obs_dim)``,
``action_weights (n_trials, n_action_units, action_dim)``, ``q (n_trials, n_input_units,
n_action_units)``; one agent is ``n_trials == 1``. The learner knows only the observation and
action boxes, observations, actions and rewards. Rules where the paper is brief:

- t counts learning steps from 0; ``act`` and ``learn`` of one step read all seven schedules
  at the same t, and ``learn`` advances it.
- the perturbed action is a copy of the chosen unit's weights plus noise, clipped to the action
  bounds (the algorithm's "keep inside"); bad observations and rewards are rejected, never clipped.
- epsilon is in action units, as Table 1 reads literally; ``epsilon_relative=True`` reads it as a
  fraction of each action range instead (the paper plots angles normalised to [0, 1], and with
  that reading Table 1's 0.1 becomes 0.63 rad; which one the paper used is not stated).
- ``periodic_actions=True`` treats the action dimensions the task declares periodic (its joint
  angles: theta and theta + 2 pi are one pose) as circles: perturbed actions wrap round instead
  of being clipped, and the action map moves along the shorter arc and wraps back into the box.
  Off by default (the paper's box); it changes nothing where the task declares no periodic dimension.
- delayed reward (gamma > 0): s'_j is the winner of the next observation before this step's
  input-map update; terminal trials use the reward alone.
- ``predict`` is greedy: the best Q for the winning input unit, ties to the lowest index, no
  random number drawn and nothing learned.
- random numbers: one row per step per trial, ``[explore?, random unit, tie-break, noise x
  action_dim, replayed step x replay]`` (two per dimension for Gaussian noise, Box-Muller); the initial weights come
  from a separate child stream of the trial's learner seed (``learners.initial_generator``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from somarm.learners import _kernels, grouping, groups, growing, interpolation
from somarm.learners.base import ConfigBase, validate_common
from somarm.learners.maps import MapLearner, grid_floats, shape_text
from somarm.learners.planning import CellModel
from somarm.learners.replay import Replay
from somarm.learners.schedules import InverseDecay, Schedule
from somarm.learners.som import grid_coordinates, grid_offsets, winners
from somarm.learners.trail import Trail
from somarm.validation import check_number

__all__ = ["RESPONSES", "ACTION_INITS", "REPRESENTATION_SETTINGS", "SOMQConfig", "SOMQLearner", "row_width",
           "grid_actions", "paper_representation"]

#: The settings that choose how the state is seen and Q is held and learned beyond the paper's one map
#: (``somarm.learners.groups``); at ``SOMQConfig``'s defaults they are the paper's model.
REPRESENTATION_SETTINGS = ("input_groups", "k_nearest", "grow_every", "local_linear", "shared_slopes",
                           "action_slopes", "action_factored", "action_gap", "n_step", "replay", "plan",
                           "input_placement")

#: The greedy responses: the paper's winning unit, or the interpolation of ``somarm.learners.interpolation``.
RESPONSES = ("winner", "interpolated")
#: How the action weights start: the paper's uniform random draw, or evenly over the action box.
ACTION_INITS = ("random", "grid")
#: How the input weights start: the paper's uniform random draw, or on a regular grid over the map's box.
INPUT_PLACEMENTS = ("random", "grid")

_F1 = InverseDecay(1000.0)


@dataclass(frozen=True)
class SOMQConfig(ConfigBase):
    """Everything that defines a SOM-Q learner; the defaults are Table 1's numbers (reach2, Fig. 7).

    ``somarm.learners.presets.get("table1")`` is the full Table 1 (it also starts the input weights in
    [0, 1]). A plain number given for a schedule is taken as a constant schedule.
    """

    input_shape: tuple[int, ...] = (50,)
    """Input map grid: ``(n,)`` for a line or ``(rows, cols)`` for a rectangle."""
    action_shape: tuple[int, ...] = (50,)
    """Action map grid, as ``input_shape``."""
    alpha: Schedule = Schedule(1.0, _F1)
    """Q-learning rate."""
    lambda_s: Schedule = Schedule(1.0, _F1)
    """Learning rate of the input map."""
    lambda_a: Schedule = Schedule(1.0, _F1)
    """Learning rate of the action map."""
    n_s: Schedule = Schedule(20.0, _F1)
    """Input map neighbourhood size N_S (grid units; 0 = the winner alone)."""
    n_a: Schedule = Schedule(20.0, _F1)
    """Action map neighbourhood size N_A."""
    p: Schedule = Schedule(1.0, _F1)
    """Probability of choosing a random action unit (Q-learning exploration), in [0, 1]."""
    epsilon: Schedule = Schedule(0.1, _F1)
    """Largest perturbation of each action element (the standard deviation for Gaussian noise)."""
    gamma: float = 0.0
    """Discount in [0, 1]; 0 is the immediate reward of all the paper's experiments."""
    neighbourhood_q: bool = True
    """Neighbourhood Q-learning (+NL); False updates only the winning pair (-NL)."""
    noise: Literal["uniform", "gaussian"] = "uniform"
    """Perturbation: ``uniform`` random(-1, 1) x epsilon (the paper's), or ``gaussian`` N(0, 1) x epsilon."""
    epsilon_relative: bool = False
    """Read epsilon as a fraction of each action dimension's range (high - low) instead of in action units."""
    input_init: tuple[float, float] | None = None
    """Range of the initial input weights in every dimension; None = the observation bounds."""
    response: Literal["winner", "interpolated"] = "winner"
    """Greedy response: ``winner`` (the paper's: the best action unit of the winning input unit) or
    ``interpolated`` (a blend over the nearest input units' greedy actions; ``somarm.learners.interpolation``)."""

    periodic_actions: bool = False
    """Treat the action dimensions the task declares periodic (joint angles) as circles: wrap round
    instead of clipping, and move the action map along the shorter arc (False: the paper's box)."""

    q_init: float = 0.0
    """Every Q value at the start (the paper's 0). A value above every return the task can give
    (optimistic initial values) makes the greedy policy try each pair until its value is learned."""

    action_init: Literal["random", "grid"] = "random"
    """Initial action weights: ``random`` (the paper's: uniform in the action box) or ``grid`` (unit i
    at its grid place spread evenly over the box, the ends on the bounds; needs one grid dimension
    per action dimension)."""

    grid_span: float = 1.0
    """With ``action_init="grid"``: the fraction of the action box the grid covers, centred on the box's
    middle, in (0, 1] (1: the ends on the bounds). A narrower grid gives finer torques where balancing
    and reaching need them; the units still move over the whole box if lambda_A > 0."""

    input_groups: str = "all"
    """Which observed dimensions each input map sees (``somarm.learners.groups``): ``all`` (one map over
    every dimension, the paper's), ``pairs`` or ``triples`` (one map per pair or triple of dimensions), ``singles`` (one per
    dimension), ``chunks:K`` (consecutive runs of K dimensions in index order) or index lists such as
    ``0,1;2,3`` (0-based, ';' between maps). Every map has ``input_shape`` units and its own Q-table over
    the one action map; their Q-values add, as tile coding's tilings do. A rule of thumb: groups of 2-3
    dimensions that vary together, a 10x10 map each."""

    k_nearest: int = 1
    """Input units per map that answer for a state, blended by tapered inverse distance, when acting and
    when learning (1: the winning unit alone, the paper's). Any value but 1, or grouped maps, runs
    ``somarm.learners.groups``' kernels; the paper's model is ``input_groups=all`` with ``k_nearest=1``."""

    grow_every: int = 0
    """Learning steps between growths of each input map (``somarm.learners.growing``): a growing map starts
    with 2x2 units (2 on a line) and gains a row or a column where its units' quantisation error is largest,
    up to ``input_shape`` units (0: every map has ``input_shape`` units from the start, the paper's)."""

    local_linear: bool = False
    """Each input unit answers with a local linear model, not one value per action unit: its Q of action
    unit a at observation x is ``q[u, a] + slopes[u, a] . z``, ``z`` the observation's place round the unit
    (in its map's dimensions, from the unit's weights; in every other observed dimension, from the box's
    middle; each over its box's span), so one map's unit can hold how the value changes with every observed
    dimension (``somarm.learners.groups``). Runs the grouped kernels; not with ``grow_every``."""

    shared_slopes: bool = False
    """With ``local_linear``: one slope vector per input unit, shared by every action unit, ``q[u, a] +
    slopes[u] . z``: how the value changes round a unit is learned from every step that unit answers for,
    whatever action was tried (a per-state baseline), and each action keeps only its constant (with
    ``action_factored``, each column of the factored table its constant)."""

    action_slopes: bool = False
    """With ``shared_slopes``: each unit's shared slope vector also changes linearly with the action unit's
    place, ``q[u, a] + (slopes[u, 0] + sum_j p_aj slopes[u, 1 + j]) . z``, ``p_a`` the action unit's weights
    over the grid's half-width round the box's middle (-1 to 1 across a grid that spans ``grid_span`` of the
    box). Each unit then holds a local linear policy beside its local linear value: which action is best
    changes with the observation within the unit's cell, so the greedy action follows the state more finely
    than the units lie. Every slope learns from every step, as the shared ones do. Not with
    ``action_factored``."""

    action_factored: bool = False
    """Q adds over the action grid's axes: ``Q(s, (i, j)) = Q_rows(s, i) + Q_cols(s, j)``, each map's table
    holding a column per row and per column of the action grid (3 + 3 for a 3x3 grid, not 9), so with
    ``action_init=grid`` each action dimension's value is learned from every step that tries any of its
    places (``somarm.learners.groups``). Runs the grouped kernels."""

    action_gap: float = 0.0
    """Advantage learning (Bellemare et al. 2016, "Increasing the action gap"): step 8 moves action unit a
    towards ``target - action_gap (max_b Q(s, b) - Q(s, a))`` instead of the target, in [0, 1). Where many
    states share an input unit, or the time step is short, the values of the actions differ by less than
    the noise of their targets; this widens the gap between the best action and the rest without changing
    which action is best. 0 is the paper's Q-learning; above 0 runs the grouped kernels
    (``somarm.learners.groups``)."""

    n_step: int = 1
    """Steps a target looks ahead (``somarm.learners.trail``): 1 is the paper's one-step target ``r + gamma
    max_a Q(s', a)``; n > 1 learns each step n steps after it was taken, towards the n rewards that followed
    it and ``gamma^n max_a Q`` of the state n steps on (sooner at an episode's end). Where an action changes
    the reward only through the states it leads to, this carries its effect in the rewards themselves rather
    than in a small difference between the next states' values. Needs gamma > 0; runs the grouped kernels."""

    replay: int = 0
    """Kept steps learned from again after each step (``somarm.learners.replay``; experience replay, Lin 1992):
    each trial keeps its last ``replay_capacity`` learned steps and relearns ``replay`` of them, drawn uniformly,
    after every new one. A replayed step moves Q alone (its target with today's Q, over both neighbourhoods),
    never a map. Where a reward is rare, its few steps are learned from many times. 0 is the paper's model
    (each step learned from once); above 0 runs the grouped kernels."""

    replay_capacity: int = 100_000
    """With ``replay``: the learned steps each trial keeps, the oldest overwritten first."""

    input_placement: Literal["random", "grid"] = "random"
    """Initial input weights: ``random`` (the paper's: uniform over the observation box, or ``input_init``) or
    ``grid`` (each map's units on a regular grid over its dimensions' box or ``input_init``, unit i at the middle of its cell;
    needs a map with one grid axis per dimension it sees). With ``lambda_s=0`` the grid's cells stay fixed."""

    plan: int = 0
    """Sweeps of value iteration over a model of the map's cells each ``plan_every`` steps
    (``somarm.learners.planning``; Dyna, Sutton 1990): each trial counts, per pair of input unit and action
    unit, its rewards and the input units it led to, and Q is set to the model's values; a pair never tried
    keeps ``q_init``. 0 is the paper's model (no model). Needs one input map with ``k_nearest=1`` and the
    one-step target; runs the grouped kernels."""

    plan_every: int = 1000
    """With ``plan``: steps between two solutions of the model."""

    SCHEDULES = ("alpha", "lambda_s", "lambda_a", "n_s", "n_a", "p", "epsilon")

    def __post_init__(self) -> None:
        validate_common(self, probabilities=("p",))
        if self.response not in RESPONSES:
            raise ValueError(f"response must be one of {', '.join(RESPONSES)}, got {self.response!r}")
        if self.action_init not in ACTION_INITS:
            raise ValueError(f"action_init must be one of {', '.join(ACTION_INITS)}, got {self.action_init!r}")
        object.__setattr__(self, "q_init", check_number("q_init", self.q_init))
        span = check_number("grid_span", self.grid_span)
        if not 0.0 < span <= 1.0:
            raise ValueError(f"grid_span must be in (0, 1], got {span!r}")
        if span != 1.0 and self.action_init != "grid":
            raise ValueError(f"grid_span applies only with action_init='grid', got action_init={self.action_init!r}")
        object.__setattr__(self, "grid_span", span)
        object.__setattr__(self, "input_groups", grouping.check_groups(self.input_groups))
        if isinstance(self.k_nearest, bool) or not isinstance(self.k_nearest, (int, np.integer)) or self.k_nearest < 1:
            raise ValueError(f"k_nearest must be a whole number >= 1, got {self.k_nearest!r}")
        object.__setattr__(self, "k_nearest", int(self.k_nearest))
        if isinstance(self.grow_every, bool) or not isinstance(self.grow_every, (int, np.integer)) or self.grow_every < 0:
            raise ValueError(f"grow_every must be a whole number >= 0 (0: no growth), got {self.grow_every!r}")
        object.__setattr__(self, "grow_every", int(self.grow_every))
        if not isinstance(self.local_linear, (bool, np.bool_)):
            raise ValueError(f"local_linear must be true or false, got {self.local_linear!r}")
        object.__setattr__(self, "local_linear", bool(self.local_linear))
        if not isinstance(self.action_factored, (bool, np.bool_)):
            raise ValueError(f"action_factored must be true or false, got {self.action_factored!r}")
        object.__setattr__(self, "action_factored", bool(self.action_factored))
        gap = check_number("action_gap", self.action_gap)
        if not 0.0 <= gap < 1.0:
            raise ValueError(f"action_gap must be in [0, 1) (0: plain Q-learning), got {self.action_gap!r}")
        object.__setattr__(self, "action_gap", gap)
        if not isinstance(self.shared_slopes, (bool, np.bool_)):
            raise ValueError(f"shared_slopes must be true or false, got {self.shared_slopes!r}")
        object.__setattr__(self, "shared_slopes", bool(self.shared_slopes))
        if self.shared_slopes and not self.local_linear:
            raise ValueError("shared_slopes needs local_linear=true, got local_linear=false")
        if not isinstance(self.action_slopes, (bool, np.bool_)):
            raise ValueError(f"action_slopes must be true or false, got {self.action_slopes!r}")
        object.__setattr__(self, "action_slopes", bool(self.action_slopes))
        if self.action_slopes and not self.shared_slopes:
            raise ValueError("action_slopes needs shared_slopes=true, got shared_slopes=false")
        if self.action_slopes and self.action_factored:
            raise ValueError("action_slopes needs a table column per action unit: it needs action_factored=false, "
                             "got action_factored=true")
        if isinstance(self.n_step, bool) or not isinstance(self.n_step, (int, np.integer)) or self.n_step < 1:
            raise ValueError(f"n_step must be a whole number >= 1 (1: the one-step target), got {self.n_step!r}")
        object.__setattr__(self, "n_step", int(self.n_step))
        if self.n_step > 1 and self.gamma == 0.0:
            raise ValueError(f"n_step={self.n_step} looks ahead through later rewards: it needs gamma > 0, got gamma=0")
        for name, least in (("replay", 0), ("replay_capacity", 1), ("plan", 0), ("plan_every", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
                raise ValueError(f"{name} must be a whole number >= {least}, got {value!r}")
            object.__setattr__(self, name, int(value))
        if self.replay and self.grow_every:
            raise ValueError("replay applies to maps of a fixed size: it needs grow_every=0, "
                             f"got grow_every={self.grow_every}")
        if self.n_step > 1 and self.grow_every:
            raise ValueError("n_step > 1 applies to maps of a fixed size: it needs grow_every=0, "
                             f"got grow_every={self.grow_every}")
        if self.local_linear and self.grow_every:
            raise ValueError("local_linear applies to maps of a fixed size: it needs grow_every=0, "
                             f"got grow_every={self.grow_every}")
        if self.input_placement not in INPUT_PLACEMENTS:
            raise ValueError(f"input_placement must be one of {', '.join(INPUT_PLACEMENTS)}, got {self.input_placement!r}")
        if self.plan:
            self._check_plannable()

    def _check_plannable(self) -> None:
        """``plan`` models one map's cells with one-step targets: refuse what it cannot model (one line)."""
        clashes = [f"{name}={value}" for name, value, ok in (
            ("k_nearest", self.k_nearest, self.k_nearest == 1), ("n_step", self.n_step, self.n_step == 1),
            ("replay", self.replay, self.replay == 0), ("grow_every", self.grow_every, self.grow_every == 0),
            ("local_linear", self.local_linear, not self.local_linear),
            ("action_factored", self.action_factored, not self.action_factored),
            ("gamma", self.gamma, 0.0 < self.gamma < 1.0)) if not ok]
        if ";" in self.input_groups:
            clashes.insert(0, f"input_groups={self.input_groups}")
        if clashes:
            raise ValueError("plan models one input map's cells with one-step targets: it needs one input map, "
                             "k_nearest=1, n_step=1, replay=0, grow_every=0, local_linear=false, action_factored=false "
                             f"and 0 < gamma < 1, got {', '.join(clashes)}")

    @property
    def grouped(self) -> bool:
        """Whether this config runs the grouped, k-nearest maps (``somarm.learners.groups``), not the paper's one map."""
        return (self.input_groups != "all" or self.k_nearest != 1 or self.grow_every > 0 or self.local_linear
                or self.action_factored or self.action_gap > 0.0 or self.n_step > 1 or self.replay > 0 or self.plan > 0
                or self.input_placement == "grid")

    def slope_rows(self, action_dim: int) -> int:
        """Slope vectors per input unit with ``local_linear``: one per table column, one where shared, and one
        per action dimension beside it with ``action_slopes``."""
        if not self.shared_slopes:
            return self.table_columns
        return 1 + action_dim if self.action_slopes else 1

    @property
    def table_columns(self) -> int:
        """Columns of each input unit's row of Q: one per action unit, or with ``action_factored`` one per
        row and per column of the action grid."""
        return int(sum(self.action_shape)) if self.action_factored else int(np.prod(self.action_shape))


def grid_actions(shape: tuple[int, ...], low: np.ndarray, high: np.ndarray, span: float = 1.0) -> np.ndarray:
    """Action weights spread evenly over the box ``[low, high]``, or over the fraction ``span`` of it
    round its middle: unit i at its grid place, ``(n_units, dim)``.

    A line of n units on one action dimension runs from low to high in n - 1 equal steps; a
    rectangle of rows x cols units covers two action dimensions (rows along the first).

    Raises:
      ValueError: the map does not have one grid dimension per action dimension (one line).
    """
    if len(shape) != low.size:
        raise ValueError(f"action_init=grid needs an action map with one grid dimension per action dimension: "
                         f"action_shape={shape_text(shape)} has {len(shape)}, the action box has {low.size}")
    middle, half = (np.asarray(high) + low) / 2.0, span * (np.asarray(high) - low) / 2.0
    low, high = middle - half, middle + half
    axes = [np.linspace(lo, hi, n) if n > 1 else np.array([(lo + hi) / 2.0])
            for n, lo, hi in zip(shape, low, high, strict=True)]
    mesh = np.meshgrid(*axes, indexing="ij")  # row-major, as the map's grid coordinates
    return np.stack([m.ravel() for m in mesh], axis=1)


def paper_representation() -> dict[str, object]:
    """The ``REPRESENTATION_SETTINGS`` at the paper's values (``SOMQConfig``'s defaults): what to change a
    preset by to see the state through one map again, whatever representation the preset holds."""
    paper = SOMQConfig()
    return {name: getattr(paper, name) for name in REPRESENTATION_SETTINGS}


def row_width(config: SOMQConfig, action_dim: int) -> int:
    """Random numbers per step per trial: explore?, random unit, tie-break, the noise, then one per replayed step."""
    return 3 + action_dim * (2 if config.noise == "gaussian" else 1) + config.replay


class SOMQLearner(MapLearner):
    """SOM-Q for ``n_trials`` independent trials (conforms to ``somarm.protocols.Learner``).

    Args:
      config: a ``SOMQConfig``.
      observation_low, observation_high: the observation box, ``(obs_dim,)`` each.
      action_low, action_high: the action box, ``(action_dim,)`` each; low < high.
      n_trials: independent trials advanced together (>= 1).
      seed: the run's seed; trial i's numbers depend only on (seed, trial_ids[i]).
      trial_ids: which trials of the run these are (default ``range(n_trials)``); ``[7]``
        replays trial 7 of a batch alone.
      action_periodic: which action dimensions are angles whose low and high are one point,
        ``(action_dim,)`` bools (default none); wrapped only with ``config.periodic_actions``.

    Raises:
      ValueError: a bad config, bounds, ``n_trials``, ``seed`` or ``trial_ids`` (one line).
    """

    kind = "somq"
    config_class = SOMQConfig
    has_action_map = True
    learned_arrays = ("input_weights", "action_weights", "q")

    @classmethod
    def memory_needed(cls, config: SOMQConfig, *, n_trials: int, obs_dim: int,
                      action_dim: int) -> tuple[str, float]:
        """Both maps' grid coordinates, and per trial the weights of both maps and Q (see ``LearnerBase``)."""
        n_s, n_a = int(np.prod(config.input_shape)), int(np.prod(config.action_shape))
        n_floats = grid_floats(config.input_shape) + grid_floats(config.action_shape)
        if config.grouped:  # G maps of n_s units over the widest group's dimensions, G tables
            # obs_dim may be a lower bound (a run's check before its task is built): index lists then
            # count as many dimensions as they name.
            size = max(obs_dim, grouping.dimensions_named(config.input_groups))
            table = grouping.group_table(grouping.parse_groups(config.input_groups, size))
            n_maps, width = table.shape
            n_c = config.table_columns
            n_floats += n_trials * (n_maps * n_s * (width + n_c + 1) + n_a * action_dim + 2 * n_maps * (config.k_nearest + 1))
            if config.local_linear:  # a slope per unit, table column (one where shared) and observed dimension
                n_floats += n_trials * n_maps * n_s * config.slope_rows(action_dim) * size
            n_floats += Trail.floats(config.n_step, n_trials=n_trials, obs_dim=size, action_dim=action_dim,
                                     n_groups=n_maps, k=config.k_nearest)
            if config.replay:
                n_floats += Replay.floats(config.replay_capacity, n_trials=n_trials, obs_dim=size, action_dim=action_dim)
                n_floats += n_trials * (config.replay + 2 * n_maps * config.k_nearest + n_maps * n_s)
            if config.plan:
                n_floats += CellModel.floats(n_trials=n_trials, n_units=n_s, n_actions=n_a) + 2 * n_trials
            return (f"a somq learner with {n_maps} input map(s) of {shape_text(config.input_shape)} units, "
                    f"action_shape={shape_text(config.action_shape)} and {n_trials} trial(s)", 8.0 * n_floats)
        n_floats += n_trials * (n_s * obs_dim + n_a * action_dim + n_s * n_a)
        return (f"a somq learner with input_shape={shape_text(config.input_shape)}, action_shape="
                f"{shape_text(config.action_shape)} and {n_trials} trial(s)", 8.0 * n_floats)

    def _build_maps(self) -> None:
        cfg = self.config
        self.action_grid = grid_coordinates(cfg.action_shape)
        self._offsets_a = grid_offsets(cfg.action_shape)
        n_s, n_a = self.input_grid.shape[0], self.action_grid.shape[0]
        self.action_weights = np.empty((self.n_trials, n_a, self.action_dim))
        spread = grid_actions(cfg.action_shape, self.action_low, self.action_high, cfg.grid_span) \
            if cfg.action_init == "grid" else None
        if cfg.grouped:
            self._groups = grouping.group_table(grouping.parse_groups(cfg.input_groups, self.obs_dim))
            n_maps = self._groups.shape[0]
            self.input_weights = np.zeros((self.n_trials, n_maps * n_s, self._groups.shape[1]))
            self._group_units = np.zeros((self.n_trials, n_maps, cfg.k_nearest), dtype=np.int64)
            self._phi = np.zeros((self.n_trials, n_maps, cfg.k_nearest))
            self._action_grid_shape = np.array(cfg.action_shape, dtype=np.int64)
            full = self._offsets_s.shape  # (rows, cols); (n, 1) for a line
            start = [min(growing.START, size) for size in full] if cfg.grow_every else list(full)
            self._shapes = np.tile(np.array(start, dtype=np.int64), (self.n_trials, n_maps, 1))
            self._errors = np.zeros((self.n_trials, n_maps * n_s))
            width = self.obs_dim if cfg.local_linear else 1
            columns = cfg.slope_rows(self.action_dim) if cfg.local_linear else 1
            self.slopes = np.zeros((self.n_trials, n_maps * n_s if cfg.local_linear else 1, columns, width))
            self._mid = (self.observation_low + self.observation_high) / 2.0
            self._span = self.observation_high - self.observation_low
            self._places = np.zeros((self.n_trials, n_a, self.action_dim if cfg.action_slopes else 0))
            self._places_middle = (self.action_high + self.action_low) / 2.0
            self._places_half = cfg.grid_span * (self.action_high - self.action_low) / 2.0
            # No one input map of (n_units, obs_dim) units to draw: figures and views of a map skip it.
            self.has_maps = False
        else:
            self._group_units = np.zeros((self.n_trials, 1, 1), dtype=np.int64)
            self._phi = np.zeros((self.n_trials, 1, 1))
            self._shapes = np.zeros((self.n_trials, 1, 2), dtype=np.int64)
            self._errors = np.zeros((self.n_trials, 1))
            self.slopes = np.zeros((self.n_trials, 1, 1, 1))
        for trial, rng in enumerate(self._initial_generators()):
            # Table 1 order: input weights first, then action weights, from one child stream.
            if cfg.grouped:
                self._initial_group_weights(self.input_weights[trial], rng)
            else:
                self.input_weights[trial] = self._initial_input_weights(rng)
            if spread is not None:
                self.action_weights[trial] = spread
                continue
            span = self.action_high - self.action_low
            self.action_weights[trial] = self.action_low + span * rng.random((n_a, self.action_dim))
        # Grouped maps: each table starts at q_init / G (/ the action grid's axes when factored), so that
        # the sum starts at q_init.
        n_rows, share = (self.input_weights.shape[1], self._groups.shape[0]) if cfg.grouped else (n_s, 1)
        if cfg.action_factored:
            share *= len(cfg.action_shape)
        self.q = np.full((self.n_trials, n_rows, cfg.table_columns), cfg.q_init / share if share > 1 else cfg.q_init)
        self._open_streams(row_width(cfg, self.action_dim))
        self._interpolated = cfg.response == "interpolated"
        self._wrap = self.action_periodic & cfg.periodic_actions  # all False: the paper's clipped box
        self._n_basis = interpolation.n_basis_for(cfg.input_shape)
        # With the interpolated response ``_actions`` holds step 7's corrected targets, these the output.
        self._outputs = np.zeros((self.n_trials, self.action_dim))
        self._shifted = np.zeros(self.n_trials, dtype=np.bool_)  # stays all False for the winner response
        # The steps that wait for their n-step target (none kept with n_step 1), under the names it is saved by.
        self._trail = Trail(cfg.n_step, cfg.gamma, n_trials=self.n_trials, obs_dim=self.obs_dim,
                            action_dim=self.action_dim, n_groups=self._group_units.shape[1], k=self._group_units.shape[2])
        for name in Trail.ARRAYS:
            setattr(self, "_trail_" + name, getattr(self._trail, name))
        # The learned steps kept to learn from again (none kept without replay), under the names they are saved by;
        # the step's numbers that pick them (left by act for learn), and the nearest units of a replayed step.
        self._replay = Replay(cfg.replay_capacity if cfg.replay else 0, n_trials=self.n_trials, obs_dim=self.obs_dim,
                              action_dim=self.action_dim)
        for name in Replay.ARRAYS:
            setattr(self, "_replay_" + name, getattr(self._replay, name))
        self._replay_numbers = np.zeros((self.n_trials, cfg.replay))
        kept = cfg.replay > 0  # without replay these are empty
        self._replayed_units = np.zeros_like(self._group_units[:self.n_trials * kept])
        self._replayed_phi = np.zeros_like(self._phi[:self.n_trials * kept])
        self._replayed_errors = np.zeros_like(self._errors[:self.n_trials * kept])  # replays add to no map's errors
        # The model of the map's cells (none kept without plan), under the names it is saved by, and the
        # nearest units of each step's next observation.
        if cfg.plan and self._groups.shape[0] != 1:
            raise ValueError(f"plan models one input map's cells: it needs one input map, got input_groups="
                             f"{cfg.input_groups} ({self._groups.shape[0]} maps over {self.obs_dim} dimensions)")
        self._model = CellModel(n_trials=self.n_trials, n_units=n_s if cfg.plan else 0, n_actions=n_a)
        for name in CellModel.ARRAYS:
            setattr(self, "_model_" + name, getattr(self._model, name))
        self._next_units = np.zeros_like(self._group_units[:self.n_trials * bool(cfg.plan)])
        self._next_phi = np.zeros_like(self._phi[:self.n_trials * bool(cfg.plan)])
        # The grouped kernel's per-trial discounts and mask (the paper's kernel takes gamma and every trial).
        self._discounts = np.zeros(self.n_trials if cfg.grouped else 0)
        self._all_trials = np.ones(self.n_trials if cfg.grouped else 0, dtype=np.bool_)

    def _initial_group_weights(self, weights: np.ndarray, rng: np.random.Generator) -> None:
        """Each map's units drawn uniformly over its dimensions' bounds (or ``input_init``), map after
        map; one map over every dimension in order draws what the paper's one map draws."""
        low, high = self.observation_low, self.observation_high
        if self.config.input_init is not None:
            low = np.full_like(low, self.config.input_init[0])
            high = np.full_like(high, self.config.input_init[1])
        n_s = self.input_grid.shape[0]
        for g, row in enumerate(self._groups):
            dims = row[row >= 0]
            if self.config.input_placement == "grid":  # unit i at the middle of its cell of the grid over the box
                shape = tuple(self.config.input_shape)
                if len(shape) != dims.size:
                    raise ValueError(f"input_placement=grid needs a map with one grid axis per dimension it sees: "
                                     f"input_shape={shape_text(shape)} has {len(shape)}, the map sees {dims.size}")
                middles = (self.input_grid[:, :dims.size] + 0.5) / np.array(shape, dtype=np.float64)
                weights[g * n_s:(g + 1) * n_s, :dims.size] = low[dims] + (high[dims] - low[dims]) * middles
                continue
            weights[g * n_s:(g + 1) * n_s, :dims.size] = low[dims] + (high[dims] - low[dims]) * rng.random((n_s, dims.size))

    @property
    def periodic_dimensions(self) -> np.ndarray:
        """The action dimensions this learner wraps round (``periodic_actions`` and the task's declaration)."""
        return self._wrap.copy()

    # ``_shapes`` and ``_errors``: each map's current grid and its units' summed errors (grouped maps only).
    # ``slopes``: each unit's local linear model (``local_linear`` only; a 1x1x1 placeholder otherwise).
    # ``_trail_*``: the steps that wait for their n-step target (``n_step`` > 1 only; empty otherwise).
    # ``_replay_*``: the learned steps kept to learn from again (``replay`` > 0 only; empty otherwise).
    # ``_model_*``: the model of the map's cells (``plan`` > 0 only; empty otherwise).
    _STATE_ARRAYS = ("input_weights", "action_weights", "q", "_shapes", "_errors", "slopes") + tuple(
        "_trail_" + name for name in Trail.ARRAYS) + tuple("_replay_" + name for name in Replay.ARRAYS) + tuple(
        "_model_" + name for name in CellModel.ARRAYS)
    # ``_shifted`` says, between act and learn, which trials' step 7 shifts (an interpolated greedy step).
    # ``_group_units`` and ``_phi``: each map's k nearest units and their weights (grouped maps only).
    # ``_replay_numbers``: the step's numbers that pick its replayed steps.
    _PENDING_ARRAYS = MapLearner._PENDING_ARRAYS + ("_shifted", "_group_units", "_phi", "_replay_numbers")
    # Files saved before these existed load with ``_shifted`` all False (nothing shifts: the winner
    # response) and the paper's one map (no groups).
    _OPTIONAL_ARRAYS = ("_shifted", "_group_units", "_phi", "_shapes", "_errors", "slopes", "_replay_numbers") + tuple(
        "_trail_" + name for name in Trail.ARRAYS) + tuple("_replay_" + name for name in Replay.ARRAYS) + tuple(
        "_model_" + name for name in CellModel.ARRAYS)

    def _check_restored(self) -> None:
        trail, most = self._trail, self._trail.observations.shape[0] - 1
        if trail.count.size and not ((trail.count >= 0) & (trail.count <= most)).all():
            raise ValueError(f"_trail_count must hold 0 to {most} waiting steps a trial (n_step - 1), "
                             f"got {trail.count.tolist()}")
        rows, n_actions = self.q.shape[1], self.action_weights.shape[1]
        if not ((trail.units >= 0) & (trail.units < rows)).all() or not (
                (trail.chosen >= 0) & (trail.chosen < n_actions)).all():
            raise ValueError(f"_trail_units must name input units 0 to {rows - 1} and _trail_chosen action units "
                             f"0 to {n_actions - 1}")
        replay = self._replay
        if replay.count.size and not ((replay.count >= 0).all() and (
                (replay.chosen >= 0) & (replay.chosen < n_actions)).all()):
            raise ValueError(f"_replay_count must be >= 0 and _replay_chosen must name action units 0 to {n_actions - 1}")
        model = self._model
        if model.active and ((model.tries < 0).any() or (model.led < 0).any()):
            raise ValueError("_model_tries and _model_led count steps: they must be >= 0")

    def act(self, observations) -> np.ndarray:
        """Steps 1 to 5: an exploring action per trial (around the interpolated response if so set).

        Args:
          observations: ``(n_trials, obs_dim)``, finite.

        Returns:
          Perturbed actions ``(n_trials, action_dim)`` inside the action bounds (a fresh array;
          wrapped round, not clipped, in the periodic dimensions with ``periodic_actions``).

        Raises:
          ValueError: wrong shape, NaN or inf; or the previous act() still waits for its learn().
        """
        self._check_not_pending()
        x = self._check_observations(observations, finite=False)
        if not _kernels.all_finite(x):  # before a random row is used
            raise ValueError("observations must be finite, got NaN or inf")
        rows = self._streams.next()
        if self.config.replay:
            self._replay_numbers[...] = rows[:, rows.shape[1] - self.config.replay:]
        values = self._current()
        if self._trail.n > 1 and self._trail.count.any():  # a new episode: the waiting steps bootstrap where it broke
            due = self._trail.due_before_act(x)
            if due.any():
                self._learn_rounds(due, self._all_trials, values)
        self._observations[...] = x
        if self.config.grouped:
            groups.act_kernel(
                self._observations, self.input_weights, self.action_weights, self.q, self.slopes,
                self._action_places(), self.config.local_linear, self.config.action_factored, self._mid, self._span,
                self._groups,
                self._shapes, self.config.k_nearest, rows, values["p"], self._epsilons(values["epsilon"]), self.action_low,
                self.action_high, self._wrap, self.config.noise == "gaussian", self._interpolated,
                self._action_grid_shape, self._group_units, self._phi, self._units, self._actions,
            )
            self._pending = True
            return self._actions.copy()
        if self._interpolated:
            interpolation.act_kernel(
                self._observations, self.input_weights, self.action_weights, self.q, rows, values["p"],
                self._epsilons(values["epsilon"]), self.action_low, self.action_high, self._wrap,
                self.config.noise == "gaussian", self._offsets_a, self._n_basis, self._winners,
                self._units, self._outputs, self._actions, self._shifted,
            )
            self._pending = True
            return self._outputs.copy()
        _kernels.act_kernel(
            self._observations, self.input_weights, self.action_weights, self.q, rows,
            values["p"], self._epsilons(values["epsilon"]), self.action_low, self.action_high, self._wrap,
            self.config.noise == "gaussian", self._winners, self._units, self._actions,
        )
        self._pending = True
        return self._actions.copy()

    def learn(self, rewards, next_observations=None, terminal: bool | np.ndarray = True) -> None:
        """Steps 6 to 10 for the rewards that followed the last ``act``.

        Args:
          rewards: ``(n_trials,)``, finite.
          next_observations: ``(n_trials, obs_dim)``; needed when gamma > 0 and a trial is not terminal.
          terminal: bool, or ``(n_trials,)`` bools; terminal trials do not bootstrap.

        Raises:
          ValueError: no ``act`` before, bad shapes, NaN or inf, or a missing ``next_observations``.
        """
        r, bootstrap, x_next = self._check_learn(rewards, next_observations, terminal, finite=False)
        if not _kernels.all_finite(r):
            raise ValueError("rewards must be finite, got NaN or inf")
        if x_next is not self._observations and not _kernels.all_finite(x_next):
            raise ValueError("next_observations must be finite, got NaN or inf")
        values = self._current()
        if self._trail.n > 1:
            self._trail.push(self._observations, self._group_units, self._phi, self._units, self._actions, r, x_next)
            self._learn_rounds(self._trail.due_after_learn(bootstrap), bootstrap, values)
        elif self.config.grouped:
            np.multiply(bootstrap, self.config.gamma, out=self._discounts)
            self._grouped_learn(r, x_next, self._discounts, self._all_trials, self._observations, self._group_units,
                                self._phi, self._units, self._actions, values)
            self._replay.push(self._all_trials, r, self._discounts, self._observations, self._units, self._actions, x_next)
            if self._model.active:
                self._plan_step(r, bootstrap, x_next)
        else:
            _kernels.learn_kernel(
                r, x_next, bootstrap, self.config.gamma, self._observations, self._winners, self._units,
                self._actions, self.input_weights, self.action_weights, self.q, values["alpha"],
                values["lambda_s"], values["lambda_a"], values["n_s"], values["n_a"],
                self._offsets_s, self._offsets_a, self.config.neighbourhood_q, self._shifted,
                self.action_low, self.action_high, self._wrap,
            )
        if self.config.replay:
            self._replay_rounds(values)
        self._pending = False
        self.t += 1

    def _grouped_learn(self, returns, x_next, discounts, active, observations, units, phi, chosen, actions,
                       values, *, replayed: bool = False) -> None:
        """Steps 6 to 9 of the grouped kernels for the ``active`` trials' steps (``observations`` ... ``actions``,
        what an ``act`` left), towards ``returns + discounts max_a Q(x_next, a)``; a ``replayed`` step (its
        ``values`` with both maps' rates at 0) adds to no map's errors and grows no map."""
        cfg = self.config
        groups.learn_kernel(
            returns, x_next, discounts, active, observations, units, phi, chosen, actions, self.input_weights,
            self.action_weights, self.q, self.slopes, self._action_places(), cfg.local_linear, cfg.action_factored,
            self._action_grid_shape, self._mid, self._span, self._groups, self._shapes, cfg.k_nearest, values["alpha"],
            values["lambda_s"], values["lambda_a"], values["n_s"], values["n_a"], self._offsets_s, self._offsets_a,
            cfg.neighbourhood_q, self.action_low, self.action_high, self._wrap,
            self._replayed_errors if replayed else self._errors,
            not replayed and cfg.grow_every > 0 and (self.t + 1) % cfg.grow_every == 0, cfg.action_gap,
        )

    def _plan_step(self, rewards: np.ndarray, bootstrap: np.ndarray, x_next: np.ndarray) -> None:
        """Count the step in the model of the map's cells, and every ``plan_every`` steps solve it into Q
        (``somarm.learners.planning``)."""
        cfg = self.config
        groups.features_kernel(x_next, self.input_weights, self._groups, self._shapes, 1, self._all_trials,
                               self._next_units, self._next_phi)
        self._model.push(self._all_trials, self._group_units[:, 0, 0], self._units, rewards, bootstrap,
                         self._next_units[:, 0, 0])
        if (self.t + 1) % cfg.plan_every == 0:
            self._model.solve(self.q, gamma=cfg.gamma, q_init=cfg.q_init, sweeps=cfg.plan)

    def _learn_rounds(self, due: np.ndarray, bootstrap: np.ndarray, values) -> None:
        """Learn from the ``due`` oldest waiting steps of each trial, oldest first (``somarm.learners.trail``)."""
        last = self._trail.last
        for active, returns, discounts, observations, units, phi, chosen, actions in self._trail.rounds(due, bootstrap):
            self._grouped_learn(returns, last, discounts, active, observations, units, phi, chosen, actions, values)
            self._replay.push(active, returns, discounts, observations, chosen, actions, last)

    def _replay_rounds(self, values) -> None:
        """Learn again from ``replay`` kept steps of each trial, each picked by one of the step's numbers, the
        nearest units of each found on today's maps (``somarm.learners.replay``)."""
        cfg = self.config
        q_alone = {**values, "lambda_s": 0.0, "lambda_a": 0.0}  # a replayed step moves no map
        for j in range(cfg.replay):
            active, returns, discounts, observations, chosen, actions, x_next = self._replay.sample(
                self._replay_numbers[:, j])
            if not active.any():
                return
            groups.features_kernel(observations, self.input_weights, self._groups, self._shapes, cfg.k_nearest, active,
                                   self._replayed_units, self._replayed_phi)
            self._grouped_learn(returns, x_next, discounts, active, observations, self._replayed_units,
                                self._replayed_phi, chosen, actions, q_alone, replayed=True)

    def greedy_units(self, observations) -> tuple[np.ndarray, np.ndarray]:
        """The winning input unit and its best action unit (ties to the lowest index).

        Args:
          observations: ``(n_trials, obs_dim)`` or ``(n_trials, n_obs, obs_dim)``.

        Returns:
          ``(input_winners, action_units)``, each of the leading shape of ``observations``.
        """
        x = self._check_observations(observations, allow_many=True)
        if self.config.grouped:  # the first map's nearest unit, and the best unit of the summed Q
            units, first = self._grouped_greedy(x)
            return first, units
        input_winners = winners(self.input_weights, x)
        index = np.arange(self.n_trials).reshape((-1,) + (1,) * (input_winners.ndim - 1))
        return input_winners, np.argmax(self.q[index, input_winners], axis=-1)

    def predict(self, observations) -> np.ndarray:
        """Greedy actions, no exploration, no learning, no random number drawn.

        Args:
          observations: ``(n_trials, obs_dim)`` or ``(n_trials, n_obs, obs_dim)``.

        Returns:
          ``(n_trials, action_dim)`` or ``(n_trials, n_obs, action_dim)``.
        """
        if self.config.grouped:
            x = self._check_observations(observations, allow_many=True)
            many = np.ascontiguousarray(x.reshape(self.n_trials, -1, self.obs_dim))
            out = np.empty((self.n_trials, many.shape[1], self.action_dim))
            groups.predict_kernel(many, self.input_weights, self.action_weights, self.q, self.slopes,
                                  self._action_places(), self.config.local_linear, self.config.action_factored,
                                  self._mid, self._span, self._groups,
                                  self._shapes, self.config.k_nearest, self._interpolated, self._action_grid_shape,
                                  self.action_low, self.action_high, self._wrap, out)
            return out.reshape(x.shape[:-1] + (self.action_dim,))
        if self._interpolated:
            x = self._check_observations(observations, allow_many=True)
            many = x.reshape(self.n_trials, -1, self.obs_dim)
            out = np.empty((self.n_trials, many.shape[1], self.action_dim))
            interpolation.predict_kernel(np.ascontiguousarray(many), self.input_weights, self.action_weights,
                                         self.q, self._offsets_a, self._n_basis, self.action_low,
                                         self.action_high, self._wrap, out)
            return out.reshape(x.shape[:-1] + (self.action_dim,))
        _, units = self.greedy_units(observations)
        index = np.arange(self.n_trials).reshape((-1,) + (1,) * (units.ndim - 1))
        return self.action_weights[index, units]

    def _action_places(self) -> np.ndarray:
        """Each action unit's place for ``action_slopes``, ``(n_trials, n_action_units, action_dim)``: its
        weights less the box's middle, over the half-width of the grid (``grid_span`` of the box); with no
        action slopes ``(n_trials, n_action_units, 0)``."""
        if self._places.shape[2]:
            np.subtract(self.action_weights, self._places_middle, out=self._places)
            self._places /= self._places_half
        return self._places

    def _grouped_greedy(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Grouped maps: the greedy action unit and the first map's nearest unit of each observation."""
        many = np.ascontiguousarray(x.reshape(self.n_trials, -1, self.obs_dim))
        units = np.empty(many.shape[:2], dtype=np.int64)
        first = np.empty(many.shape[:2], dtype=np.int64)
        groups.greedy_kernel(many, self.input_weights, self.q, self.slopes, self._action_places(),
                             self.config.local_linear, self.config.action_factored, self._action_grid_shape, self.action_weights.shape[1],
                             self._mid, self._span, self._groups, self._shapes, self.config.k_nearest, units, first)
        return units.reshape(x.shape[:-1]), first.reshape(x.shape[:-1])
