"""``somarm bench adapters``: what the Gymnasium and SB3 adapters add per env-step, beside the bare task.

In one run, on one task (reach2 by default, the cheapest physics, so the adapters' share shows):

- the batched task itself, ``reset`` + ``step`` of ``--envs`` trials (per trial-step), against
  ``somarm.peers.vec_env.BatchedVecEnv`` with as many envs (per env-step; it builds the per-env info dicts);
- ``tasks.make(n_trials=1)`` against one ``gymnasium.make("somarm/<Name>-v0")`` env, and against
  Gymnasium's ``SyncVectorEnv`` of ``--envs`` separate envs (per env-step).

The overhead is the adapter's time minus the bare task's. Each figure is the best of ``--repeats``.
"""

from __future__ import annotations

import numpy as np

from somarm.helptext import PlainHelpFormatter
from somarm.perf import best_seconds
from somarm.validation import OneLineParser, whole_number

__all__ = ["measure", "main"]


def measure(task: str, *, n_envs: int, steps: int, repeats: int) -> dict[str, float]:
    """Microseconds per env-step of each path (see the module doc), keyed by a short label."""
    import gymnasium

    from somarm import tasks
    from somarm.peers.gym import env_id, to_task_actions
    from somarm.peers.vec_env import BatchedVecEnv

    batched = tasks.make(task, n_trials=n_envs)
    single = tasks.make(task)
    normalised = np.zeros((n_envs, batched.action_dim), dtype=np.float32)
    task_actions = to_task_actions(normalised, batched.action_low, batched.action_high)
    venv = BatchedVecEnv(task, n_envs)
    venv.reset()
    env = gymnasium.make(env_id(task))
    env.reset(seed=0)
    sync = gymnasium.vector.SyncVectorEnv([lambda: gymnasium.make(env_id(task)) for _ in range(n_envs)])
    sync.reset(seed=0)

    def bare_batched():
        for _ in range(steps):
            batched.reset()
            batched.step(task_actions)

    def bare_single():
        for _ in range(steps):
            single.reset()
            single.step(task_actions[:1])

    def vec():
        for _ in range(steps):
            venv.step(normalised)

    def gym_single():
        for _ in range(steps):
            env.reset()
            env.step(normalised[0])

    def gym_sync():
        for _ in range(steps):
            sync.step(normalised)  # autoreset: every other call resets instead of stepping

    per_batch, per_one = 1e6 / (steps * n_envs), 1e6 / steps
    return {
        "task batched": best_seconds(bare_batched, repeats) * per_batch,
        "BatchedVecEnv": best_seconds(vec, repeats) * per_batch,
        "task single": best_seconds(bare_single, repeats) * per_one,
        "gymnasium env": best_seconds(gym_single, repeats) * per_one,
        "SyncVectorEnv": best_seconds(gym_sync, repeats) * per_batch * 2,
    }


def main(argv: list[str] | None = None) -> int:
    """Print the figures; ``--quick`` for a smoke run."""
    parser = OneLineParser(prog="somarm bench adapters", description=__doc__.splitlines()[0],
                           formatter_class=PlainHelpFormatter)
    parser.add_argument("--task", default="reach2", help="task (default reach2)")
    parser.add_argument("--envs", type=whole_number, default=100, help="envs (trials) stepped together (default 100)")
    parser.add_argument("--steps", type=whole_number, help="steps per timing (default 300, quick 30)")
    parser.add_argument("--repeats", type=whole_number, help="best of this many runs (default 3, quick 1)")
    parser.add_argument("--quick", action="store_true", help="fewer steps (a smoke run)")
    args = parser.parse_args(argv)
    steps = args.steps or (30 if args.quick else 300)
    repeats = args.repeats or (1 if args.quick else 3)
    figures = measure(args.task, n_envs=args.envs, steps=steps, repeats=repeats)
    print(f"{args.task}: microseconds per env-step, {args.envs} envs, {steps} steps, best of {repeats}")
    for label, value in figures.items():
        print(f"{label:16s} {value:10.2f}")
    print(f"overhead per env-step: BatchedVecEnv {figures['BatchedVecEnv'] - figures['task batched']:.2f} us, "
          f"gymnasium env {figures['gymnasium env'] - figures['task single']:.2f} us")
    return 0
