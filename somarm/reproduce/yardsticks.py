"""Hand-made controllers replayed on the benchmark environments: the yardsticks of the benchmarks part (and the
dmc part's hold on pendulum-swingup, ``pendulum_hold``).

SOM-Q's greedy policy is a table: the winning input unit picks one of a fixed grid of torques. A
controller known to work tells what that form costs, apart from learning. Replay it, then make it
coarse the way SOM-Q is coarse: round its torque to the preset's grid (the action side), or compute it
from the centre of a grid cell instead of the observation (the state side, as a nearest-unit lookup
does), or from the input units SOM-Q itself learned: the nearest one, as the paper's winner response
sees the state, or a blend over the nearest few, as the interpolated response does; or from maps of
400 to 10,000 units learned on the controller's own states, the best case for a map of that size; or,
for Reacher-v5, as SOM-Q itself learns to hold the controller through each input representation
(``REPRESENTATIONS``: one map, maps over pairs of dimensions whose Q-values add, k nearest units, growing maps,
local linear units, Q adding over the torque grid's axes).
Every number is a mean undiscounted return over fresh episodes of the environment itself.

The controllers are this project's:

- InvertedPendulum-v5: a linear state feedback, ``u = K . obs``, with gains found by a random search
  over linear policies (they balance all 1,000 steps).
- dm_control's pendulum-swingup (``pendulum_hold``): a PD law on the pole's angle from upright, ``u =
  clip(-10 theta - 2 omega)``, within 45 degrees of upright and no torque elsewhere. It never swings the
  pole up: it holds it only in the episodes that start near upright (the suite starts the pole at a random
  angle), so it tells what a return earned that way is worth.
- Reacher-v5: a Jacobian-transpose PD law on the fingertip-to-target vector of the observation,
  ``u = kp J(q)^T (target - tip) - kd qdot``, with the arm's link lengths from the model (0.1, 0.11);
  and a joint-space PD law, ``u = kp (q* - q) - kd qdot``, q* the target's inverse kinematics (the
  elbow solution nearer the arm's pose). The second is the stronger: what the preset's torques allow
  when the controller is good; the first is the one the representations are shown learning.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from somarm.learners.somq import paper_representation

__all__ = ["INVERTED_PENDULUM_GAINS", "REACHER_GAINS", "REACHER_JOINT_GAINS", "REACHER_CONTROLLERS", "ENVIRONMENTS", "REPRESENTATIONS", "mean_return", "round_to",
           "cell_centre", "pendulum_hold", "learned_map", "controller_map", "controller_states", "through_map", "through_representation", "inverted_pendulum", "reacher", "measure", "table"]

Policy = Callable[[np.ndarray], np.ndarray]

#: ``K`` of ``u = K . (cart x, pole angle, cart velocity, pole angular velocity)``.
INVERTED_PENDULUM_GAINS = np.array([-0.05, 2.82, 1.67, 2.73])
#: ``(kp, kd)`` of Reacher-v5's PD law.
REACHER_GAINS = (20.0, 0.1)
#: ``(kp, kd)`` of Reacher-v5's joint-space PD law (over the joint angles' errors, radians).
REACHER_JOINT_GAINS = (0.5, 0.1)
_REACHER_LINKS = (0.1, 0.11)
#: The input maps learned on a controller's own states: the presets' 400 units, 2,500 and 10,000;
#: the states it visits with this much torque noise (sd; a sixth of InvertedPendulum-v5's box, a tenth
#: of Reacher-v5's, the step of its preset's grid), and how many.
CONTROLLER_MAP_SHAPES = ((20, 20), (50, 50), (100, 100))
CONTROLLER_MAP_NOISE = {"InvertedPendulum-v5": 0.5, "Reacher-v5": 0.1}
CONTROLLER_MAP_STEPS = 100_000


def mean_return(env_id: str, policy: Policy, episodes: int, seed: int) -> float:
    """The mean undiscounted return of ``policy`` over ``episodes`` episodes reset with seeds
    ``seed, seed + 1, ...``; actions are clipped to the action box."""
    import gymnasium

    env = gymnasium.make(env_id)
    low, high = env.action_space.low, env.action_space.high
    total = 0.0
    try:
        for episode in range(episodes):
            obs, _ = env.reset(seed=seed + episode)
            done = False
            while not done:
                obs, reward, terminated, truncated, _ = env.step(np.clip(policy(obs), low, high))
                total += float(reward)
                done = terminated or truncated
    finally:
        env.close()
    return total / episodes


def round_to(policy: Policy, levels: np.ndarray) -> Policy:
    """``policy`` with each action element rounded to the nearest of ``levels`` (a torque grid)."""
    levels = np.asarray(levels, dtype=np.float64)
    return lambda obs: levels[np.argmin(np.abs(levels[None, :] - np.asarray(policy(obs))[:, None]), axis=1)]


def cell_centre(policy: Policy, low: np.ndarray, high: np.ndarray, cells: int) -> Policy:
    """``policy`` answering for the centre of the observation's cell in a grid of ``cells`` per
    dimension over ``[low, high]`` (a nearest-unit lookup on a uniform map)."""
    span = np.asarray(high, dtype=np.float64) - low

    def centred(obs: np.ndarray) -> np.ndarray:
        u = np.clip((obs - low) / span, 0.0, 1.0)
        return policy(low + span * np.round(u * (cells - 1)) / (cells - 1))
    return centred


def pendulum_hold(obs: np.ndarray) -> np.ndarray:
    """The pendulum-swingup hold: observations ``(n, 3)`` of the suite's pendulum (cosine and sine of the
    pole's angle from upright, its angular velocity) to torques ``(n, 1)``: ``clip(-10 theta - 2 omega)``
    within 45 degrees of upright, 0 elsewhere."""
    obs = np.asarray(obs, dtype=np.float64)
    angle = np.arctan2(obs[:, 1], obs[:, 0])
    near = obs[:, 0] > np.cos(np.pi / 4)
    return np.where(near, np.clip(-10.0 * angle - 2.0 * obs[:, 2], -1.0, 1.0), 0.0)[:, None]


def learned_map(env_id: str, steps: int, seed: int):
    """The input map SOM-Q learns on ``env_id`` with the environment's benchmark preset: one trial of
    ``steps`` steps at ``seed``; returns the task (its observation scaling) and the units ``(n, obs_dim)``."""
    from somarm.agent import SOMQ

    model = SOMQ(env_id, seed=seed, n_trials=1)
    model.learn(steps)
    return model.task, model.learner.input_weights[0].copy()


def controller_map(env_id: str, policy: Policy, task, shape: tuple[int, ...], steps: int, noise: float,
                   seed: int) -> np.ndarray:
    """An input map trained on the states ``policy`` visits, not on SOM-Q's: the best case for the map.

    ``policy`` runs with Gaussian noise of sd ``noise`` on its torque (so the states spread round the
    ones it keeps) for ``steps`` steps, episodes reset from a generator seeded with ``seed``; a map of
    ``shape`` starting uniform at random learns each scaled state (``task.scale``) once, in order, by the
    benchmark presets' input-map recipe: lambda_S = 1/(t/2000 + 1), N_S = 1/(t/20000 + 1). Returns its
    units ``(n, obs_dim)``.
    """
    import gymnasium

    from somarm.learners import som

    rng = np.random.default_rng(seed)
    env = gymnasium.make(env_id)
    low, high = env.action_space.low, env.action_space.high
    states = []
    try:
        obs, _ = env.reset(seed=int(rng.integers(2**31)))
        while len(states) < steps:
            action = np.asarray(policy(obs), dtype=np.float64)
            action = np.clip(action + noise * rng.standard_normal(action.shape), low, high)
            obs, _, terminated, truncated, _ = env.step(action)
            states.append(task.scale(obs))
            if terminated or truncated:
                obs, _ = env.reset(seed=int(rng.integers(2**31)))
    finally:
        env.close()
    coordinates = som.grid_coordinates(shape)  # grid distances from each winner alone: no n x n matrix
    units = rng.random((coordinates.shape[0], len(states[0])))
    for t, state in enumerate(states):
        x = np.asarray(state, dtype=np.float64)
        som.update(units[None], x[None], som.winners(units[None], x[None]), 1.0 / (t / 2000.0 + 1.0),
                   1.0 / (t / 20000.0 + 1.0), coordinates)
    return units


def through_map(policy: Policy, task, units: np.ndarray, n_basis: int = 1, dims=None) -> Policy:
    """``policy`` answering for the input units nearest the observation instead of the observation.

    With ``n_basis = 1`` the nearest unit's place alone (the winner response's view of the state);
    with more, a blend of the policy at the ``n_basis`` nearest units with the interpolated
    response's tapered inverse-distance weights ``1/d_i - 1/d_(n_basis+1)``
    (``somarm.learners.interpolation``), so the blend moves continuously between units. ``dims``: the
    observed dimensions a map over some of them sees (``units (n, len(dims))``); the others pass as
    observed (default: every dimension).
    """
    def place(x: np.ndarray, unit: int) -> np.ndarray:
        if dims is None:
            return task.unscale(units[unit])
        x = x.copy()
        x[dims] = units[unit]
        return task.unscale(x)

    def seen(obs: np.ndarray) -> np.ndarray:
        x = task.scale(obs)
        distances = np.sqrt(((units - (x if dims is None else x[dims])) ** 2).sum(axis=1))
        order = np.argsort(distances, kind="stable")[: n_basis + 1]
        if n_basis == 1 or distances[order[0]] == 0.0:
            return policy(place(x, order[0]))
        weights = 1.0 / distances[order[:n_basis]] - 1.0 / distances[order[n_basis]]
        answers = np.array([policy(place(x, i)) for i in order[:n_basis]])
        return weights @ answers / weights.sum()
    return seen


def controller_states(env_id: str, policy: Policy, task, steps: int, noise: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The scaled states ``policy`` visits with Gaussian torque noise of sd ``noise`` (``steps`` of them,
    episodes reset from a generator seeded with ``seed``) and the policy's own torque at each, clipped
    to the action box: ``(steps, obs_dim)``, ``(steps, action_dim)``."""
    import gymnasium

    rng = np.random.default_rng(seed)
    env = gymnasium.make(env_id)
    low, high = env.action_space.low, env.action_space.high
    states, torques = [], []
    try:
        obs, _ = env.reset(seed=int(rng.integers(2**31)))
        while len(states) < steps:
            action = np.clip(np.asarray(policy(obs), dtype=np.float64), low, high)
            states.append(task.scale(obs))
            torques.append(action)
            obs, _, terminated, truncated, _ = env.step(np.clip(action + noise * rng.standard_normal(action.shape),
                                                               low, high))
            if terminated or truncated:
                obs, _, = env.reset(seed=int(rng.integers(2**31)))
    finally:
        env.close()
    return np.array(states), np.array(torques)


