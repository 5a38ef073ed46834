"""MuJoCo's work in the batched flights, for the benchmarks: a clock of the native rollouts.

``RolloutClock`` counts the thread CPU spent inside ``mujoco.rollout`` (every thread's) and the
body-steps MuJoCo took (projectiles in the model times steps); ``us_per_projectile_step`` divides
the CPU by the RK4 steps the throws need (each throw's own model steps), so a design that steps
bodies it does not need, or pays a fixed cost per model step more often, reads higher.
"""

from __future__ import annotations

import threading
import time
import types

from somarm.tasks import flight

__all__ = ["RolloutClock"]


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
