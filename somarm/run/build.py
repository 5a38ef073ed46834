"""Building a run: its task and learner from a resolved ``RunConfig``, after a memory check.

Everything here reads typed values: the resolved config's ``learner_config`` and ``task_params``.
"""

from __future__ import annotations

import numpy as np

from somarm.protocols import BatchedTask, Learner
from somarm.run.config import RunConfig
from somarm.validation import check_memory

__all__ = ["make_task", "make_learner", "make", "memory_needs", "check_memory_needs"]

#: Memory per trial for its random streams (generators and buffers), task and learner together.
_STREAM_BYTES_PER_TRIAL = 4096


def make_task(config: RunConfig, trial_ids: np.ndarray | None = None) -> BatchedTask:
    """The batched task of a (resolved) run config, for its trials or the given ``trial_ids``."""
    from somarm import tasks

    ids = config.trial_ids_array() if trial_ids is None else trial_ids
    return tasks.make(config.task, n_trials=len(ids), seed=config.seed, trial_ids=ids, backend=config.backend,
                      **config.task_params)


def make_learner(config: RunConfig, task: BatchedTask) -> Learner:
    """The learner of a (resolved) run config, reading the task's observation and action boxes (bounds
    and periodic action dimensions)."""
    from somarm import learners

    return learners.make(
        config.learner,
        config.learner_config,
        observation_low=task.observation_low,
        observation_high=task.observation_high,
        action_low=task.action_low,
        action_high=task.action_high,
        action_periodic=task.action_periodic,
        n_trials=config.n_trials,
        seed=config.seed,
        trial_ids=config.trial_ids_array(),
    )


def make(config: RunConfig) -> tuple[BatchedTask, Learner]:
    """Make the task and the learner of a (resolved) run config."""
    check_memory_needs([config])
    task = make_task(config)
    return task, make_learner(config, task)


def memory_needs(configs: list[RunConfig]) -> tuple[str, float]:
    """What (resolved) configs trained in one group need, ``(description, bytes)``, before anything is built.

    A lower bound (one observation and one action dimension) for the learners, plus the learning
    curves (two floats per block and trial) and about 4 KiB per trial for the task's and the
    learner's random streams (measured: 20,000 reach2 trials); each learner checks its exact need
    again when built. The seed plays no part: a group at N seeds needs N times one seed's bytes.

    Raises:
      ValueError: an unknown learner kind, or settings a kind refuses outright (one line).
    """
    from somarm import learners

    total, described = 0.0, []
    for config in configs:
        what, n_bytes = learners.memory_needed(config.learner, config.learner_config, n_trials=config.n_trials,
                                               obs_dim=1, action_dim=1)
        total += n_bytes + (16.0 * (config.n_steps // config.block) + _STREAM_BYTES_PER_TRIAL) * config.n_trials
        described.append(what)
    return f"{'; '.join(described)}, over {configs[0].n_steps} steps", total


def check_memory_needs(configs: list[RunConfig]) -> None:
    """Refuse, before the task or a learner is built, runs that cannot fit in memory (``memory_needs``).

    Raises:
      ValueError: one line naming the settings and the size.
    """
    what, total = memory_needs(configs)
    check_memory(what, total, "use smaller maps, fewer trials or fewer steps (or a larger --block)")
