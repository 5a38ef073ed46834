"""A run's ``summary.json``: its settings, steps, time and final rewards, and a greedy evaluation."""

from __future__ import annotations

from typing import Any

import numpy as np

from somarm import __version__
from somarm.run.group import RunResult
from somarm.run.loop import final_blocks, final_rewards

__all__ = ["greedy_summary", "summary"]


def greedy_summary(result: RunResult, n_observations: int = 1000) -> dict[str, Any]:
    """The summary keys of a greedy evaluation on fresh observations (seeded by the run's seed).

    A failed evaluation gives ``{"greedy_error": message}`` instead, so the run is still written.
    """
    from somarm.run import evaluation

    if result.steps_done == 0:
        return {}
    try:
        greedy = evaluation.evaluate_greedy(result.learner, result.task, n_observations=n_observations,
                                            seed=result.config.seed)
    except ValueError as exc:
        return {"greedy_error": str(exc)}
    out = {
        "greedy_mean_reward": float(greedy.mean()),
        "greedy_sd_reward": float(greedy.std()),
        "greedy_observations": n_observations,
    }
    if result.task.episodic:  # whole greedy episodes from the task's start poses
        episodes = evaluation.greedy_episodes(result.learner, result.task, n_episodes=100,
                                              seed=result.config.seed)
        lengths = episodes["mean_length"][np.isfinite(episodes["mean_length"])]
        out.update({
            "greedy_success_rate": float(episodes["success_rate"].mean()),
            "greedy_mean_episode_length": float(lengths.mean()) if lengths.size else None,
            "greedy_episodes": 100,
        })
    return out


def _number_or_none(x: float) -> float | None:
    """JSON has no NaN: a mean over nothing is written as null."""
    return float(x) if np.isfinite(x) else None


def summary(result: RunResult, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """The ``summary.json`` of a run: settings, steps, time, final rewards, then ``extra``."""
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