def through_representation(env_id: str, states: np.ndarray, torques: np.ndarray, task, changes: dict,
                           seed: int, preset: str | None = None) -> Policy:
    """A controller as a SOM-Q learner with the benchmark preset changed by ``changes`` (an input
    representation: ``input_groups``, ``k_nearest``, ``grow_every``, ``input_shape``, ``response``) can hold
    it, learned on the controller's own ``states`` and ``torques`` (``controller_states``): each step one
    action unit is tried at random and rewarded ``-|a - torque|^2`` (gamma 0), so the greedy unit is the
    grid torque nearest the controller's as that representation sees the state (no neighbourhood over the
    torques, which would blur their values together; one-step targets, as gamma 0 looks no further; Q starts at -1, below
    what a tried torque earns, so a pair never tried is never the greedy one). Returns the learner's
    greedy policy over raw observations (``task.scale``). ``preset``: the preset changed (default: the
    benchmark's for ``env_id``; a suite task's registered id, ``somarm.tasks.dmc.gym_id``, names its own)."""
    from somarm.learners import make, presets
    from somarm.learners.schedules import Constant
    from somarm.tasks import gym_envs

    config = presets.get(preset or gym_envs.BENCHMARKS[env_id][0]).with_changes(
        {"gamma": 0.0, "n_step": 1, "p": 1.0, "p.decay": Constant(), "p.floor": 0.0, "epsilon": 0.0, "q_init": -1.0,
         "n_a": 0.0, **changes})
    facts = gym_envs.describe(env_id)
    learner = make("somq", config, observation_low=np.zeros(states.shape[1]), observation_high=np.ones(states.shape[1]),
                   action_low=facts["action_low"], action_high=facts["action_high"], seed=seed)
    for state, torque in zip(states, torques, strict=True):
        action = learner.act(state[None])
        learner.learn(-((action - torque) ** 2).sum(axis=1))
    return lambda obs: learner.predict(task.scale(obs)[None])[0]


