"""A Reacher-v5 PD law held through SOM-Q input representations, on a tuning seed.

The PD law of ``somarm.reproduce.yardsticks`` runs with torque noise for ``--states`` steps from the seed;
a SOM-Q learner with the reacher preset changed by each ``--rep`` learns it from those states
(``yardsticks.through_representation``: gamma 0, one random grid torque a step, rewarded by minus its
squared distance from the PD torque), and its greedy policy is replayed for ``--episodes`` episodes.
Prints one JSON line per representation. For choosing settings on seeds 100-199 only.

    python scripts/yardstick_representation.py --seed 100 --rep "input_groups=pairs input_shape=10x10 k_nearest=3"
"""

from __future__ import annotations

import argparse
import json
import time

from somarm.learners.settings import parse_settings
from somarm.learners.somq import SOMQConfig
from somarm.reproduce import yardsticks
from somarm.tasks import gym_envs

ENV = "Reacher-v5"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=100, help="a tuning seed (100-199)")
    parser.add_argument("--states", type=int, default=50_000)
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--noise", type=float, default=yardsticks.CONTROLLER_MAP_NOISE[ENV])
    parser.add_argument("--controller", choices=sorted(yardsticks.REACHER_CONTROLLERS), default="jacobian",
                        help="the law held: the Jacobian-transpose PD law or the joint-space one")
    parser.add_argument("--rep", action="append", default=[], metavar="'KEY=VALUE ...'",
                        help="one representation: settings changed from the reacher preset (repeatable)")
    args = parser.parse_args()
    if not 100 <= args.seed <= 199:
        raise SystemExit(f"seed {args.seed}: tuning seeds are 100-199")
    scaling = gym_envs.BoxScaling(*gym_envs.estimate_bounds(gym_envs.GymParams(ENV), args.seed))
    controller = yardsticks.REACHER_CONTROLLERS[args.controller]
    states, torques = yardsticks.controller_states(ENV, controller, scaling, args.states, args.noise, args.seed)
    for text in args.rep or [""]:
        overrides = dict(item.split("=", 1) for item in text.split())
        start = time.perf_counter()
        policy = yardsticks.through_representation(ENV, states, torques, scaling,
                                                   parse_settings(SOMQConfig, overrides), args.seed)
        learned = time.perf_counter() - start
        value = yardsticks.mean_return(ENV, policy, args.episodes, args.seed)
        print(json.dumps({"seed": args.seed, "states": args.states, "controller": args.controller, "set": overrides, "return": round(value, 2),
                          "learn_s": round(learned, 1)}), flush=True)


if __name__ == "__main__":
    main()
