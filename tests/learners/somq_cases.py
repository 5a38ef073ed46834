"""Shared by the learner tests (not collected): bounds, a small annealing config, the circle arc, a driver of episodes, a
save between act and learn, a chain paid at its end, the bytes a learner holds."""

import numpy as np

from somarm.learners.schedules import ExponentialDecay, InverseDecay, Schedule
from somarm.learners.somq import SOMQConfig, SOMQLearner

BOUNDS = dict(observation_low=[0.0, -1.0], observation_high=[1.0, 1.0], action_low=[-1.0, 0.0, -2.0],
              action_high=[1.0, 1.0, 2.0])
#: Four observed dimensions and two action dimensions, for the grouped maps' tests.
BOX4 = dict(observation_low=[0.0, -1.0, 0.0, -2.0], observation_high=[1.0, 1.0, 2.0, 2.0],
            action_low=[-1.0, 0.0], action_high=[1.0, 1.0])


def small_config(input_shape, neighbourhood_q, gamma, noise="uniform", **changes) -> SOMQConfig:
    """A 7-unit action map whose schedules anneal within a test, so late, narrow-neighbourhood steps are covered."""
    fast = InverseDecay(50.0)
    return SOMQConfig(
        input_shape=input_shape, action_shape=(7,), alpha=Schedule(0.9, fast), lambda_s=Schedule(0.8, fast),
        lambda_a=Schedule(0.7, fast, floor=0.05), n_s=Schedule(3.0, fast), n_a=Schedule(2.5, fast),
        p=Schedule(0.6, fast), epsilon=Schedule(0.4, ExponentialDecay(0.99), floor=0.01), gamma=gamma,
        neighbourhood_q=neighbourhood_q, noise=noise, **changes,
    )


def arc(difference, period):
    """An independent (NumPy) statement of the shorter way round a circle, to check the kernels with."""
    return difference - period * np.floor(difference / period + 0.5)


def batch_and_alone(config: SOMQConfig, drive, steps: int):
    """A batch of three trials and its third trial alone (seed 9, ``BOX4``), each driven ``steps`` steps by
    ``drive(learner, steps)``: a trial alone must equal the same trial in a batch."""
    batch = SOMQLearner(config, n_trials=3, seed=9, **BOX4)
    alone = SOMQLearner(config, n_trials=1, seed=9, trial_ids=[2], **BOX4)
    drive(batch, steps)
    drive(alone, steps)
    return batch, alone


def drive_episodes(learner, steps, seed=6):
    """Each trial walks its own chain from its own stream (by trial id), ending episodes at terminal states and
    at time limits at different steps in different trials."""
    streams = [np.random.default_rng([seed, int(i)]) for i in learner.trial_ids]
    low, high = learner.observation_low, learner.observation_high
    x = np.array([low + (high - low) * rng.random(low.size) for rng in streams])
    for _ in range(steps):
        actions = learner.act(x)
        nxt = np.array([low + (high - low) * rng.random(low.size) for rng in streams])
        ends = np.array([rng.random() for rng in streams])
        terminal = ends < 0.08
        learner.learn(-np.abs(actions).sum(axis=1) + x[:, 0], nxt, terminal)
        restart = np.array([low + (high - low) * rng.random(low.size) for rng in streams])
        x = np.where((ends < 0.16)[:, None], restart, nxt)  # terminal, or a time limit: a new episode


def held_bytes(learner) -> int:
    """Bytes of the arrays a learner holds, each counted once (the Motoric Map's action grid is its input grid)."""
    arrays = {id(value): value for value in vars(learner).values() if isinstance(value, np.ndarray)}
    return sum(value.nbytes for value in arrays.values())


def chain_start_values(changes: dict, steps: int, n_trials: int = 8) -> np.ndarray:
    """A chain of 10 cells over [0, 1] walked from middle to middle (left, stay, right), paid 1 only on reaching the
    last cell (terminal), 100 steps an episode from the first cell; 10 input units fixed on the cells, so Q is a
    table; ``changes`` to the learner's settings (``replay``, ``plan``). Returns each trial's learned value of the
    first cell over its true value gamma^8."""
    config = SOMQConfig(input_shape=(10,), action_shape=(3,), action_init="grid", alpha=Schedule(0.5),
                        lambda_s=Schedule(0.0), lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0),
                        p=Schedule(0.3), epsilon=Schedule(0.0), gamma=0.9, input_groups="0", **changes)
    learner = SOMQLearner(config, n_trials=n_trials, seed=1, observation_low=[0.0], observation_high=[1.0],
                          action_low=[-1.0], action_high=[1.0])
    learner.input_weights[:, :, 0] = np.linspace(0.05, 0.95, 10)
    x = np.full((n_trials, 1), 0.05)
    for t in range(1, steps + 1):
        nxt = np.clip(x + 0.1 * np.round(learner.act(x)), 0.05, 0.95)  # from cell middle to cell middle
        goal = nxt[:, 0] >= 0.95 - 1e-9  # the last cell (nine tenths added to 0.05 may land a rounding below 0.95)
        learner.learn(goal.astype(float), nxt, goal)
        x = np.where((goal | (t % 100 == 0))[:, None], 0.05, nxt)
    return learner.q[:, 0].max(axis=1) / 0.9 ** 8


def saved_between_act_and_learn_goes_on_alike(config: SOMQConfig, drive, folder, names, *, before: int = 30,
                                               after: int = 10, acting_on=None) -> None:
    """Two trials (seed 4, ``BOX4``) driven ``before`` steps by ``drive(learner, steps)``, saved to ``folder``
    between an ``act`` (on ``acting_on(learner)``, default 0.5 everywhere) and its ``learn``, and loaded; the
    learner and its copy then learn the same step and ``after`` more: the arrays ``names`` must be equal."""
    a = SOMQLearner(config, n_trials=2, seed=4, **BOX4)
    drive(a, before)
    a.act(np.full((2, 4), 0.5) if acting_on is None else acting_on(a))
    a.save(folder / "l.npz")
    b = SOMQLearner.load(folder / "l.npz")
    for learner in (a, b):
        learner.learn([1.0, 0.0], np.full((2, 4), 0.2), np.array([False, True]))
        drive(learner, after)
    for name in names:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