#: What every row of ``REPRESENTATIONS`` starts from (the paper's one map, whatever the preset holds), so a
#: row is the representation its label names.
_PLAIN = paper_representation()

#: The input representations the Reacher-v5 yardsticks learn the PD law through (``somarm.learners.groups``).
REPRESENTATIONS = (
    ("one 20x20 map (the paper's)", {"input_groups": "all", "input_shape": (20, 20), "k_nearest": 1}),
    ("one 20x20 map, its 3 nearest units", {"input_groups": "all", "input_shape": (20, 20), "k_nearest": 3}),
    ("45 maps of 10x10, one per pair of dimensions", {"input_groups": "pairs", "input_shape": (10, 10),
                                                      "k_nearest": 1}),
    ("45 pair maps of 10x10, their 3 nearest units",
     {"input_groups": "pairs", "input_shape": (10, 10), "k_nearest": 3}),
    ("45 pair maps of 10x10, their 3 nearest units, local linear units with one slope vector per unit "
     "(local_linear, shared_slopes: the reacher preset's)",
     {"input_groups": "pairs", "input_shape": (10, 10), "k_nearest": 3, "local_linear": True, "shared_slopes": True}),
    ("45 pair maps of 10x10, their 3 nearest units, local linear units with one slope vector per unit and one per "
     "torque axis (local_linear, shared_slopes, action_slopes)",
     {"input_groups": "pairs", "input_shape": (10, 10), "k_nearest": 3, "local_linear": True, "shared_slopes": True,
      "action_slopes": True}),
    ("45 pair maps growing to 10x10 (a row or column every 1,000 steps), their 3 nearest units",
     {"input_groups": "pairs", "input_shape": (10, 10), "k_nearest": 3, "grow_every": 1000}),
    ("45 pair maps of 10x10, their 3 nearest units, Q adding over the torque grid's axes (action_factored)",
     {"input_groups": "pairs", "input_shape": (10, 10), "k_nearest": 3, "action_factored": True}),
    ("45 pair maps of 5x5, their 3 nearest units, local linear units (local_linear), action_factored",
     {"input_groups": "pairs", "input_shape": (5, 5), "k_nearest": 3, "local_linear": True, "action_factored": True}),
)


