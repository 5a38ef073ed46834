"""Where a learned greedy cart goes on dmc:cartpole-balance (or ``--task dmc:cartpole-swingup``): train the
task's preset (or ``--preset``, changed by ``--set KEY=VALUE``) for ``--samples`` steps at a tuning seed,
then replay its greedy policy (the interpolated response, SOM-Q+) over the suite's episodes 0 to
``--episodes`` - 1 and print, per episode, the return, how far the cart went, the first step it came
within 5 cm of the end of its rail, the first step the pole fell below horizontal (0 on the swing-up, whose
pole starts hanging), the highest the pole
rose (the largest cosine of its angle from upright) and the steps it spent within 30 degrees of upright,
and the mean absolute force. One JSON line per episode. Used by docs/benchmarks/dmc/TUNING.md.

    python scripts/dmc_cart_replay.py --seed 100 --samples 100000 --set input_shape=20x20 --set alpha.floor=0.05
    python scripts/dmc_cart_replay.py --task dmc:cartpole-swingup --seed 100

(that is ``dmc_balance`` as it was before it took a 30x30 map and a step size falling to 0).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from somarm import tasks
from somarm.tasks.dmc import SuiteEnv, split_name

sys.path.insert(0, str(Path(__file__).resolve().parent))
from dmc_yardsticks import _returns  # noqa: E402  (how the yardsticks play a suite episode)
from tune_benchmark import greedy_policy, trained  # noqa: E402  (how the tuning scripts train)

#: The cartpole tasks replayed.
TASKS = ("dmc:cartpole-balance", "dmc:cartpole-swingup")


def _first(mask: np.ndarray) -> int | None:
    return int(np.argmax(mask)) if mask.any() else None


def replay(env: SuiteEnv, policy, episodes: int) -> list[dict]:
    """``policy`` (observation -> action) on cartpole ``env`` over its episodes 0 to ``episodes`` - 1: per
    episode the return, the rail's end, how far the cart went, the first step it came within 5 cm of the
    rail's end, the first step the pole fell below horizontal, the pole's largest cosine from upright and
    its steps within 30 degrees of upright, and the mean absolute force."""
    rail = float(env.physics.named.model.jnt_range["slider"][1])
    seen = [([], [], []) for _ in range(episodes)]

    def watch(episode, env, action):
        carts, cosines, forces = seen[episode]
        carts.append(abs(float(env.physics.named.data.qpos["slider"][0])))
        cosines.append(float(env.physics.pole_angle_cosine()[0]))
        forces.append(abs(float(action[0])))  # _returns passes the action as a 1-d array

    rows = []
    for episode, total in enumerate(_returns(env, policy, episodes, watch)):
        carts, cosines = np.asarray(seen[episode][0]), np.asarray(seen[episode][1])
        rows.append({"episode": episode, "return": total, "rail_m": rail,
                     "cart_max_m": round(float(carts.max()), 3), "cart_at_rail_step": _first(carts > rail - 0.05),
                     "pole_fell_step": _first(cosines < 0), "pole_top_cos": round(float(cosines.max()), 3),
                     "steps_upright": int((cosines > np.cos(np.pi / 6)).sum()), "mean_abs_force": round(float(np.mean(seen[episode][2])), 3)})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", choices=TASKS, default=TASKS[0])
    parser.add_argument("--seed", type=int, default=100, help="a tuning seed (100-199)")
    parser.add_argument("--samples", type=int, default=100_000)
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--preset", default=None, help="default: the task's")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()
    preset = args.preset or tasks.record(args.task).preset
    task, learner, _ = trained(args.task, args.seed, preset, args.set, args.samples)
    env = SuiteEnv(*split_name(args.task))
    for row in replay(env, greedy_policy(learner, task), args.episodes):
        print(json.dumps({"task": args.task, "seed": args.seed, "preset": preset, "settings": args.set, "samples": args.samples, **row}),
              flush=True)
    env.close()
    task.close()


if __name__ == "__main__":
    main()
