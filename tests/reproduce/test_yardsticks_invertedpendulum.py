"""InvertedPendulum-v5's yardstick: which terms of the linear controller balancing needs, at the preset's torques."""

import numpy as np
import pytest

from somarm.learners import presets
from somarm.learners.somq import grid_actions
from somarm.reproduce import yardsticks

pytest.importorskip("gymnasium")
pytest.importorskip("mujoco")

_ENV = "InvertedPendulum-v5"
#: Which term of ``u = K . (cart x, pole angle, cart velocity, pole angular velocity)`` each test drops.
_POSITION, _VELOCITY = 0, 2


def _episodes(dropped: int, episodes: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """The returns and the cart's last position of the linear controller without term ``dropped``, its
    torque rounded to the invertedpendulum preset's grid, over ``episodes`` episodes (reset seeds 0, 1, ...)."""
    import gymnasium

    config = presets.get("invertedpendulum")
    env = gymnasium.make(_ENV)
    levels = np.unique(grid_actions(config.action_shape, env.action_space.low, env.action_space.high,
                                    config.grid_span))
    gains = yardsticks.INVERTED_PENDULUM_GAINS.copy()
    gains[dropped] = 0.0
    policy = yardsticks.round_to(lambda obs: np.array([gains @ obs]), levels)
    returns, last_x = np.zeros(episodes), np.zeros(episodes)
    try:
        for episode in range(episodes):
            obs, _ = env.reset(seed=episode)
            done = False
            while not done:
                obs, reward, terminated, truncated, _ = env.step(policy(obs).astype(np.float32))
                returns[episode] += reward
                done = terminated or truncated
            last_x[episode] = obs[0]
    finally:
        env.close()
    return returns, last_x


def test_the_rounded_controller_balances_without_the_cart_position_term():
    returns, _ = _episodes(_POSITION)
    assert returns.min() >= 950.0, returns


def test_without_the_cart_velocity_term_the_cart_runs_to_the_end_of_its_rail():
    returns, last_x = _episodes(_VELOCITY)
    # The pole is held (every episode lasts far longer than random actions' few steps) while the cart
    # drifts: each episode ends near an end of the rail ([-1, 1]), long before the 1,000-step limit.
    assert returns.max() < 500.0, returns
    assert np.abs(last_x).min() > 0.8, last_x
