"""Yardsticks for SOM-Q on the suite: what simple fixed controllers earn on the dmc report's tasks over the
suite's 1,000-step episodes (reset seeds 0 to ``--episodes`` - 1), with ``--through`` how much of each
controller SOM-Q's maps can hold, and with ``--hold`` what the pendulum hold earns on tuning seeds' own
evaluation episodes.

- cartpole-balance: no force at all; the discrete-time LQR law of the pole linearised round upright
  (the suite's own physics, differentiated numerically at the control timestep); the same law rounded to
  the 11 forces of the ``dmc`` preset's grid (a sixth of the action box) and to 11 over the whole box.
- pendulum-swingup: energy pumping (``u = clip(5 w (E* - E))``, E the pole's energy from the suite's
  mass, length and gravity, E* upright at rest) and a PD catch (``u = clip(-10 theta - 2 w)``) once the
  pole is within 18 degrees of upright; rounded to the ``dmc`` preset's 11 torques and to 11 over the box;
  the latter read at the centre of each state's cell of a uniform 30x30 or 10x10 grid over angle and
  velocity (``on_grid``: cells evenly spread); the catch alone, no torque farther than 45 degrees from
  upright (``pendulum_hold``: what a policy earns that holds the pole only where an episode starts near it).
- cartpole-swingup: energy pumping with no catch (``pump``: the largest force, pushed against the pole's
  swing, ``u = -F sign(theta' cos theta)``), at the ``dmc`` preset's largest force (a sixth of the box) and
  at the box's: whether the preset's forces can bring the pole up at all.
- point_mass-easy: the PD law ``u = clip(-50 x - 10 v)`` and the same rounded to the 3x3 grid of
  ``dmc_2d`` (-1, 0, 1 per axis).
- reacher-easy and reacher-hard: a joint-space PD law on the arm's inverse kinematics (``reach``: the target
  is the finger plus ``to_target``, the joint angles that put the finger there are solved for the elbow
  solution nearer the arm's own angles, ``u = clip(10 (q* - q) - q')``, the link lengths read from the model), as it is and
  rounded to the 3x3 grid of ``dmc_2d`` (-1, 0, 1 per joint).

``--through``: each controller (rounded to a grid SOM-Q can answer with) as SOM-Q holds it when it
learns it by imitation (``somarm.reproduce.yardsticks.through_representation``: gamma 0, one random
action unit a step, rewarded by minus its squared distance from the controller's action) on
``--states`` states the controller visits with action noise, from tuning seed ``--seed``; each
representation is the task's preset changed as its row says, over the task's observation bounds
(``BOUNDS``). The returns are the learned greedy policies'. This tells apart what the maps can hold
from what Q-learning finds in them. For the tasks of ``AT_UNITS`` also the controller itself read at the
nearest unit of a map of each shape learned on its own states (``somarm.reproduce.yardsticks.controller_map``,
the best case for a map of that size): where the units lie, apart from learning the actions.

Prints one JSON line per row. Used by docs/benchmarks/dmc/TUNING.md.

    python scripts/dmc_yardsticks.py --episodes 5
    python scripts/dmc_yardsticks.py --through --seed 100 --states 50000 [--task dmc:pendulum-swingup]
    python scripts/dmc_yardsticks.py --hold 100-111 --episodes 30
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import scipy.linalg

from somarm.reproduce.yardsticks import pendulum_hold
from somarm.tasks.dmc import SuiteEnv, split_name

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tune_benchmark import seed_params, tuning_seed  # noqa: E402  (a tuning seed's task, as the tuning scripts make it)

#: The suite's reacher tasks (one controller and one set of bounds for both).
REACHERS = ("dmc:reacher-easy", "dmc:reacher-hard")

#: The observation bounds the ``--through`` maps scale by (the region each controller keeps the task in).
BOUNDS = {
    "dmc:cartpole-balance": ([-1.5, -1.0, -0.25, -1.5, -2.0], [1.5, 1.0, 0.25, 1.5, 2.0]),
    "dmc:cartpole-swingup": ([-1.8, -1.0, -1.0, -1.5, -10.0], [1.8, 1.0, 1.0, 1.5, 10.0]),
    "dmc:pendulum-swingup": ([-1.0, -1.0, -10.0], [1.0, 1.0, 10.0]),
    "dmc:point_mass-easy": ([-0.03, -0.03, -0.1, -0.1], [0.03, 0.03, 0.1, 0.1]),
    **dict.fromkeys(REACHERS, ([-3.5, -2.8, -0.45, -0.45, -5.0, -5.0], [3.5, 2.8, 0.45, 0.45, 5.0, 5.0])),
}
#: point_mass-easy's maps over the whole arena instead (a row of ``THROUGH`` may name other bounds).
ARENA = ([-0.3, -0.3, -0.1, -0.1], [0.3, 0.3, 0.1, 0.1])
#: Per task: the action noise (sd) of the visited states, and the representations tried (preset changes,
#: with the observation bounds of their maps where not ``BOUNDS``).
THROUGH = {
    "dmc:cartpole-balance": (0.1, [
        "input_groups=all local_linear=false shared_slopes=false",  # the dmc preset's one map
        "local_linear=false shared_slopes=false", "input_groups=2,3,4 local_linear=false shared_slopes=false",
        "input_shape=30x30 local_linear=false shared_slopes=false", "", "shared_slopes=false",
        "input_shape=10x10 action_slopes=true"]),
    "dmc:cartpole-swingup": (0.05, [
        "", "input_shape=30x30", "k_nearest=3", "input_groups=1,2,4", "input_groups=1,4"]),
    "dmc:pendulum-swingup": (0.3, [
        "grid_span=1", "grid_span=1 input_shape=30x30", "grid_span=1 k_nearest=3",
        "local_linear=true shared_slopes=true", "local_linear=true shared_slopes=true action_slopes=true",
        "input_shape=10x10 local_linear=true shared_slopes=true action_slopes=true", "input_groups=1,2",
        ("", ([-1.0, -1.0, -4.0], [1.0, 1.0, 4.0])), ("", ([0.5, -1.0, -5.0], [1.0, 1.0, 5.0])),
        ("", ([0.8, -0.6, -4.0], [1.0, 0.6, 4.0]))]),
    "dmc:point_mass-easy": (0.3, [("input_groups=all", ARENA), ("", ARENA), "", "k_nearest=3"]),
    **dict.fromkeys(REACHERS, (0.3, [
        "", "input_shape=30x30", "k_nearest=3", "input_groups=0,1,2,3", "input_groups=0,1;2,3",
        "input_groups=pairs input_shape=10x10 k_nearest=3 local_linear=true shared_slopes=true"])),
}

#: The preset a task's ``--through`` rows change, where not the task's own: cartpole-swingup's rows hold the
#: pump in the ``dmc`` recipe's map and forces (a sixth of the box), what its rows were run on.
THROUGH_PRESET = {"dmc:cartpole-swingup": "dmc"}

#: The map shapes the controller is read through at its nearest unit, per task (with ``--through``).
AT_UNITS = {"dmc:pendulum-swingup": [(30, 30), (50, 50)],
            **dict.fromkeys(REACHERS, [(20, 20), (50, 50)])}


def _returns(env: SuiteEnv, policy, episodes: int, watch=None) -> list[float]:
    """``policy``'s return on each of ``env``'s episodes 0 to ``episodes`` - 1; ``watch(episode, env, action)``,
    if given, after every step."""
    out = []
    for episode in range(episodes):
        observation, _ = env.reset(seed=episode)
        total, done = 0.0, False
        while not done:
            action = np.atleast_1d(policy(observation))
            observation, reward, terminated, truncated, _ = env.step(action)
            total += reward
            done = terminated or truncated
            if watch is not None:
                watch(episode, env, action)
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


def _swing_up(env: SuiteEnv):
    """Energy pumping and a PD catch for the suite's pendulum: its mass, the distance of its centre of mass
    from the hinge and its inertia about the hinge, read from the model."""
    model = env.physics.model
    body = model.body("pole").id
    mass, arm = float(model.body_mass[body]), float(np.linalg.norm(model.body_ipos[body]))
    inertia = float(model.body_inertia[body, 1]) + mass * arm ** 2
    weight = mass * arm * float(-model.opt.gravity[2])

    def law(o: np.ndarray) -> np.ndarray:
        cos, sin, w = o
        if cos > 0.95:
            return np.clip(-10.0 * np.arctan2(sin, cos) - 2.0 * w, -1.0, 1.0)
        energy = 0.5 * inertia * w * w + weight * (cos - 1.0)
        return np.clip(5.0 * w * -energy, -1.0, 1.0) if abs(w) > 1e-3 else 1.0

    return law


def on_grid(law, angles: int, speeds: int, top_speed: float = 10.0):
    """``law`` over (cos, sin, angular velocity) read at the centre of the observation's cell of a uniform
    ``angles`` x ``speeds`` grid over the angle and the velocity (+-``top_speed``, the outer cells open)."""
    def held(o: np.ndarray) -> np.ndarray:
        i = np.floor((np.arctan2(o[1], o[0]) + np.pi) / (2 * np.pi) * angles)
        angle = -np.pi + (min(i, angles - 1) + 0.5) * 2 * np.pi / angles
        j = np.clip(np.floor((o[2] + top_speed) / (2 * top_speed) * speeds), 0, speeds - 1)
        return law(np.array([np.cos(angle), np.sin(angle), -top_speed + (j + 0.5) * 2 * top_speed / speeds]))
    return held


def pump(force: float):
    """Energy pumping for the suite's cartpole, with no catch: ``force`` pushed against the pole's swing."""
    def law(o: np.ndarray) -> np.ndarray:
        _, cos, _, _, thetadot = o
        return np.array([-force * np.sign(thetadot * cos) if abs(thetadot) > 1e-3 else force])
    return law


def reach(env: SuiteEnv, gain: float = 10.0, damping: float = 1.0):
    """A joint-space PD law on the suite reacher's inverse kinematics: the finger sent to the target (the
    finger plus ``to_target``) through the joint angles that put it there, of the two elbow solutions the
    one with the smaller summed joint error from the arm's own angles."""
    model = env.physics.model
    upper = float(np.linalg.norm(model.body("hand").pos[:2]))  # shoulder to wrist
    lower = float(np.linalg.norm(model.body("finger").pos[:2]))  # wrist to finger

    def law(o: np.ndarray) -> np.ndarray:
        shoulder, wrist, dx, dy = o[:4]
        x = upper * np.cos(shoulder) + lower * np.cos(shoulder + wrist) + dx
        y = upper * np.sin(shoulder) + lower * np.sin(shoulder + wrist) + dy
        bend = np.arccos(np.clip((x * x + y * y - upper ** 2 - lower ** 2) / (2 * upper * lower), -1.0, 1.0))
        errors = []
        for elbow in (bend, -bend):
            base = np.arctan2(y, x) - np.arctan2(lower * np.sin(elbow), upper + lower * np.cos(elbow))
            errors.append(np.array([(base - shoulder + np.pi) % (2 * np.pi) - np.pi, elbow - wrist]))
        error = min(errors, key=lambda e: float(np.abs(e).sum()))
        return np.clip(gain * error - damping * o[4:6], -1.0, 1.0)

    return law


