"""Train SOM-Q on the two-link arm (Figs. 7-10) headless; edit the config below and run.

    python examples/train_reach2.py --trials 20 --steps 50000 --seed 0 --out runs/reach2

The logic lives in ``somarm.run``; this script only chooses a configuration.
"""

from __future__ import annotations

import argparse
import os
import sys

os.environ.setdefault("MUJOCO_GL", "disable")

from somarm import run  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="runs/reach2__somq")
    args = parser.parse_args()
    config = run.RunConfig(
        task="reach2",
        learner="somq",
        preset="table1",  # Table 1: 50x1 input map, 50x1 action map, f(t) = 1/(t/1000 + 1)
        overrides={},  # typed, e.g. {"epsilon": 0.2, "decay": InverseDecay(2000.0)} (learners.schedules)
        n_trials=args.trials,
        n_steps=args.steps,
        seed=args.seed,
    )
    result = run.train(config)
    greedy = run.greedy_summary(result)
    run.write(result, args.out, extra_summary=greedy)
    print(f"greedy mean distance to fresh goals: {-greedy['greedy_mean_reward']:.4f} (results in {args.out})")


if __name__ == "__main__":
    try:
        main()
    except ValueError as exc:  # bad settings: one line, no traceback
        sys.exit(f"train_reach2: error: {exc}")