def _representation_rows(env_id: str, policy: Policy, scaling, map_steps: int | None,
                         seed: int) -> list[tuple[str, Policy]]:
    """``policy`` learned through each of ``REPRESENTATIONS`` on its own states (``map_steps`` of them,
    None: ``CONTROLLER_MAP_STEPS``, 0: no rows), greedy with the winning action unit."""
    if map_steps == 0:
        return []
    steps, noise = CONTROLLER_MAP_STEPS if map_steps is None else map_steps, CONTROLLER_MAP_NOISE[env_id]
    states, torques = controller_states(env_id, policy, scaling, steps, noise, seed)
    where = f"learned on the controller's own states ({steps:,} steps, torque noise sd {noise:g})"
    return [(f"PD law as SOM-Q holds it through {label}, {where}",
             through_representation(env_id, states, torques, scaling, {**_PLAIN, **changes, "response": "winner"},
                                    seed))
            for label, changes in REPRESENTATIONS]


def _map_rows(env_id: str, policy: Policy, map_steps: int | None, seed: int,
              roundings: tuple[tuple[str, np.ndarray], ...] = ()) -> list[tuple[str, Policy]]:
    """The policy seen through the preset's learned input map (after ``map_steps`` steps, None: the
    benchmark's own, 0: no rows): by its nearest unit, blended, and blended with each unit's action
    rounded to each of ``roundings`` (label, levels) first: the interpolated response's form when
    every unit holds one torque of a grid."""
    from somarm.learners import presets
    from somarm.learners.grouping import parse_groups
    from somarm.learners.interpolation import n_basis_for
    from somarm.tasks import gym_envs

    preset, steps = gym_envs.BENCHMARKS[env_id]
    map_steps = steps if map_steps is None else map_steps
    config = presets.get(preset)
    dims = None
    if config.grouped:  # one map over some of the dimensions is seen through; several maps are not
        groups = parse_groups(config.input_groups, gym_envs.describe(env_id)["observation_low"].size)
        if len(groups) > 1 or config.k_nearest != 1 or config.grow_every:
            return []
        dims = np.array(groups[0])
    if map_steps <= 0:
        return []
    task, units = learned_map(env_id, map_steps, seed)
    shape = "x".join(str(n) for n in config.input_shape)
    n_basis = n_basis_for(config.input_shape)
    where = f"the preset's {shape} input map after {map_steps:,} steps"
    if dims is not None:
        where += f" (over dimensions {', '.join(map(str, dims))}; the others as observed)"
    blended = f"state seen through {where}: blended over its {n_basis} nearest units"
    return [(f"state seen through {where}: its nearest unit", through_map(policy, task, units, dims=dims)),
            (blended, through_map(policy, task, units, n_basis, dims))] + [
            (f"{blended}, each unit's torque rounded to {label}",
             through_map(round_to(policy, levels), task, units, n_basis, dims))
            for label, levels in roundings]


