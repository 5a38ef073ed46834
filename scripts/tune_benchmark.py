"""Score SOM-Q settings on a benchmark's tuning seeds, as the benchmarks part scores them.

One trial per seed, the environment's preset changed by ``--set KEY=VALUE``, trained for ``--samples``
and scored at each rung of ``--rungs`` by the greedy return over ``--episodes`` fresh episodes (the reset
seeds and the observation scaling of the seed itself, as ``somarm compare --seed S --seeds 1`` would).
Prints one JSON line per seed. For choosing settings on seeds 100-199 only.

    python scripts/tune_benchmark.py gym:Reacher-v5 --seeds 100,101 --set input_groups=pairs --set input_shape=5x5
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from somarm import tasks
from somarm.learners import make, presets
from somarm.reproduce.benchmarks import TUNING_SEEDS
from somarm.run.evaluation import evaluation_rng


def tuning_seed(seed: int) -> int:
    """``seed``, if it is a tuning seed (``TUNING_SEEDS``); else the scripts' one-line exit."""
    if seed not in TUNING_SEEDS:
        raise SystemExit(f"seed {seed}: tuning seeds are {TUNING_SEEDS.start}-{TUNING_SEEDS[-1]}")
    return seed


def _train(task, learner, steps: int) -> int:
    """``steps`` steps of one trial on an episodic task (as ``somarm compare`` trains); returns how many of
    them paid a positive reward."""
    paid = 0
    for _ in range(steps):
        actions = learner.act(task.reset())
        rewards = task.step(actions)
        paid += int(np.count_nonzero(np.asarray(rewards) > 0))
        learner.learn(rewards, task.next_observations, task.terminal)
    return paid


def seed_params(name: str, seed: int, preset: str, given: dict | None = None, scaled_as: str | None = None) -> dict:
    """Task ``name``'s parameters at tuning seed ``seed``: how ``preset`` scales its task (``scaled_as``,
    default ``name``: ``presets.task_params_of``) with ``given`` over it, completed at the seed (the
    observation scaling estimated there where not given)."""
    asked = presets.task_params_of(preset, scaled_as or name)
    return tasks.record(name).complete(tasks.check_params(name, {**asked, **(given or {})}), seed)


def learner_for(task, settings, seed: int):
    """SOM-Q with ``settings`` over ``task``'s observation and action boxes, seeded by ``seed``."""
    return make("somq", settings, observation_low=task.observation_low, observation_high=task.observation_high,
                action_low=task.action_low, action_high=task.action_high, action_periodic=task.action_periodic,
                seed=seed)


def parse_sets(sets: list[str]) -> dict[str, str]:
    """``--set KEY=VALUE`` texts by key; the scripts' one-line exit for one without ``=``."""
    for item in sets:
        if "=" not in item:
            raise SystemExit(f"--set {item}: give KEY=VALUE")
    return dict(item.split("=", 1) for item in sets)


def preset_settings(preset: str, overrides: dict[str, str]):
    """``preset``'s config changed by ``overrides`` (text by key); the scripts' one-line exit for an unknown
    preset or a bad setting."""
    try:
        return presets.get(preset).with_overrides(overrides)
    except ValueError as exc:
        raise SystemExit(str(exc)) from None


def trained(name: str, seed: int, preset: str, sets: list[str], samples: int):
    """``preset`` changed by ``sets`` (``KEY=VALUE`` texts) trained on task ``name`` for ``samples`` steps at tuning
    seed ``seed``: ``(task, learner, paid)``, ``paid`` the training steps that paid a positive reward."""
    tuning_seed(seed)
    settings = preset_settings(preset, parse_sets(sets))
    task = tasks.make(name, seed=seed, **seed_params(name, seed, preset))
    learner = learner_for(task, settings, seed)
    return task, learner, _train(task, learner, samples)


def greedy_policy(learner, task):
    """The trained ``learner``'s greedy policy on ``task``'s raw observations (one at a time) -> an action."""
    return lambda o: np.asarray(learner.predict(task.scale(o)[None])[0]).reshape(-1)


def scores_at_rungs(task, judge, learner, starts, rungs) -> dict[int, tuple[float, float, np.ndarray, int]]:
    """Train ``learner`` on ``task`` up to each rung in turn: at each, the greedy mean return on ``judge``
    from ``starts``, the training seconds so far, each episode's return, and the training steps so far
    that paid a positive reward."""
    done, wall, paid, scores = 0, 0.0, 0, {}
    for rung in rungs:
        start = time.perf_counter()
        paid += _train(task, learner, rung - done)
        wall += time.perf_counter() - start
        done = rung
        returns = judge.run_episodes(lambda x, model=learner: model.predict(x[None])[0], starts)["returns"]
        scores[rung] = (float(returns.mean()), wall, np.asarray(returns, dtype=np.float64), paid)
    return scores


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("task")
    parser.add_argument("--seeds", default="100", help="comma-separated tuning seeds (100-199)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--samples", type=int, default=None, help="default: the task's run length")
    parser.add_argument("--rungs", default="", help="comma-separated sample counts scored on the way")
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--response", default=None, help="winner or interpolated (default: the preset's)")
    parser.add_argument("--task-set", action="append", default=[], metavar="KEY=JSON",
                        help="a task parameter over the preset's own (observation_ranges={\"6\": [-5, 5]})")
    args = parser.parse_args()
    record = tasks.record(args.task)
    samples = args.samples or record.n_steps
    rungs = sorted({int(r) for r in args.rungs.split(",") if r} | {samples})
    overrides = parse_sets(args.set)
    if args.response:
        overrides["response"] = args.response
    settings = preset_settings(record.preset, overrides)
    for seed in (tuning_seed(int(s)) for s in args.seeds.split(",")):
        # The observation scaling estimated at the seed, the task of the seed, fresh episodes of the seed.
        params = seed_params(args.task, seed, record.preset,
                             {key: json.loads(value) for key, value in (item.split("=", 1) for item in args.task_set)})
        task, judge = tasks.make(args.task, seed=seed, **params), tasks.make(args.task, seed=seed, **params)
        starts = judge.sample_starts(evaluation_rng(seed), args.episodes)
        scored = scores_at_rungs(task, judge, learner_for(task, settings, seed), starts, rungs)
        scores = {rung: (round(mean, 2), round(wall, 1)) for rung, (mean, wall, _, _) in scored.items()}
        print(json.dumps({"seed": seed, "set": overrides, "task_set": args.task_set, "scores": scores}), flush=True)


if __name__ == "__main__":
    main()
