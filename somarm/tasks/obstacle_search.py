"""Yardsticks for ``reach2_obstacle``: the shortest path by search, a distance-greedy and a random policy.

All three act through the task's own physics (``Obstacle.advance``), so they measure the task the
learner faces. The shortest path is searched over a fine grid of the continuous action box
(``moves``: 7 x 7 target changes by default, corners, edges and the null move among them), without
merging states: every node of the search is a whole sequence of moves integrated from the start,
velocities and contacts included. The search is a beam search (the ``beam`` most promising nodes
of each depth are expanded) guided by the joint-space distance to the goal around the wall
(``JointField``); every path it returns has been replayed through ``Obstacle.run_episodes`` and
reaches the goal in the steps it says.
"""

from __future__ import annotations

import functools

import numpy as np

from somarm.protocols import EpisodicTask
from somarm.tasks.obstacle_geometry import fingertips, touches_wall

#: The task searched: a ``somarm.tasks.obstacle.Obstacle`` (not imported: the task imports this module
#: for its shortest paths).
Obstacle = EpisodicTask

__all__ = ["moves", "JointField", "joint_field", "shortest_paths", "replay", "distance_greedy_policy",
           "random_policy"]

#: Cells per joint of the joint-space grid over [-pi, pi]^2 that guides the search (0.04 rad each).
_CELLS = 160


def moves(max_step: float, per_joint: int = 7) -> np.ndarray:
    """A grid of target changes over the action box, ``(per_joint ** 2, 2)``: ``per_joint`` values from
    ``-max_step`` to ``max_step`` per joint (odd: the null move included)."""
    grid = np.linspace(-max_step, max_step, per_joint)
    return np.stack(np.meshgrid(grid, grid, indexing="ij"), axis=-1).reshape(-1, 2)


@functools.lru_cache(maxsize=1)
def _free_cells() -> tuple[np.ndarray, np.ndarray]:
    """The joint-space grid's cell centres ``(_CELLS,)`` and which cells are clear of the wall ``(_CELLS, _CELLS)``."""
    centres = np.linspace(-np.pi, np.pi, _CELLS, endpoint=False) + np.pi / _CELLS
    poses = np.stack(np.meshgrid(centres, centres, indexing="ij"), axis=-1)
    return centres, ~touches_wall(poses)


class JointField:
    """Joint-space steps to a goal around the wall: a breadth-first wave over the grid's clear cells.

    ``cells[i, j]`` is the fewest king moves (one cell in each joint at most) from cell ``(i, j)`` to a
    cell whose fingertip is within the tolerance of the goal, through clear cells; a pose never
    moves across the wall. It ignores the servos' lag, so it guides the search but bounds nothing.
    """

    def __init__(self, goal: np.ndarray, tolerance: float):
        centres, free = _free_cells()
        self.cell = float(centres[1] - centres[0])
        tips = _grid_fingertips()
        reached = free & (np.linalg.norm(tips - np.asarray(goal), axis=-1) < tolerance)
        cells = np.full(free.shape, np.inf)
        cells[reached] = 0
        front, k = reached, 0
        while front.any():
            k += 1
            padded = np.pad(front, 1)
            near = np.zeros_like(front)
            for di in (0, 1, 2):
                for dj in (0, 1, 2):
                    near |= padded[di:di + front.shape[0], dj:dj + front.shape[1]]
            front = near & free & ~reached
            cells[front] = k
            reached |= front
        self.cells = cells

    def radians(self, angles: np.ndarray) -> np.ndarray:
        """Joint-space path length (rad, king moves) from joint angles ``(..., 2)`` to the goal; inf if walled off."""
        index = np.clip(((np.asarray(angles) + np.pi) / self.cell).astype(int), 0, _CELLS - 1)
        return self.cells[index[..., 0], index[..., 1]] * self.cell


@functools.lru_cache(maxsize=1)
def _grid_fingertips() -> np.ndarray:
    centres, _ = _free_cells()
    return fingertips(np.stack(np.meshgrid(centres, centres, indexing="ij"), axis=-1))


def joint_field(goal: np.ndarray, tolerance: float) -> JointField:
    """The ``JointField`` of ``goal`` (x, y) for the given tolerance."""
    return JointField(goal, tolerance)


def replay(task: Obstacle, starts: np.ndarray, plans: list[np.ndarray | None]) -> dict[str, np.ndarray]:
    """``task.run_episodes`` of fixed move sequences: plan k ``(n_k, 2)`` from start k ``(4,)``, then null moves.

    Returns:
      ``run_episodes``'s answer (success, length, returns), one episode per plan (None: null moves only).
    """
    limit = task.params.step_limit
    table = np.zeros((len(starts), limit, 2))
    for k, plan in enumerate(plans):
        if plan is not None:
            table[k, :min(len(plan), limit)] = plan[:limit]
    step = iter(range(limit))
    return task.run_episodes(lambda observations: table[:, next(step)], starts)


#: Children a depth refines per start (those nearest the goal), if nearer than _NEAR x the tolerance.
_REFINED, _NEAR = 4, 3.0


