"""Rows of ``somarm bench tasks`` for the driven arms: actuated reach and reach2_obstacle steps.

An actuated reach evaluation integrates the servos for the settle time (20 timesteps at the
default 0.2 s); a reach2_obstacle step integrates one control interval (30 timesteps) with contacts.
Each is timed at the experiment's batch size (the trials of the task's preset) and at a large
batch, where ``mujoco.rollout`` shares the work between threads.
"""

from __future__ import annotations

import time

import numpy as np

from somarm import tasks

__all__ = ["ROWS", "measure_row", "print_rows"]

#: (label, task, task parameters, experiment batch, large batch)
ROWS: tuple[tuple[str, str, dict, int, int], ...] = (
    ("reach2 actuated", "reach2", {"dynamics": "actuated"}, 20, 4000),
    ("reach20 actuated", "reach20", {"dynamics": "actuated"}, 20, 1000),
    ("reach2_obstacle step", "reach2_obstacle", {}, 10, 4000),
)


def measure_row(name: str, params: dict, n_trials: int, *, repeats: int, steps: int) -> float:
    """Evaluations (reach) or trial-steps (obstacle) per second of ``reset`` + ``step`` at ``n_trials``."""
    task = tasks.make(name, n_trials=n_trials, **params)
    rng = np.random.default_rng(0)
    actions = rng.uniform(task.action_low, task.action_high, (steps, n_trials, task.action_low.size))
    task.reset()
    task.step(actions[0])  # models and thread pools are built here, outside the timing
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for a in actions:
            task.reset()
            task.step(a)
        best = min(best, time.perf_counter() - start)
    return steps * n_trials / best


def print_rows(*, quick: bool, repeats: int) -> None:
    """Print one line per driven row: the rate at the experiment's batch and at a large batch."""
    print(f"\n{'driven arms':22s} {'batch':>6s} {'evals/s':>10s} {'large batch':>11s} {'evals/s':>10s}")
    for label, name, params, small, large in ROWS:
        large = large // 10 if quick else large
        steps_small, steps_large = (3, 1) if quick else (40, 3)
        rate_small = measure_row(name, params, small, repeats=repeats, steps=steps_small)
        rate_large = measure_row(name, params, large, repeats=repeats, steps=steps_large)
        print(f"{label:22s} {small:6d} {rate_small:10.3g} {large:11d} {rate_large:10.3g}", flush=True)
    print("actuated reach: one evaluation integrates the settle time (0.2 s, 20 timesteps); "
          "reach2_obstacle: one trial-step integrates 0.3 s (30 timesteps) with contacts.")