def controllers() -> dict[str, list[tuple[str, object]]]:
    """Per task: (what, policy) of every fixed controller, the first of each the one ``--through`` holds."""
    sixth, whole = np.linspace(-1 / 6, 1 / 6, 11), np.linspace(-1.0, 1.0, 11)
    cartpole = SuiteEnv("cartpole", "balance")
    gain = _cartpole_gain(cartpole)
    cartpole.close()

    def lqr(o: np.ndarray) -> np.ndarray:
        x, cos, sin, xdot, thetadot = o
        return np.clip(-gain @ np.array([x, np.arctan2(sin, cos), xdot, thetadot]), -1.0, 1.0)

    pendulum = SuiteEnv("pendulum", "swingup")
    swing = _swing_up(pendulum)
    pendulum.close()
    arm = SuiteEnv("reacher", "easy")
    ik = reach(arm)
    arm.close()
    pd = lambda o: np.clip(-50.0 * o[:2] - 10.0 * o[2:], -1.0, 1.0)  # noqa: E731
    still = lambda o: 0.0  # noqa: E731
    return {
        "dmc:cartpole-balance": [
            ("LQR rounded to the dmc preset's 11 forces (a sixth of the box)", lambda o: _rounded(lqr(o), sixth)),
            ("no force", still), ("LQR", lqr),
            ("LQR rounded to 11 forces over the box", lambda o: _rounded(lqr(o), whole))],
        "dmc:cartpole-swingup": [
            ("energy pumping at the dmc preset's largest force (a sixth of the box), no catch", pump(1 / 6)),
            ("energy pumping at the box's largest force, no catch", pump(1.0)), ("no force", still)],
        "dmc:pendulum-swingup": [
            ("energy pumping and PD catch rounded to 11 torques over the box", lambda o: _rounded(swing(o), whole)),
            ("energy pumping and PD catch", swing),
            ("energy pumping and PD catch rounded to the dmc preset's 11 torques", lambda o: _rounded(swing(o), sixth)),
            ("energy pumping and PD catch rounded to 11 torques over the box, on a 30x30 grid over angle and velocity",
             on_grid(lambda o: _rounded(swing(o), whole), 30, 30)),
            ("energy pumping and PD catch rounded to 11 torques over the box, on a 10x10 grid over angle and velocity",
             on_grid(lambda o: _rounded(swing(o), whole), 10, 10)),
            ("the PD catch alone within 45 degrees of upright, no torque elsewhere (pendulum_hold)",
             lambda o: pendulum_hold(o[None])[0])],
        "dmc:point_mass-easy": [
            ("PD rounded to the dmc_2d preset's 3x3 grid", lambda o: np.round(pd(o))), ("PD", pd)],
        **dict.fromkeys(REACHERS, [
            ("joint-space PD on the inverse kinematics rounded to the dmc_2d preset's 3x3 grid",
             lambda o: np.round(ik(o))),
            ("joint-space PD on the inverse kinematics", ik), ("no force", still)]),
    }


