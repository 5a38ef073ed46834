"""The comparison part: SOM-Q beside a fixed action grid and SB3's TD3 and SAC (``--only peers``).

Not part of the default reproduction (TD3 and SAC take a gradient step per sample, so the part takes
far longer than the paper's experiments); ``somarm reproduce --only peers`` runs it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from somarm.learners.tabular import MAX_TABLE_ENTRIES, TabularConfig
from somarm.peers import compare
from somarm.peers.plot import NAMES
from somarm.reproduce.common import Context, fmt
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.report import Claim, Section

__all__ = ["TASKS", "Trained", "train", "measure", "report", "peers", "table"]

#: The tasks of the part and the learners run on each (a fixed grid cannot take reach20's 20 angles).
TASKS: dict[str, tuple[str, ...]] = {
    "reach2": compare.LEARNERS,
    "reach20": ("somq", "somq+", "motoric", "td3", "sac"),
    "throw_distance": compare.LEARNERS,
}
#: The tasks whose action space is small enough for a fixed grid.
_LOW_DIM = ("reach2", "throw_distance")


def table(result: dict) -> list[str]:
    """Markdown rows: median greedy error per learner (columns) at each sample count (rows), then costs."""
    kinds = list(result["learners"])
    rungs = sorted({n for data in result["learners"].values() for n in data["samples"]})
    lines = ["| samples | " + " | ".join(NAMES[k] for k in kinds) + " |", "|---" * (len(kinds) + 1) + "|"]
    for rung in rungs:
        cells = []
        for kind in kinds:
            data = result["learners"][kind]
            cells.append(fmt(float(np.median(data["error"][data["samples"].index(rung)])), 2)
                         if rung in data["samples"] else "-")
        lines.append(f"| {rung} | " + " | ".join(cells) + " |")
    per_sample = [f"{1e3 * float(np.median(result['learners'][k]['seconds_per_sample'])):.3g}" for k in kinds]
    lines.append("| ms per sample | " + " | ".join(per_sample) + " |")
    return lines


#: The greedy errors whose time to reach the time-to-error table gives.
THRESHOLDS = (0.05, 0.02, 0.01)


def time_to_error(result: dict) -> list[str]:
    """Markdown rows: per learner, the training seconds (and samples) at the first rung whose median
    error over seeds is at most each of ``THRESHOLDS`` (median of the seeds' wall times there)."""
    lines = ["| learner | " + " | ".join(f"error <= {t}" for t in THRESHOLDS) + " |",
             "|---" * (len(THRESHOLDS) + 1) + "|"]
    for kind, data in result["learners"].items():
        medians = np.median(np.array(data["error"]), axis=1)
        walls = np.median(np.array(data["wall_seconds"]), axis=1)
        cells = []
        for threshold in THRESHOLDS:
            reached = np.flatnonzero(medians <= threshold)
            cells.append(f"{fmt(float(walls[reached[0]]), 2)} s ({fmt(data['samples'][reached[0]])} samples)"
                         if reached.size else "not reached")
        lines.append(f"| {NAMES[kind]} | " + " | ".join(cells) + " |")
    return lines


def _final(result: dict, kind: str) -> float:
    return float(np.median(result["learners"][kind]["error"][-1]))


@dataclass(frozen=True)
class Trained:
    """Every comparison's answer, and the budgets they ran at."""

    results: dict[str, dict]  #: ``compare.compare``'s answer, by task
    budgets: dict[str, int]  #: somarm's learners' samples, by task
    seeds: int  #: seeds per learner
    peer_samples: int  #: TD3's and SAC's samples


def train(ctx: Context) -> Trained:
    """Every learner of ``TASKS`` on each task through ``somarm.peers.compare`` (which writes
    ``peers/<task>/compare.json`` and ``compare.png``): somarm's learners for the task's run length, TD3
    and SAC for 10,000 samples, 2 seeds each (``ctx.quick``: 200 and 120 samples, 1 seed).

    Raises:
      KeyboardInterrupt: a comparison was stopped (what finished is written).
    """
    seeds, peer_samples = ctx.pick(2, 1), ctx.pick(10_000, 120)
    budgets = {task: ctx.pick(compare.task_defaults(task)[1], 200) for task in TASKS}
    results = {}
    for task, learners in TASKS.items():
        config = compare.CompareConfig(task=task, learners=learners, samples=budgets[task],
                                       peer_samples=peer_samples, seeds=seeds, eval_seed=ctx.seed)
        results[task] = compare.compare(config, ctx.out_dir / "peers" / task, progress=ctx.progress)
    return Trained(results, budgets, seeds, peer_samples)


def measure(results: dict[str, dict]) -> dict:
    """The fixed grid's final error over SOM-Q's on the low-dimensional tasks, reach20's table size
    for the smallest grid against the limit, SOM-Q's and random actions' error on reach20, and each
    task's cost per sample of every learner.

    Args:
      results: ``train``'s answer.

    Returns:
      The numbers the claims and notes read, by name.
    """
    grid = TabularConfig(action_bins=2)
    return {
        "ratios": {t: _final(results[t], "tabular") / _final(results[t], "somq") for t in _LOW_DIM},
        "cells": grid.observation_bins ** 2,
        "entries": grid.action_bins ** 20 * grid.observation_bins ** 2,
        "somq20": _final(results["reach20"], "somq"),
        "random20": results["reach20"]["random_action_error"],
        "cost": {task: {k: np.median(v["seconds_per_sample"]) for k, v in results[task]["learners"].items()}
                 for task in TASKS},
    }


def _claims(m: dict) -> list[Claim]:
    ratios, entries = m["ratios"], m["entries"]
    return [
        Claim("Discussion: where the action space is low-dimensional, it may be easier to hardwire fixed actions "
              "at regular intervals and use standard Q-learning.",
              "after the same samples, the fixed grid's median error is "
              + ", ".join(f"{fmt(ratios[t], 2)} x SOM-Q's on {t}" for t in _LOW_DIM) + ".",
              all(r <= 1.1 for r in ratios.values()), "the grid's error at most 1.1 x SOM-Q's on both tasks"),
        Claim("Fig. 11: with 20 joint angles it is infeasible to populate the action space with enough a priori "
              "fixed actions; SOM-Q's adaptive action map learns the task.",
              f"even 2 values per angle over the {m['cells']} observation cells make {entries:,} table entries "
              f"(the limit is {MAX_TABLE_ENTRIES:,}); SOM-Q's 50 action units reach a median error "
              f"{fmt(m['somq20'], 2)} (random actions {fmt(m['random20'], 2)}).",
              entries > MAX_TABLE_ENTRIES and m["somq20"] < m["random20"] / 2,
              "no fixed grid fits, and SOM-Q's error below half the random actions'"),
    ]


def _notes(results: dict[str, dict], m: dict, seeds: int) -> list[str]:
    notes = []
    for task, result in results.items():
        notes += ["", f"`{task}`: median greedy error over {seeds} seed(s) on the same "
                  f"{result['observations']} fresh observations (random actions score "
                  f"{fmt(result['random_action_error'], 2)}); full data in `peers/{task}/compare.json`.", "",
                  *table(result), "", f"Time to a greedy error on `{task}` (training wall time, median over seeds):",
                  "", *time_to_error(result)]
    for task, cost in m["cost"].items():
        notes += ["", f"Cost per sample on `{task}`: TD3 {cost['td3'] / cost['somq']:.3g} x and SAC "
                  f"{cost['sac'] / cost['somq']:.3g} x SOM-Q's (same run, same machine)."]
    return notes


def report(ctx: Context, trained: Trained) -> Section:
    """Every learner on reach2, reach20 and throw_distance: error against samples and wall time, and the
    time each takes to reach a greedy error of 0.05, 0.02 and 0.01."""
    results, budgets, seeds, peer_samples = trained.results, trained.budgets, trained.seeds, trained.peer_samples
    m = measure(results)
    section = Section("peers", "Peers: SOM-Q beside a fixed action grid, TD3 and SAC (Stable-Baselines3)")
    section.figures += [ctx.out_dir / "peers" / task / "compare.png" for task in TASKS]
    section.notes += _notes(results, m, seeds)
    section.claims += _claims(m)
    section.choices += [
        f"Budgets: somarm's learners train for "
        f"{', '.join(f'{fmt(n)} samples on {t}' for t, n in budgets.items())}"
        f"{'' if ctx.quick else ' (the tasks default run lengths)'}, TD3 and SAC for "
        f"{peer_samples} samples (each costs a gradient step); {seeds} seed(s), the same for every learner.",
        "TD3 and SAC use Stable-Baselines3's defaults (MlpPolicy, torch on one thread) through `somarm.peers.gym`, "
        "TD3 with Gaussian action noise of sd 0.1 on its [-1, 1] actions (SB3's TD3 adds none by default); every "
        "setting is written into each `compare.json`.",
        "SOM-Q+ is the task's `+` preset (`table1+` on the arms, `table5+` on the throw) with the interpolated "
        "response (`somarm.learners.interpolation`), trained for the same samples as SOM-Q.",
        "The tabular learner: 16 cells per observation dimension, 16 actions per action dimension, sample-mean Q, "
        "epsilon = 1/(t/1000 + 1) (as SOM-Q's p in Table 1).",
        "Error is minus the mean reward on the same fresh observations for every learner (the evaluation stream).",
    ]
    return section


#: The comparison part; it declares no lockstep groups (``groups`` None): its comparisons run one seed
#: after another and keep only their numbers, so its memory does not grow with ``--seeds``.
peers = Experiment(None, train, report)
