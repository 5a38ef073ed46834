"""Score SOM-Q settings on a suite task's tuning seeds (100-199), as the dmc part scores them.

One trial per seed: the task's preset (or ``--preset``) changed by ``--set KEY=VALUE``, the task by
``--task-set KEY=JSON`` (``observation_low=[...]``: the scaling bounds), trained for ``--samples`` and
scored at each rung of ``--rungs`` (``--samples`` and the rungs count the task's steps: decisions of
``action_repeat`` suite steps where the preset or ``--task-set`` holds actions, as the row's
``action_repeat`` says) by the mean undiscounted greedy return over ``--episodes`` fresh episodes of the seed (the reset seeds of the seed's evaluation stream; the observation scaling estimated
at the seed where not given). Prints one JSON line per seed and appends it to ``--record`` (a JSON-lines
file, e.g. docs/benchmarks/dmc/tuning.jsonl): the score at each rung, each episode's return at the last
(the episodes are drawn in order, so the first 10 of ``--episodes 30`` are the 10 of the default) and the
training steps that paid a positive reward by each rung. For choosing settings on seeds 100-199 only.

    python scripts/tune_dmc.py dmc:cartpole-balance --seeds 100,101 --set gamma=0.99 \\
        --task-set 'observation_low=[-2,-1,-1,-2,-5]' --task-set 'observation_high=[2,1,1,2,5]'
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from somarm import tasks
from somarm.run.evaluation import episode_starts

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tune_benchmark import learner_for, parse_sets, preset_settings, scores_at_rungs, seed_params, tuning_seed  # noqa: E402  (the scoring both tuning scripts share)


def _register_repeat(name: str, k: int) -> str:
    """Suite task ``name`` with every action held for ``k`` of the suite's control steps (their rewards
    summed), registered as ``tune-dmc/DOMAIN-TASK-rK-v0`` in this process; its ``gym:`` name."""
    import gymnasium

    from somarm.tasks.dmc import SuiteEnv, split_name

    domain, task = split_name(name)

    class Repeat(gymnasium.Wrapper):
        def step(self, action):
            total = 0.0
            for _ in range(k):
                observation, reward, terminated, truncated, info = self.env.step(action)
                total += reward
                if terminated or truncated:
                    break
            return observation, total, terminated, truncated, info

    env_id = f"tune-dmc/{domain}-{task}-r{k}-v0"
    gymnasium.register(env_id, entry_point=lambda: Repeat(SuiteEnv(domain, task)), disable_env_checker=True)
    return "gym:" + env_id


def _task_set(items: list[str]) -> dict:
    out = {}
    for item in items:
        key, _, text = item.partition("=")
        try:
            out[key] = json.loads(text)
        except json.JSONDecodeError:
            out[key] = text
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("task")
    parser.add_argument("--seeds", default="100", help="comma-separated tuning seeds (100-199)")
    parser.add_argument("--preset", default=None, help="the preset to start from (default: the task's)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--task-set", action="append", default=[], metavar="KEY=JSON")
    parser.add_argument("--train-task-set", action="append", default=[], metavar="KEY=JSON",
                        help="set for the training task only (time_limit=2: shorter training episodes)")
    parser.add_argument("--samples", type=int, default=None, help="default: the task's run length")
    parser.add_argument("--rungs", default="", help="comma-separated sample counts scored on the way")
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--record", default=None, help="a JSON-lines file each seed's row is appended to")
    parser.add_argument("--note", default="", help="a word on what the row tries")
    parser.add_argument("--action-repeat", type=int, default=1, help="hold each action for K control steps")
    args = parser.parse_args()
    name = args.task if args.action_repeat == 1 else _register_repeat(args.task, args.action_repeat)
    record = tasks.record(name)
    samples = args.samples or record.n_steps
    rungs = sorted({int(r) for r in args.rungs.split(",") if r} | {samples})
    overrides = parse_sets(args.set)
    preset = args.preset or tasks.record(args.task).preset
    settings = preset_settings(preset, overrides)
    given = _task_set(args.task_set)
    for seed in (tuning_seed(int(s)) for s in args.seeds.split(",")):
        params = seed_params(name, seed, preset, given, scaled_as=args.task)
        train_params = {**params, **_task_set(args.train_task_set)}
        task, judge = tasks.make(name, seed=seed, **train_params), tasks.make(name, seed=seed, **params)
        starts = episode_starts(judge, args.episodes, seed)
        scored = scores_at_rungs(task, judge, learner_for(task, settings, seed), starts, rungs)
        scores = {rung: round(mean, 1) for rung, (mean, *_) in scored.items()}
        _, wall, returns, _ = scored[rungs[-1]]
        row = {"task": args.task, "seed": seed, "steps": samples, "preset": preset,
               "settings": [f"{k}={v}" for k, v in overrides.items()],
               "task_settings": [f"{k}={json.dumps(v)}" for k, v in given.items()],
               "train_task_settings": args.train_task_set,
               "action_repeat": args.action_repeat * int(params.get("action_repeat", 1)), "greedy": scores[samples], "rungs": scores, "episodes": args.episodes, "train_s": round(wall, 1),
               "returns": [round(float(x), 1) for x in returns],
               "paid_training_steps": {rung: paid for rung, (*_, paid) in scored.items()},
               "note": args.note}
        print(json.dumps(row), flush=True)
        if args.record:
            with Path(args.record).open("a") as f:
                f.write(json.dumps(row) + "\n")
        task.close()
        judge.close()


if __name__ == "__main__":
    main()