def _through(task: str, law, args) -> list[dict]:
    """``law`` as each of the task's ``THROUGH`` representations holds it (rows, one a representation)."""
    from somarm import tasks
    from somarm.learners.settings import parse_settings
    from somarm.learners.somq import SOMQConfig
    from somarm.reproduce import yardsticks
    from somarm.tasks.dmc import gym_id

    noise, representations = THROUGH[task]
    preset = THROUGH_PRESET.get(task, tasks.record(task).preset)
    env = SuiteEnv(*split_name(task))
    rows, visited = [], {}  # the controller's states once per bounds: (scaling, states, actions)
    for row in representations:
        text, (low, high) = row if isinstance(row, tuple) else (row, BOUNDS[task])
        key = (tuple(low), tuple(high))
        if key not in visited:
            scaling = tasks.make(task, seed=args.seed, observation_low=low, observation_high=high)
            visited[key] = (scaling, *yardsticks.controller_states(gym_id(task), law, scaling, args.states, noise,
                                                                   args.seed))
        scaling, states, actions = visited[key]
        changes = parse_settings(SOMQConfig, dict(item.split("=", 1) for item in text.split()))
        policy = yardsticks.through_representation(gym_id(task), states, actions, scaling, changes, args.seed,
                                                   preset=preset)
        rows.append({"task": task, "held by": f"the {preset} preset" + (f", {text}" if text else ""),
                     "bounds": [low, high], "seed": args.seed, "states": args.states, "noise": noise,
                     "returns": _returns(env, policy, args.episodes)})
    for shape in AT_UNITS.get(task, []):
        scaling = tasks.make(task, seed=args.seed, observation_low=BOUNDS[task][0], observation_high=BOUNDS[task][1])
        units = yardsticks.controller_map(gym_id(task), law, scaling, shape, args.states, noise, args.seed)
        rows.append({"task": task, "held by": f"the controller itself at the nearest unit of a {shape[0]}x{shape[1]} "
                     "map learned on its states", "bounds": list(BOUNDS[task]), "seed": args.seed, "states": args.states,
                     "noise": noise, "returns": _returns(env, yardsticks.through_map(law, scaling, units), args.episodes)})
        scaling.close()
    for scaling, _, _ in visited.values():
        scaling.close()
    env.close()
    return rows


