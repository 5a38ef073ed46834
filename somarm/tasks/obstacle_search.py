"""Yardsticks for ``reach2_obstacle``: the shortest path by search, a distance-greedy and a random policy.

All three use the task's own physics (``Obstacle.advance``), so they measure the task the learner
faces. The search moves only by the nine corner, edge and null moves of the action box
(``obstacle.moves``); a learner with continuous actions could at best tie it.
"""

from __future__ import annotations

import numpy as np

from somarm.tasks.obstacle import Obstacle, moves

__all__ = ["shortest_path", "distance_greedy_policy", "random_policy"]


def shortest_path(task: Obstacle, start: np.ndarray, *, cell: float = 0.05,
                  max_depth: int | None = None) -> np.ndarray | None:
    """The fewest steps from rest at ``start`` to the goal, by breadth-first search over the nine moves.

    States closer than ``cell`` rad in both angles are merged (and their velocities ignored), which
    keeps the search to a few thousand states; the path returned is replayed exactly by the task.

    Args:
      task: the task (its parameters and physics).
      start: start angles ``(2,)``.
      cell: merge radius in radians; smaller is slower and can only find a path as short or shorter.
      max_depth: give up after this many steps (default: the task's step limit).

    Returns:
      The moves ``(n_steps, 2)`` of a shortest path, or None if none is found within ``max_depth``.
    """
    options = moves(task.params.max_step)
    depth_limit = max_depth or task.params.step_limit
    start = np.asarray(start, dtype=np.float64)
    frontier_q, frontier_v = start[None], np.zeros((1, 2))
    plans = [np.zeros((0, 2))]
    seen = {tuple(np.round(start / cell).astype(int))}
    for _ in range(depth_limit):
        k = len(options)
        q = np.repeat(frontier_q, k, axis=0)
        v = np.repeat(frontier_v, k, axis=0)
        tried = np.tile(options, (len(frontier_q), 1))
        new_q, new_v = task.advance(q, v, tried)
        reached = task.distances(new_q) < task.params.tolerance
        if reached.any():
            i = int(np.flatnonzero(reached)[0])
            return np.vstack([plans[i // k], tried[i]])
        keep_q, keep_v, keep_plans = [], [], []
        for i in range(len(new_q)):
            key = tuple(np.round(new_q[i] / cell).astype(int))
            if key not in seen:
                seen.add(key)
                keep_q.append(new_q[i])
                keep_v.append(new_v[i])
                keep_plans.append(np.vstack([plans[i // k], tried[i]]))
        if not keep_q:
            return None
        frontier_q, frontier_v, plans = np.array(keep_q), np.array(keep_v), keep_plans
    return None


def distance_greedy_policy(task: Obstacle):
    """A policy that takes, of the nine moves, the one whose step from rest ends nearest the goal.

    It maximises the next reward only: what a learner with gamma = 0 can at best learn.
    """
    options = moves(task.params.max_step)

    def policy(angles: np.ndarray) -> np.ndarray:
        rewards = task.evaluate(angles[:, None, :], options[None, :, :])  # (n, 9)
        return options[np.argmax(rewards, axis=1)]

    return policy


def random_policy(task: Obstacle, rng: np.random.Generator):
    """A policy that draws every target change uniformly from the action box."""

    def policy(angles: np.ndarray) -> np.ndarray:
        return rng.uniform(task.action_low, task.action_high, (len(angles), 2))

    return policy
