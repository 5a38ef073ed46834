"""A run's ``summary.json``: its settings, steps, time and final rewards, and a greedy evaluation."""

from __future__ import annotations

import signal
import time
from typing import Any

import numpy as np

from somarm import __version__
from somarm.protocols import BatchedTask, Learner
from somarm.run.group import RunResult
from somarm.run.loop import final_blocks, final_rewards

__all__ = ["GREEDY_EPISODES", "greedy_measures", "greedy_cost", "greedy_summary", "summary"]

#: Greedy episodes per trial of an episodic task, from the task's start distribution.
GREEDY_EPISODES = 100


def greedy_measures(learner: Learner, task: BatchedTask, *, seed: int, n_observations: int = 1000,
                    shortest: bool = True) -> dict[str, Any]:
    """The greedy keys of ``summary.json`` for a trained learner on its task.

    A one-step task scores the greedy action on ``n_observations`` fresh observations:
    ``greedy_mean_reward`` and ``greedy_sd_reward`` (mean over observations per trial, then mean
    and sd over trials), ``greedy_observations``. An episodic task (``task.episodic``) runs
    ``GREEDY_EPISODES`` whole greedy episodes per trial instead, since one step from rest says
    nothing of where an episode goes: ``greedy_mean_return`` and ``greedy_sd_return`` (the
    undiscounted return per episode, mean over episodes per trial, then mean and sd over trials),
    ``greedy_success_rate`` (episodes reaching the goal, over all trials; a task with a goal only),
    ``greedy_episodes_cut`` and ``greedy_episode_cap`` (where the task's cap on greedy episodes cut
    some before their own end, as a Gymnasium task's ``evaluation_steps`` does: how many, over all
    trials, and the cap), and
    ``greedy_mean_episode_length`` (steps over all episodes; on a task with a goal, an episode that
    does not reach it counting at the step limit), ``greedy_episodes``, and beside the greedy length ``shortest_mean_episode_length``: the
    mean over the same episodes of the shortest path from each start (``task.shortest_lengths``; a search
    of some seconds, left out with ``shortest=False``, as a sweep, which ranks by the return, does).

    Raises:
      ValueError: the learner cannot act on the task (the caller reports it).
    """
    from somarm.run import evaluation

    if task.episodic:
        episodes = evaluation.greedy_episodes(learner, task, n_episodes=GREEDY_EPISODES, seed=seed)
        measures = {
            "greedy_mean_return": float(episodes["mean_return"].mean()),
            "greedy_sd_return": float(episodes["mean_return"].std()),
            "greedy_mean_episode_length": float(episodes["mean_length"].mean()),
            "greedy_episodes": GREEDY_EPISODES,
        }
        if "success_rate" in episodes:  # a task with a goal says whether each episode reached it
            measures["greedy_success_rate"] = float(episodes["success_rate"].mean())
        if "cut" in episodes and episodes["cut"].any():  # the returns are over the cap's steps, not whole episodes
            measures["greedy_episodes_cut"] = int(episodes["cut"].sum())
            measures["greedy_episode_cap"] = int(episodes["lengths"][episodes["cut"]].max())
        if shortest and task.has_shortest_paths:
            lengths = evaluation.shortest_lengths(task, n_episodes=GREEDY_EPISODES, seed=seed)
            measures["shortest_mean_episode_length"] = float(lengths.mean())
        return measures
    greedy = evaluation.evaluate_greedy(learner, task, n_observations=n_observations, seed=seed)
    return {
        "greedy_mean_reward": float(greedy.mean()),
        "greedy_sd_reward": float(greedy.std()),
        "greedy_observations": n_observations,
    }


def greedy_cost(greedy: dict[str, Any]) -> tuple[float, float]:
    """What a run is ranked by, lower is better, and its sd over trials, from ``greedy_measures``'s keys.

    Minus the greedy return of an episodic task (its steps plus the distances along the way), minus
    the greedy one-step reward of the others (the distance to the goal, or the miss of a throw).

    Raises:
      KeyError: neither a return nor a one-step reward (a failed or missing evaluation).
    """
    if "greedy_mean_return" in greedy:
        return -greedy["greedy_mean_return"], greedy["greedy_sd_return"]
    return -greedy["greedy_mean_reward"], greedy["greedy_sd_reward"]


def greedy_summary(result: RunResult, n_observations: int = 1000, *, shortest: bool = True) -> dict[str, Any]:
    """The summary keys of the run's greedy evaluation (``greedy_measures``, seeded by the run's seed;
    ``shortest``: with an episodic task's shortest paths).

    A failed evaluation gives ``{"greedy_error": message}`` instead, so the run is still written. So
    does one that Ctrl-C or SIGTERM cuts short (``stopping.cut_short_by_signals``: the signal is then
    handed on, so a command that holds signals back while it writes ends as interrupted after writing),
    with ``"greedy_cut": true``; the run then counts as interrupted (``result.interrupted``), so that it
    does not replace an earlier run in its folder.
    """
    from somarm.run.stopping import cut_short_by_signals

    if result.steps_done == 0:
        return {}

    def measure() -> dict[str, Any]:
        try:
            return greedy_measures(result.learner, result.task, seed=result.config.seed,
                                   n_observations=n_observations, shortest=shortest)
        except ValueError as exc:
            return {"greedy_error": str(exc)}

    started = time.perf_counter()
    measures, signum = cut_short_by_signals(measure)
    if signum:
        result.interrupted = True
        return {"greedy_error": f"stopped by {signal.Signals(signum).name} after "
                                f"{time.perf_counter() - started:.1f} s: the trained run is written without it "
                                "(somarm evaluate scores it)", "greedy_cut": True}
    return measures


def _number_or_none(x: float) -> float | None:
    """JSON has no NaN: a mean over nothing is written as null."""
    return float(x) if np.isfinite(x) else None


def summary(result: RunResult, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """The ``summary.json`` of a run: settings, steps, time, final rewards, then ``extra``.

    ``final_mean_reward`` and ``final_sd_reward`` are the training reward over the last
    ``final_window_steps`` steps (a tenth of the run, at most 1000 steps, in whole blocks): each
    trial's mean over that window, then their mean and sd over trials. The progress line's ``mean
    reward, last block`` is the last block's alone, so the two agree only where the window is one block.
    """
    config = result.config
    window = min(1000, max(config.block, config.n_steps // 10))
    final = final_rewards(result.block_means, config.block, window)
    window = final_blocks(len(result.block_means), config.block, window) * config.block
    return {
        "task": config.task,
        "learner": config.learner,
        "preset": config.preset,
        "seed": config.seed,
        "n_trials": config.n_trials,
        "steps": result.steps_done,
        "steps_requested": config.n_steps,
        "interrupted": result.interrupted,
        "wall_time_s": round(result.wall_time, 3),
        "final_window_steps": window,
        "final_mean_reward": _number_or_none(np.mean(final)),
        "final_sd_reward": _number_or_none(np.std(final)),
        "somarm_version": __version__,
        **(extra or {}),
    }