def hold_on_seeds(seeds: list[int], episodes: int) -> list[dict]:
    """``pendulum_hold`` on each tuning seed's own evaluation episodes of dmc:pendulum-swingup (the starts
    ``scripts/tune_dmc.py`` scores a seed on, drawn in order: the first 10 of 30 are its default 10)."""
    from somarm import tasks
    from somarm.run.evaluation import episode_starts

    name = "dmc:pendulum-swingup"
    rows = []
    for seed in seeds:
        # the suite's own observations at its own step (the task's preset sees the angle, every 5 steps); the
        # starts are the same reset seeds whatever the view
        judge = tasks.make(name, seed=seed, **seed_params(name, seed, "dmc"))
        returns = judge.run_episodes(lambda x, scaling=judge.scaling: pendulum_hold(scaling.unscale(x)),
                                     episode_starts(judge, episodes, seed))["returns"]
        judge.close()
        rows.append({"task": name, "controller": "pendulum_hold", "seed": seed,
                     "returns": [round(float(x), 1) for x in returns],
                     "first 10": round(float(np.mean(returns[:10])), 1), "mean": round(float(np.mean(returns)), 1)})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--through", action="store_true", help="each controller as SOM-Q's maps hold it")
    parser.add_argument("--seed", type=int, default=100, help="with --through: a tuning seed (100-199)")
    parser.add_argument("--states", type=int, default=50_000, help="with --through: the controller's states learned")
    every = controllers()
    parser.add_argument("--task", choices=list(every), default=None, help="one task's rows (default: every task's)")
    parser.add_argument("--hold", default=None, metavar="FIRST-LAST",
                        help="the pendulum hold on these tuning seeds' own evaluation episodes (--episodes of them)")
    args = parser.parse_args()
    if args.hold is not None:
        first, _, last = args.hold.partition("-")
        if not (first.isdigit() and (last or first).isdigit()
                and 100 <= int(first) <= int(last or first) <= 199):
            raise SystemExit(f"--hold {args.hold}: give tuning seeds FIRST-LAST within 100-199")
        for row in hold_on_seeds(list(range(int(first), int(last or first) + 1)), args.episodes):
            print(json.dumps(row), flush=True)
        return
    if args.through:
        tuning_seed(args.seed)
    if args.through and args.task not in (None, *THROUGH):
        raise SystemExit(f"--through takes {', '.join(THROUGH)}, not {args.task}")
    rows = []
    for task in THROUGH if args.through else every:
        laws = every[task]
        if args.task not in (None, task):
            continue
        if args.through:
            rows += _through(task, laws[0][1], args)
            continue
        env = SuiteEnv(*split_name(task))
        rows += [{"task": task, "controller": what, "returns": _returns(env, law, args.episodes)} for what, law in laws]
        env.close()
    for row in rows:
        row["mean"] = round(float(np.mean(row["returns"])), 1)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
