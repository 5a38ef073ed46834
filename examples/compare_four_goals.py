"""SOM-Q against the Motoric Map on the four-goal task (Fig. 13), headless.

    python examples/compare_four_goals.py --trials 20 --seed 0 --out runs/four_goals

Writes one run folder per learner and prints the mean error before and after the goals move.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "disable")

from somarm import run  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--switch", type=int, default=20_000, help="step at which the goals move")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="runs/four_goals")
    args = parser.parse_args()
    for learner in ("somq", "motoric"):
        config = run.RunConfig(
            task="four_goals",
            learner=learner,
            preset="table2",  # Table 2: 10x10 input map, 8x1 action map, floors on alpha, lambda_A, epsilon
            task_params={"switch_step": args.switch},
            n_trials=args.trials,
            n_steps=2 * args.switch,
            seed=args.seed,
        )
        result = run.train(config, label=learner)
        run.write(result, Path(args.out) / learner)
        before = -result.block_means[result.steps <= args.switch].mean()
        after = -result.block_means[result.steps > args.switch].mean()
        print(f"{learner:8s} mean error before the move {before:.4f}, after {after:.4f}")


if __name__ == "__main__":
    try:
        main()
    except ValueError as exc:  # bad settings: one line, no traceback
        sys.exit(f"compare_four_goals: error: {exc}")
