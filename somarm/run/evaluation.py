"""Greedy evaluation: any learner with ``predict`` on fresh observations of any batched task."""

from __future__ import annotations

import numpy as np

from somarm.protocols import BatchedTask, EpisodicTask, Learner
from somarm.streams import PURPOSES
from somarm.validation import check_int, check_memory

__all__ = ["evaluation_rng", "evaluate_greedy", "evaluation_bytes", "episode_starts", "greedy_episodes",
           "shortest_lengths"]


def evaluation_rng(seed: int) -> np.random.Generator:
    """The generator for evaluation observations: its own stream, apart from training's."""
    check_int("seed", seed, minimum=0)
    return np.random.Generator(
        np.random.PCG64(np.random.SeedSequence(int(seed), spawn_key=(PURPOSES["evaluation"],)))
    )


def evaluate_greedy(
    learner: Learner, task: BatchedTask, *, n_observations: int = 1000, seed: int = 0
) -> np.ndarray:
    """Mean reward of each trial's greedy policy on the same fresh observations.

    Args:
      learner: a trained learner with ``n_trials`` trials.
      task: a task with the same number of trials (its current phase is used).
      n_observations: fresh observations drawn from the task's distribution (>= 1).
      seed: seed of the evaluation stream (independent of training's streams).

    Returns:
      Mean reward per trial, shape ``(n_trials,)``.
    """
    n_observations = check_int("n_observations", n_observations)
    check_memory(f"{n_observations} fresh observations for {learner.n_trials} trial(s)",
                 evaluation_bytes(learner, n_observations), "give fewer observations")
    observations = task.sample_observations(evaluation_rng(seed), n_observations)
    # A slice of the observations at a time, so that the learner's and the task's working arrays
    # (trials x observations x units) stay small; every observation is scored alone, so the rewards
    # do not depend on the slicing, and their mean is taken over all of them at once.
    size = max(1, _CHUNK_ELEMENTS // learner.n_trials)
    rewards = np.empty((learner.n_trials, n_observations))
    for start in range(0, n_observations, size):
        part = observations[start:start + size]
        batch = np.ascontiguousarray(np.broadcast_to(part, (learner.n_trials, *part.shape)))
        rewards[:, start:start + size] = task.evaluate(batch, learner.predict(batch))
    return rewards.mean(axis=-1)


#: Trial-observation pairs scored at once by ``evaluate_greedy`` (bounds its working memory).
_CHUNK_ELEMENTS = 200_000


def evaluation_bytes(learner: Learner, n_observations: int) -> float:
    """About the memory ``evaluate_greedy`` holds beyond its slices: the observations (float64) and
    every trial's reward for each, twice over while they are made."""
    return 16.0 * n_observations * (learner.observation_low.size + learner.n_trials)


def episode_starts(task: EpisodicTask, n_episodes: int, seed: int) -> np.ndarray:
    """The starts every trial's greedy episodes start from (``task.sample_starts`` on the evaluation
    stream of ``seed``: start observations, or a Gymnasium environment's reset seeds)."""
    return task.sample_starts(evaluation_rng(seed), check_int("n_episodes", n_episodes))


def greedy_episodes(learner: Learner, task: EpisodicTask, *, n_episodes: int = 100, seed: int = 0) -> dict[str, np.ndarray]:
    """Each trial's greedy policy run for whole episodes of a multi-step task (``task.episodic``).

    Every trial starts the same ``n_episodes`` episodes (``task.sample_starts`` from the evaluation
    stream of ``seed``: start poses, or a Gymnasium environment's reset seeds); all ``n_trials x
    n_episodes`` episodes run in one batch.

    Args:
      learner: a trained learner with ``n_trials`` trials.
      task: a multi-step task (``task.episodic``: an ``EpisodicTask``).
      n_episodes: episodes per trial (>= 1).
      seed: seed of the evaluation stream.

    Returns:
      ``{"success_rate", "mean_length", "mean_return"}``, each ``(n_trials,)``: the fraction of
      episodes that reach the goal (only for a task with a goal); the mean steps over all episodes;
      and the mean undiscounted return per episode. On a task with a goal, an episode that never
      reaches it counts at the step limit (where ``run_episodes`` cuts it), so a trial that reaches
      the goal once in 100 episodes has a mean length near the step limit, not the length of its one
      success; on a task without one (a Gymnasium task), an episode's length is where it ended. Also ``"lengths"`` and ``"success"``, ``(n_trials, n_episodes)``:
      every episode's steps and whether it reached the goal; and, for a task that caps its greedy
      episodes below their own end (a Gymnasium task's ``evaluation_steps``), ``"cut"``: whether the
      cap cut each.

    Raises:
      ValueError: a task without whole episodes, or a bad ``n_episodes``.
    """
    if not task.episodic:
        raise ValueError(f"task {task.name} has one-step episodes; greedy episodes need a multi-step task")
    starts = episode_starts(task, n_episodes, seed)
    n_trials = learner.n_trials

    def policy(observations: np.ndarray) -> np.ndarray:
        return learner.predict(observations.reshape(n_trials, n_episodes, -1)).reshape(len(observations), -1)

    episodes = task.run_episodes(policy, np.tile(starts, (n_trials,) + (1,) * (starts.ndim - 1)))
    lengths = episodes["length"].reshape(n_trials, n_episodes)
    out = {
        "mean_length": lengths.mean(axis=1),
        "mean_return": episodes["returns"].reshape(n_trials, n_episodes).mean(axis=1),
        "lengths": lengths,
    }
    if "cut" in episodes:  # the task's cap on greedy episodes cut these before their own end
        out["cut"] = episodes["cut"].reshape(n_trials, n_episodes)
    if "success" in episodes:  # a task with a goal says whether each episode reached it
        out["success"] = episodes["success"].reshape(n_trials, n_episodes)
        out["success_rate"] = out["success"].mean(axis=1)
    return out


#: The shortest paths of the last few evaluation streams: (task, its parameters, episodes, seed) ->
#: lengths. A search is deterministic and costs seconds; runs of one task scored on the same stream
#: (a sweep's points, the two learners of a report) share it.
_SHORTEST: dict[tuple, np.ndarray] = {}


def shortest_lengths(task: EpisodicTask, *, n_episodes: int = 100, seed: int = 0) -> np.ndarray:
    """The fewest steps from each start of ``episode_starts`` to its goal (``task.shortest_lengths``:
    found by search, checked by replay), ``(n_episodes,)``; the same episodes ``greedy_episodes`` runs."""
    key = (task.name, repr(getattr(task, "params", None)), int(n_episodes), int(seed))
    if key not in _SHORTEST:
        if len(_SHORTEST) >= 8:
            _SHORTEST.pop(next(iter(_SHORTEST)))
        _SHORTEST[key] = np.asarray(task.shortest_lengths(episode_starts(task, n_episodes, seed)))
    return _SHORTEST[key].copy()