def _refine(task: Obstacle, qpos: np.ndarray, qvel: np.ndarray, actions: np.ndarray, goal: np.ndarray,
            rounds: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A pattern search of the move from each state ``(n, 2)``, starting at ``actions`` ``(n, 2)``, that ends
    nearest ``goal``: each round tries a step up and down in each joint and halves the step where none helps.

    Returns:
      The moves, their distances to the goal ``(n,)``, and the states after them.
    """
    low, high = task.action_low, task.action_high
    step = np.full(len(actions), (high[0] - low[0]) / 12)
    best = actions.copy()
    q, v = task.advance(qpos, qvel, best)
    distance = task.distances(q, goal)
    signs = np.array([[1, 0], [-1, 0], [0, 1], [0, -1]], dtype=float)
    for _ in range(rounds):
        tried = np.clip(best[:, None, :] + step[:, None, None] * signs[None], low, high).reshape(-1, 2)
        q_new, v_new = task.advance(np.repeat(qpos, 4, axis=0), np.repeat(qvel, 4, axis=0), tried)
        d_new = task.distances(q_new, goal).reshape(-1, 4)
        j = np.argmin(d_new, axis=1)
        pick = np.arange(len(best)) * 4 + j
        gain = d_new[np.arange(len(best)), j] < distance
        best[gain] = tried[pick[gain]]
        q[gain], v[gain], distance[gain] = q_new[pick[gain]], v_new[pick[gain]], d_new[np.arange(len(best)), j][gain]
        step[~gain] /= 2
    return best, distance, q, v


def shortest_paths(task: Obstacle, starts: np.ndarray, *, beam: int = 8, per_joint: int = 7,
                   max_depth: int | None = None) -> dict[str, object]:
    """The shortest path found from each start ``(m, 4)`` (angles and goal) to its goal.

    A beam search over ``moves(max_step, per_joint)``, all starts in one batch: each depth integrates
    every kept node's moves from its own state (angles and velocities, as the task does), stops a
    start at the first depth whose node reaches the goal, and keeps the ``beam`` nodes nearest the
    goal in joint space (``JointField``; the fingertip distance breaks ties). The plans found are
    replayed through ``task.run_episodes``; the lengths returned are the replay's.

    Args:
      task: the task (its parameters and physics).
      starts: start observations ``(m, 4)``.
      beam: nodes kept per depth and start (more: slower, and a path as short or shorter).
      per_joint: move values per joint (odd).
      max_depth: give up after this many steps (default: the task's step limit).

    Returns:
      ``{"length": (m,) steps (the step limit where none is found), "found": (m,) bool,
      "plans": list of (length, 2) moves or None}``.
    """
    starts = np.asarray(starts, dtype=np.float64).reshape(-1, 4)
    options = moves(task.params.max_step, per_joint)
    k, tolerance = len(options), task.params.tolerance
    fields = [joint_field(start[2:], tolerance) for start in starts]
    nodes = [(start[None, :2], np.zeros((1, 2)), np.zeros((1, 0, 2))) for start in starts]
    plans: list[np.ndarray | None] = [None] * len(starts)
    for _ in range(max_depth or task.params.step_limit):
        active = [i for i, plan in enumerate(plans) if plan is None]
        if not active:
            break
        qpos = np.concatenate([np.repeat(nodes[i][0], k, axis=0) for i in active])
        qvel = np.concatenate([np.repeat(nodes[i][1], k, axis=0) for i in active])
        tried = np.concatenate([np.tile(options, (len(nodes[i][0]), 1)) for i in active])
        new_q, new_v = task.advance(qpos, qvel, tried)
        offset = 0
        for i in active:
            n = len(nodes[i][0]) * k
            q, v, a = new_q[offset:offset + n], new_v[offset:offset + n], tried[offset:offset + n]
            history = np.concatenate([np.repeat(nodes[i][2], k, axis=0), a[:, None]], axis=1)
            offset += n
            distances = task.distances(q, starts[i, 2:])
            if not (distances < tolerance).any():
                near = np.argsort(distances)[:_REFINED]
                near = near[distances[near] < _NEAR * tolerance]
                if near.size:  # close calls: the last move refined over the continuous box
                    parents = near // k
                    moved, distances_near, q_near, v_near = _refine(
                        task, nodes[i][0][parents], nodes[i][1][parents], a[near], starts[i, 2:])
                    better = distances_near < distances[near]
                    q[near[better]], v[near[better]] = q_near[better], v_near[better]
                    history[near[better], -1] = moved[better]
                    distances[near[better]] = distances_near[better]
            if (distances < tolerance).any():
                plans[i] = history[int(np.argmin(distances))]
                continue
            keep = np.lexsort((distances, fields[i].radians(q)))[:beam]
            nodes[i] = (q[keep], v[keep], history[keep])
    episodes = replay(task, starts, plans)
    found = episodes["success"] & np.array([plan is not None for plan in plans])
    return {"length": episodes["length"], "found": found, "plans": plans}


def distance_greedy_policy(task: Obstacle, per_joint: int = 7):
    """A policy that takes, of ``moves(max_step, per_joint)``, the one whose step from rest ends nearest
    the goal: it maximises the next reward only, what a learner with gamma = 0 can at best learn.

    Its moves are those of a straight approach where nothing is in the way, so its success rate says
    how many goals a straight move reaches.
    """
    options = moves(task.params.max_step, per_joint)

    def policy(observations: np.ndarray) -> np.ndarray:
        rewards = task.evaluate(observations[:, None, :], options[None, :, :])  # (n, moves)
        return options[np.argmax(rewards, axis=1)]

    return policy


def random_policy(task: Obstacle, rng: np.random.Generator):
    """A policy that draws every target change uniformly from the action box."""

    def policy(observations: np.ndarray) -> np.ndarray:
        return rng.uniform(task.action_low, task.action_high, (len(observations), 2))

    return policy
