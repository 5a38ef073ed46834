"""Yardsticks for SOM-Q on the suite: what simple fixed controllers earn on dmc:cartpole-balance and
dmc:point_mass-easy, over the suite's 1,000-step episodes (reset seeds 0 to ``--episodes`` - 1).

- cartpole-balance: no force at all; the discrete-time LQR law of the pole linearised round upright
  (the suite's own physics, differentiated numerically at the control timestep); the same law rounded to
  the 11 forces of the ``dmc`` preset's grid (a sixth of the action box) and to 11 over the whole box.
- point_mass-easy: the PD law ``u = clip(-50 x - 10 v)`` and the same rounded to the 3x3 grid of
  ``dmc_2d`` (-1, 0, 1 per axis).

Prints one JSON line per controller. Used by docs/benchmarks/dmc/TUNING.md to say what the
representation can hold, apart from learning.

    python scripts/dmc_yardsticks.py --episodes 5
"""

from __future__ import annotations

import argparse
import json

import numpy as np
import scipy.linalg

from somarm.tasks.dmc import SuiteEnv


def _returns(env: SuiteEnv, policy, episodes: int) -> list[float]:
    out = []
    for episode in range(episodes):
        observation, _ = env.reset(seed=episode)
        total, done = 0.0, False
        while not done:
            observation, reward, terminated, truncated, _ = env.step(np.atleast_1d(policy(observation)))
            total += reward
            done = terminated or truncated
        out.append(round(total, 1))
    return out


def _cartpole_gain(env: SuiteEnv) -> np.ndarray:
    """LQR gain on (x, theta, x', theta') at the control timestep, from the suite's physics."""
    physics = env.physics
    sub_steps = int(round(env.dt / physics.model.opt.timestep))

    def advance(state: np.ndarray, force: float) -> np.ndarray:
        with physics.reset_context():
            physics.data.qpos[:] = state[:2]
            physics.data.qvel[:] = state[2:]
        physics.set_control(np.array([force]))
        for _ in range(sub_steps):
            physics.step()
        return np.concatenate([physics.data.qpos, physics.data.qvel])

    h, zero = 1e-5, np.zeros(4)
    a = np.stack([(advance(zero + h * e, 0.0) - advance(zero - h * e, 0.0)) / (2 * h) for e in np.eye(4)], axis=1)
    b = ((advance(zero, h) - advance(zero, -h)) / (2 * h))[:, None]
    q, r = np.diag([1.0, 10.0, 1.0, 1.0]), np.array([[5.0]])
    p = scipy.linalg.solve_discrete_are(a, b, q, r)
    return np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)[0]


def _rounded(u: np.ndarray, grid: np.ndarray) -> np.ndarray:
    return grid[np.abs(grid[None, :] - np.atleast_1d(u)[:, None]).argmin(axis=1)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=5)
    args = parser.parse_args()
    rows = []
    env = SuiteEnv("cartpole", "balance")
    gain = _cartpole_gain(env)

    def lqr(o: np.ndarray) -> np.ndarray:
        x, cos, sin, xdot, thetadot = o
        return np.clip(-gain @ np.array([x, np.arctan2(sin, cos), xdot, thetadot]), -1.0, 1.0)

    sixth, whole = np.linspace(-1 / 6, 1 / 6, 11), np.linspace(-1.0, 1.0, 11)
    for what, policy in [("no force", lambda o: 0.0), ("LQR", lqr),
                         ("LQR rounded to the dmc preset's 11 forces (a sixth of the box)", lambda o: _rounded(lqr(o), sixth)),
                         ("LQR rounded to 11 forces over the box", lambda o: _rounded(lqr(o), whole))]:
        rows.append({"task": "dmc:cartpole-balance", "controller": what, "returns": _returns(env, policy, args.episodes)})
    env.close()
    env = SuiteEnv("point_mass", "easy")
    pd = lambda o: np.clip(-50.0 * o[:2] - 10.0 * o[2:], -1.0, 1.0)  # noqa: E731
    for what, policy in [("PD", pd), ("PD rounded to the dmc_2d preset's 3x3 grid", lambda o: np.round(pd(o)))]:
        rows.append({"task": "dmc:point_mass-easy", "controller": what, "returns": _returns(env, policy, args.episodes)})
    env.close()
    for row in rows:
        row["mean"] = round(float(np.mean(row["returns"])), 1)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
