"""Whether a learned greedy pendulum catches the pole from rest near upright on dmc:pendulum-swingup: train the
task's preset (or ``--preset``, changed by ``--set KEY=VALUE``) for ``--samples`` steps at a tuning seed, then
start the suite's pendulum at rest at each of ``--angles`` degrees either side of upright and count the suite's
steps of ``--steps`` that it pays (within its 8 degrees), for the learned greedy policy (the interpolated
response, SOM-Q+; seeing and acting as its preset asks, ``angles`` and ``action_repeat``) and for the hold (``somarm.reproduce.yardsticks.pendulum_hold``, a PD law within 45 degrees)
from the same starts. One JSON line per angle, then one with the training steps that were paid and how many
of the input map's units lie within 10, 20 and 45 degrees of upright below 3 rad/s, and how many different
units answer for the starts. Used by
docs/benchmarks/dmc/TUNING.md.

    python scripts/dmc_pendulum_catch.py --seed 100
    python scripts/dmc_pendulum_catch.py --seed 102 --set replay=8
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from somarm import tasks
from somarm.reproduce.yardsticks import pendulum_hold
from somarm.tasks.dmc import SuiteEnv

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tune_benchmark import greedy_policy, trained  # noqa: E402  (how the tuning scripts train)

TASK = "dmc:pendulum-swingup"


def paid_from_rest(env: SuiteEnv, policy, angle: float, steps: int) -> int:
    """The suite's steps of ``steps`` that it pays ``policy`` (observation -> action, as ``env`` shows it) with the
    pole started at rest ``angle`` radians from upright (``env``'s decisions of ``action_repeat`` steps)."""
    env.reset(seed=0)
    physics = env.physics
    with physics.reset_context():
        physics.named.data.qpos["hinge"] = angle
        physics.named.data.qvel["hinge"] = 0.0
    observation = env.observation_of(env.environment.task.get_observation(physics))
    paid = 0.0
    for _ in range(-(-steps // env.action_repeat)):
        observation, reward, *_ = env.step(np.atleast_1d(policy(observation)))
        paid += reward  # each suite step pays 1 within the 8 degrees, else 0
    return int(round(paid))


def catches(env: SuiteEnv, policy, angles_deg: list[float], steps: int) -> list[tuple[float, list[int]]]:
    """Per angle, the paid steps from rest at minus and plus that many degrees from upright."""
    return [(deg, [paid_from_rest(env, policy, sign * np.radians(deg), steps) for sign in (-1, 1)])
            for deg in angles_deg]


def units_near_upright(units: np.ndarray, degrees: float, speed: float = 3.0) -> int:
    """How many of the input map's ``units`` (observations: cosine, sine and angular velocity, or with the task's
    ``angles`` the angle and angular velocity) lie within ``degrees`` of upright and ``speed`` rad/s of rest."""
    angle = np.degrees(units[:, 0] if units.shape[1] == 2 else np.arctan2(units[:, 1], units[:, 0]))
    return int(((np.abs(angle) < degrees) & (np.abs(units[:, -1]) < speed)).sum())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=100, help="a tuning seed (100-199)")
    parser.add_argument("--samples", type=int, default=None, help="default: the task's run length")
    parser.add_argument("--preset", default=None, help="default: the task's")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--angles", default="0,5,10,15,20,30,45", help="degrees from upright, comma-separated")
    parser.add_argument("--steps", type=int, default=300, help="steps from each start (50 a second)")
    args = parser.parse_args()
    preset = args.preset or tasks.record(TASK).preset
    samples = args.samples or tasks.record(TASK).n_steps
    task, learner, paid = trained(TASK, args.seed, preset, args.set, samples)
    seen = task.env_of(0).unwrapped  # the suite task as the preset sees and acts on it
    env, plain = SuiteEnv("pendulum", "swingup", angles=seen.angles, action_repeat=seen.action_repeat), \
        SuiteEnv("pendulum", "swingup")
    learned = greedy_policy(learner, task)
    held = lambda o: pendulum_hold(o[None])[0]  # noqa: E731
    angles = [float(a) for a in args.angles.split(",")]
    head = {"task": TASK, "seed": args.seed, "preset": preset, "settings": args.set, "samples": samples,
            "steps": args.steps}
    for (deg, mine), (_, hold) in zip(catches(env, learned, angles, args.steps),
                                      catches(plain, held, angles, args.steps), strict=True):
        print(json.dumps({**head, "angle_deg": deg, "learned_paid": mine, "hold_paid": hold}), flush=True)
    units = task.unscale(learner.input_weights[0])
    near = {deg: units_near_upright(units, deg) for deg in (10, 20, 45)}
    rest = np.array([env.observation_of({"orientation": [np.cos(a), np.sin(a)], "velocity": [0.0]})
                     for deg in angles for a in np.radians([-deg, deg])])
    winners, _ = learner.greedy_units(task.scale(rest)[None])
    print(json.dumps({**head, "paid_training_steps": paid, "map_units": len(units), "units_near_upright": near,
                      "units_answering_the_starts": len(set(winners[0].tolist()))}), flush=True)
    env.close()
    plain.close()
    task.close()


if __name__ == "__main__":
    main()