def _controller_map_rows(env_id: str, policy: Policy, scaling, map_steps: int | None,
                         seed: int) -> list[tuple[str, Policy]]:
    """The best case for an input map: ``policy`` seen through maps of each of ``CONTROLLER_MAP_SHAPES``
    learned on its own states (``controller_map``, ``map_steps`` steps, None: ``CONTROLLER_MAP_STEPS``,
    0: no rows) over the benchmark task's ``scaling``, by the nearest unit and blended."""
    from somarm.learners.interpolation import n_basis_for

    if map_steps == 0:
        return []
    steps, noise = CONTROLLER_MAP_STEPS if map_steps is None else map_steps, CONTROLLER_MAP_NOISE[env_id]
    rows = []
    for shape in CONTROLLER_MAP_SHAPES:
        units, n_basis = controller_map(env_id, policy, scaling, shape, steps, noise, seed), n_basis_for(shape)
        where = (f"state seen through a {shape[0]}x{shape[1]} map learned on the controller's own states "
                 f"({steps:,} steps, torque noise sd {noise:g})")
        rows += [(f"{where}: its nearest unit", through_map(policy, scaling, units)),
                 (f"{where}: blended over its {n_basis} nearest units", through_map(policy, scaling, units, n_basis))]
    return rows


def _levels(shape: tuple[int, ...], env_id: str, fraction: float = 1.0) -> np.ndarray:
    """The torques of each axis of a benchmark preset's frozen grid (``somq.grid_actions``) over the
    environment's action box, or over ``fraction`` of it round its middle; every axis here has the
    same range, so one list serves all."""
    from somarm.learners.somq import grid_actions
    from somarm.tasks import gym_envs

    facts = gym_envs.describe(env_id)
    return np.unique(grid_actions(shape, facts["action_low"], facts["action_high"], fraction))


