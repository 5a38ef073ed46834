"""The five-seed table of docs/continuous-response.md: reach2 greedy error and failed trials per seed.

    python scripts/reach2_response_seeds.py --seeds 5

Each seed trains ``table1+`` with both responses, joint angles as circles and in the box, in
lockstep (20 trials x 50,000 steps each); each run's greedy error is the mean distance to 1000 fresh
goals per trial (as summary.json's), and a trial fails by ``metrics.failed_trials``. About 20-35 s
a seed on two cores.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("MUJOCO_GL", "disable")

from somarm import run  # noqa: E402
from somarm.reproduce import metrics  # noqa: E402
from somarm.run import evaluation  # noqa: E402

#: The table's rows: (response, joint angles as circles).
ROWS = [("interpolated", True), ("interpolated", False), ("winner", True), ("winner", False)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--steps", type=int, default=50_000)
    args = parser.parse_args()
    cells = {row: [] for row in ROWS}
    for seed in range(args.seeds):
        configs = [run.RunConfig(task="reach2", preset="table1+", n_trials=args.trials, n_steps=args.steps,
                                 seed=seed, overrides={"response": response, "periodic_actions": circles})
                   for response, circles in ROWS]
        for row, result in zip(ROWS, run.train_group(configs, progress=False), strict=True):
            errors = -evaluation.evaluate_greedy(result.learner, result.task, n_observations=1000, seed=seed)
            cells[row].append(f"{errors.mean():.4f} ({int(metrics.failed_trials(errors).sum())})")
    print("| preset, response, actions | " + " | ".join(f"seed {s}" for s in range(args.seeds)) + " |")
    print("|---|" + "---|" * args.seeds)
    for (response, circles), texts in cells.items():
        print(f"| `table1+`, {response}, {'circles' if circles else 'box'} | " + " | ".join(texts) + " |")


if __name__ == "__main__":
    main()
