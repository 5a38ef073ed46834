"""MuJoCo's work in the batched flights, for the benchmarks: a clock of the native rollouts, and the
chunked design the tasks' staircase replaced, kept as the point of comparison.

``RolloutClock`` counts the thread CPU spent inside ``mujoco.rollout`` (every thread's) and the
body-steps MuJoCo took (projectiles in the model times steps); ``us_per_projectile_step`` divides
the CPU by the RK4 steps the throws need (each throw's own model steps), so a design that steps
bodies it does not need, or pays a fixed cost per model step more often, reads higher.

The chunked design: a batch sorted by flight length and cut into chunks of similar flights (the
cheapest cut by dynamic programming under a cost model: per chunk a native call, then its longest
flight's steps, each a fixed cost plus one per projectile of its model); each chunk flew side by
side in a model of its size, every body to the chunk's longest flight, in one ``mujoco.rollout``.
The flights themselves are the tasks' (the same models, steps, time scaling and landing location),
so both designs land every throw at the same x, bit for bit (tested): only the MuJoCo work differs.
``scripts/bench_floor.py`` times the two side by side.
"""

from __future__ import annotations

import threading
import time
import types
from typing import NamedTuple

import numpy as np

from somarm.tasks import flight

__all__ = ["RolloutClock", "ChunkedPlan", "cut", "plan", "fly", "fly_sorted"]


class RolloutClock:
    """Within the block, the thread CPU inside the flights' native rollouts and the body-steps they take.

    Attributes:
      seconds: thread CPU seconds inside ``mujoco.rollout`` (summed over threads).
      body_steps: projectiles in the model times steps, over every rollout.
    """

    def __init__(self) -> None:
        self.seconds = 0.0
        self.body_steps = 0
        self._lock = threading.Lock()
        self._module = flight.mj_rollout

    def __enter__(self) -> RolloutClock:
        module = self._module

        def timed(models, *args, nstep, **kwargs):
            start = time.thread_time()
            try:
                return module.rollout(models, *args, nstep=nstep, **kwargs)
            finally:
                spent = time.thread_time() - start
                with self._lock:
                    self.seconds += spent
                    self.body_steps += nstep * (models[0].nv // 2)

        flight.mj_rollout = types.SimpleNamespace(rollout=timed)
        return self

    def __exit__(self, *exc) -> None:
        flight.mj_rollout = self._module

    def us_per_projectile_step(self, needed: float) -> float:
        """Microseconds of MuJoCo per RK4 step the throws need (``needed``: their model steps summed)."""
        return self.seconds / needed * 1e6

#: The chunked design's cost of a chunk's native call, in projectile-steps, and its most throws per model.
_CALL_COST = 40.0
_CAP = 256


class ChunkedPlan(NamedTuple):
    """A batch cut into chunks: the sorting permutation, the sorted throws and the chunks ``(start, stop)``."""

    order: np.ndarray
    flat: tuple  #: ux, uy, k, W, scale and model steps, in flight order (as ``flight._plan``)
    chunks: list


def cut(steps: np.ndarray) -> list[tuple[int, int]]:
    """The chunks ``(start, stop)`` of flights of ascending model steps (``flight._model_steps``):
    the tasks' cut into chunks of similar flights, under the chunked design's cost per chunk."""
    return flight._chunks(steps, _CAP, _CALL_COST)


def plan(ux, uy, Fr, W, M, *, G: float = 0.05, tolerance: float = flight.DEFAULT_TOLERANCE) -> ChunkedPlan:
    """The chunks of a batch (1-D arrays of one length), the flights sorted as the tasks sort them."""
    tasks_plan = flight._plan(ux, uy, Fr, W, M, G=G, tolerance=tolerance, workers=1)
    return ChunkedPlan(tasks_plan.order, tasks_plan.flat, cut(tasks_plan.flat[-1]))


def fly_sorted(flat: tuple, G: float = 0.05) -> np.ndarray:
    """``fly`` of throws already sorted by flight length (``flight._plan``'s ``flat``), cut here."""
    return fly(ChunkedPlan(np.arange(len(flat[0])), flat, cut(flat[-1])), G)


def fly(chunked: ChunkedPlan, G: float = 0.05) -> np.ndarray:
    """Landing x of a planned batch in flight order, chunk by chunk in this thread.

    Raises:
      RuntimeError: a throw is still in the air after its chunk's steps.
    """
    ux, uy, k, W, scale, steps = chunked.flat
    out = np.empty(len(ux))
    for a, b in chunked.chunks:
        m = b - a
        batch = flight._batch_for_thread(flight._model_size(m), G)
        start = np.zeros(batch.n_state)
        start[batch.qvel:batch.qvel + 2 * m:2] = ux[a:b]
        start[batch.qvel + 1:batch.qvel + 2 * m:2] = uy[a:b] / scale[a:b]
        rate = scale[a:b] * k[a:b]
        rows = batch.roll(start, int(steps[b - 1]), rate, -rate * W[a:b])
        if flight._land_segment(rows, m, batch.qvel, G, np.arange(a, b), scale, out, np.empty(m, np.int64)):
            raise RuntimeError(f"projectile(s) still flying after {int(steps[b - 1])} steps")
    return out