def _torques(levels: np.ndarray) -> str:
    return ", ".join(f"{v:g}" for v in levels)


def inverted_pendulum(episodes: int, seed: int, map_steps: int | None = 0) -> list[tuple[str, float]]:
    """The linear controller, its torque rounded to grids, its state to uniform cells over the
    benchmark task's scaling (the rail, the ending angle, velocities from random actions), and (with
    ``map_steps``) its state seen through the input map SOM-Q learns in that many steps (None: the
    benchmark's own)."""
    from somarm.learners import presets
    from somarm.tasks import gym_envs

    env_id = "InvertedPendulum-v5"

    def linear(obs: np.ndarray) -> np.ndarray:
        return np.array([INVERTED_PENDULUM_GAINS @ obs])

    how = presets.task_params_of("invertedpendulum", "gym:" + env_id)
    low, high = (np.array(b) for b in gym_envs.estimate_bounds(gym_envs.GymParams(env_id), seed, how=how))
    config = presets.get("invertedpendulum")
    preset = _levels(config.action_shape, env_id, config.grid_span)
    whole, narrow = _levels((3,), env_id), _levels((3,), env_id, 1.0 / 6.0)
    even = _levels((5,), env_id)
    packed = np.max(even) * np.linspace(-1.0, 1.0, 9) ** 3
    rows = [("linear controller", linear),
            (f"torque rounded to the preset's {preset.size} torques ({_torques(preset)})", round_to(linear, preset)),
            (f"torque rounded to 3 torques over the whole box ({_torques(whole)})", round_to(linear, whole)),
            (f"torque rounded to 3 torques over a sixth of the box ({_torques(narrow)})", round_to(linear, narrow)),
            (f"torque rounded to {even.size} even torques", round_to(linear, even)),
            ("torque rounded to 9 torques packed near 0 (3 s^3, s even in [-1, 1])", round_to(linear, packed))]
    rows += [(f"state at the centre of its cell, {k}^4 = {k ** 4:,} cells", cell_centre(linear, low, high, k))
             for k in (5, 9, 17)]
    fine = np.linspace(-1.0, 1.0, 21)
    rows += _map_rows(env_id, linear, map_steps, seed,
                      ((f"the preset's {preset.size}", preset), ("3 over the whole box", whole),
                       (f"{fine.size} even in [-1, 1]", fine)))
    rows += _controller_map_rows(env_id, linear, gym_envs.BoxScaling(low, high), map_steps, seed)
    return [(label, mean_return(env_id, policy, episodes, seed)) for label, policy in rows]


def _reacher_pd(obs: np.ndarray) -> np.ndarray:
    c1, c2, s1, s2 = obs[:4]
    c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
    l1, l2 = _REACHER_LINKS
    jacobian = np.array([[-l1 * s1 - l2 * s12, -l2 * s12], [l1 * c1 + l2 * c12, l2 * c12]])
    kp, kd = REACHER_GAINS
    return kp * jacobian.T @ -obs[8:10] - kd * obs[6:8]


def _reacher_joint_angles(obs: np.ndarray) -> np.ndarray:
    """How far each joint is from the pose that puts the fingertip on the target (the target's inverse
    kinematics, of its two elbow solutions the one nearer the arm's pose), wrapped into (-pi, pi]."""
    l1, l2 = _REACHER_LINKS
    q = np.arctan2(obs[2:4], obs[0:2])
    target_x, target_y = obs[4], obs[5]
    bend = np.arccos(np.clip((target_x ** 2 + target_y ** 2 - l1 ** 2 - l2 ** 2) / (2.0 * l1 * l2), -1.0, 1.0))
    best = None
    for elbow in (bend, -bend):
        shoulder = np.arctan2(target_y, target_x) - np.arctan2(l2 * np.sin(elbow), l1 + l2 * np.cos(elbow))
        error = np.angle(np.exp(1j * (np.array([shoulder, elbow]) - q)))
        if best is None or np.abs(error).sum() < np.abs(best).sum():
            best = error
    return best


def _reacher_joint_pd(obs: np.ndarray) -> np.ndarray:
    """The joint-space PD law ``u = kp (q* - q) - kd qdot``, q* the target's inverse kinematics."""
    kp, kd = REACHER_JOINT_GAINS
    return kp * _reacher_joint_angles(obs) - kd * obs[6:8]


#: The Reacher-v5 controllers the yardsticks replay: the Jacobian-transpose PD law and the joint-space one.
REACHER_CONTROLLERS: dict[str, Policy] = {"jacobian": _reacher_pd, "joint": _reacher_joint_pd}


def reacher(episodes: int, seed: int, map_steps: int | None = 0) -> list[tuple[str, float]]:
    """No torque, the PD law, the PD law rounded to torque grids, the joint-space PD law as it is and rounded
    to the preset's grid, and (with ``map_steps``) the PD law's state
    seen through the input map SOM-Q learns in that many steps and through maps learned on its own states."""
    from somarm.learners import presets
    from somarm.tasks import gym_envs

    config = presets.get("reacher")
    preset, whole = _levels(config.action_shape, "Reacher-v5", config.grid_span), _levels(config.action_shape, "Reacher-v5")
    grid = "x".join(str(n) for n in config.action_shape)
    rows = [("no torque", lambda obs: np.zeros(2)), ("PD law", _reacher_pd),
            (f"PD law rounded to the preset's {grid} grid ({_torques(preset)} per joint)", round_to(_reacher_pd, preset))]
    if not np.array_equal(preset, whole):
        rows.append((f"PD law rounded to a {grid} grid over the whole box ({_torques(whole)} per joint)",
                     round_to(_reacher_pd, whole)))
    rows += [("joint-space PD law (over the joint angles to the target's inverse kinematics)", _reacher_joint_pd),
             (f"joint-space PD law rounded to the preset's {grid} grid", round_to(_reacher_joint_pd, preset))]
    rows += _map_rows("Reacher-v5", _reacher_pd, map_steps, seed)
    if map_steps != 0:  # the task's own scaling, estimated from random actions (an infinite Box)
        bounds = gym_envs.estimate_bounds(gym_envs.GymParams("Reacher-v5"), seed)
        rows += _controller_map_rows("Reacher-v5", _reacher_pd, gym_envs.BoxScaling(*bounds), map_steps, seed)
        rows += _representation_rows("Reacher-v5", _reacher_pd, gym_envs.BoxScaling(*bounds), map_steps, seed)
    return [(label, mean_return("Reacher-v5", policy, episodes, seed)) for label, policy in rows]


#: The environments with yardsticks, and how to measure them.
ENVIRONMENTS: dict[str, Callable[[int, int, int | None], list[tuple[str, float]]]] = {
    "InvertedPendulum-v5": inverted_pendulum,
    "Reacher-v5": reacher,
}


def measure(envs: tuple[str, ...], episodes: int, seed: int,
            map_steps: int | None = 0) -> dict[str, list[tuple[str, float]]]:
    """The yardsticks of those of ``envs`` that have them, with the input maps SOM-Q learns in
    ``map_steps`` steps (None: each benchmark's own steps; 0: none)."""
    return {env_id: ENVIRONMENTS[env_id](episodes, seed, map_steps) for env_id in envs if env_id in ENVIRONMENTS}


def table(results: dict[str, list[tuple[str, float]]], episodes: int) -> list[str]:
    """The yardsticks as a Markdown table (no lines when there are none)."""
    if not results:
        return []
    lines = [f"Yardsticks: hand-made controllers replayed, and made coarse the way SOM-Q's table is "
             f"(mean return over {episodes} fresh episodes; `somarm.reproduce.yardsticks`):", "",
             "| environment | controller | return |", "|---|---|---|"]
    for env_id, rows in results.items():
        lines += [f"| {env_id} | {label} | {value:.1f} |" for label, value in rows]
    return lines
