"""A training run, owned in one place: its configuration, building, training, summary and folder.

``RunConfig`` (``somarm.run_config``, re-exported here) is the single source of a run's
settings: the ``somarm train`` options, their defaults and help are derived from its fields (as
CleanRL derives its command line from a dataclass), and it is saved as ``config.json``. ``train``/``train_group`` build the task and the
learners once and hand them to the loop in ``somarm.training``; ``write`` and ``load`` own the
run folder::

    result = run.train(RunConfig(task="reach2", n_trials=20))
    run.write(result, "runs/reach2", extra_summary=run.greedy_summary(result))
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from somarm import __version__
from somarm.io import atomic_save_npz, atomic_write_json
from somarm.protocols import BatchedTask, Learner
from somarm.run_config import RunConfig, add_options, from_options, parse_assignments
from somarm.training import StepHook, final_blocks, final_rewards, loop
from somarm.validation import check_int, check_memory

__all__ = [
    "RunConfig",
    "RunResult",
    "add_options",
    "from_options",
    "parse_assignments",
    "make_task",
    "share_lanes",
    "make_learner",
    "make",
    "check_memory_needs",
    "train",
    "train_group",
    "RunGroup",
    "greedy_summary",
    "summary",
    "write",
    "load",
    "task_for",
    "final_rewards",
]


#: Memory per trial for its random streams (generators and buffers), task and learner together.
_STREAM_BYTES_PER_TRIAL = 4096


# -- building -----------------------------------------------------------------------------------
def make_task(config: RunConfig, trial_ids: np.ndarray | None = None) -> BatchedTask:
    """The batched task of a (resolved) run config, for its trials or the given ``trial_ids``."""
    from somarm import tasks

    ids = config.trial_ids_array() if trial_ids is None else trial_ids
    return tasks.make(config.task, n_trials=len(ids), seed=config.seed, trial_ids=ids, backend=config.backend,
                      **tasks.parse_values(config.task_params))


def make_learner(config: RunConfig, task: BatchedTask) -> Learner:
    """The learner of a (resolved) run config, reading the task's observation and action boxes (bounds
    and periodic action dimensions)."""
    from somarm import learners, presets

    learner_config = presets.config_for(config.learner, config.preset).with_overrides(config.overrides)
    return learners.make(
        config.learner,
        learner_config,
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


def check_memory_needs(configs: list[RunConfig]) -> None:
    """Refuse, before the task or a learner is built, runs that cannot fit in memory.

    A lower bound (one observation and one action dimension) for the learners, plus the learning
    curves (two floats per block and trial) and about 4 KiB per trial for the task's and the
    learner's random streams (measured: 20,000 reach2 trials); each learner checks its exact need
    again when built.

    Raises:
      ValueError: one line naming the settings and the size.
    """
    from somarm import presets
    from somarm.learner_base import memory_needed

    total, described = 0.0, []
    for config in configs:
        learner_config = presets.config_for(config.learner, config.preset).with_overrides(config.overrides)
        what, n_bytes = memory_needed(config.learner, learner_config, config.n_trials, 1, 1)
        total += n_bytes + (16.0 * (config.n_steps // config.block) + _STREAM_BYTES_PER_TRIAL) * config.n_trials
        described.append(what)
    check_memory(f"{'; '.join(described)}, over {configs[0].n_steps} steps", total,
                 "use smaller maps, fewer trials or fewer steps (or a larger --block)")


# -- training -----------------------------------------------------------------------------------
@dataclass
class RunResult:
    """What ``train`` returns: the trained learner and its learning curves."""

    config: RunConfig
    learner: Learner
    task: BatchedTask
    block_means: np.ndarray  #: (n_blocks, n_trials) mean reward of each complete block
    block_sq_means: np.ndarray  #: (n_blocks, n_trials) mean squared reward of each block (data spread)
    steps_done: int
    wall_time: float
    interrupted: bool = False
    snapshots: dict[int, dict[str, np.ndarray]] = field(default_factory=dict)
    """Copies of the maps (and Q) of every trial taken after the steps asked for in ``train``."""

    @property
    def steps(self) -> np.ndarray:
        """Step at the end of each recorded block, shape ``(n_blocks,)``."""
        return (np.arange(len(self.block_means)) + 1) * self.config.block


def train(config: RunConfig, *, progress: bool = True, on_step: StepHook | None = None,
          label: str | None = None, snapshots_at: tuple[int, ...] = ()) -> RunResult:
    """Train ``config.n_trials`` trials for ``config.n_steps`` steps.

    Ctrl-C or SIGTERM stops at the end of the current step and returns what was learned so far
    (``interrupted=True``): the caller can still write a valid partial run.

    Args:
      config: the run (defaults are filled in here).
      progress: draw a progress bar with the running mean reward on stderr.
      on_step: called as ``on_step(step, observations, actions, rewards)`` after every step
        (the live viewer); it must be cheap.
      label: progress-bar label (default ``task/learner``).
      snapshots_at: steps after which to copy the maps (``RunResult.snapshots``).

    Returns:
      A ``RunResult``.

    Raises:
      ValueError: a bad setting (before anything is trained).
    """
    return train_group([config], progress=progress, on_step=on_step, label=label, snapshots_at=snapshots_at)[0]


def train_group(configs: list[RunConfig], *, progress: bool = True, on_step: StepHook | None = None,
                label: str | None = None, snapshots_at: tuple[int, ...] = ()) -> list[RunResult]:
    """Train several learners in lockstep, with one physics call per step for all (``RunGroup``).

    The configs share backend, steps and block; those of one task, task parameters and seed share
    one batched task. Each config's trials see the same observations and random numbers as when
    trained alone, so results equal ``train``'s. Comparisons (Figs. 13, 21-24), Fig. 25's four
    experiments and ``reproduce --seeds`` run this way: the physics dominates their cost.

    Returns:
      One ``RunResult`` per config, in order. ``on_step`` sees the whole group's arrays (one task).
    """
    lanes = 1 if on_step is not None else None
    return RunGroup(configs, lanes=lanes).train(progress=progress, on_step=on_step, label=label,
                                                snapshots_at=snapshots_at)


def share_lanes(trials: list[int], lanes: int) -> list[int]:
    """The lane (thread) of each config in a lockstep group: the most trials first, each to the
    lane with the fewest so far (ties to the lowest lane). With one lane, or one config, all in lane 0.
    """
    load = [0] * max(1, min(lanes, len(trials)))
    lane_of = [0] * len(trials)
    for j in sorted(range(len(trials)), key=lambda j: -trials[j]):
        k = load.index(min(load))
        lane_of[j] = k
        load[k] += trials[j]
    return lane_of


class RunGroup:
    """Configs trained in lockstep, resolved and built once: a task per task, task parameters and
    seed (shared by the configs that share those), one learner each.

    Configs of one task differ only in their learner settings (learner, preset, overrides, trials)
    and share one batched task; configs of different tasks or seeds (Fig. 25's experiments A-D,
    ``reproduce --seeds``) get a task each, stepped together with one physics call where the tasks
    allow it (``tasks.base.step_together``: several throw tasks fly in one batch). Building is
    where a bad preset, ``--set`` or ``--task-set`` fails, so a caller can build first (fail fast),
    then prepare its output, then ``train`` what it built.

    With several threads (``tasks.threads()``, 2 by default) the configs are shared out between
    lanes (``share_lanes``), each with its own tasks and learners, stepped side by side in one
    thread each: a lane's physics, learning and drawing run while the other lane's do. A trial's
    arithmetic does not depend on its lane, so the results equal one lane's (and separate runs).

    Args:
      configs: the configs of the group.
      lanes: threads to share the configs between (default ``tasks.threads()``; at most one per config).

    Raises:
      ValueError: a bad setting, or configs that do not share backend, steps and block.
    """

    def __init__(self, configs: list[RunConfig], *, lanes: int | None = None) -> None:
        self.configs = [c.resolved() for c in configs]
        if len({(c.backend, c.n_steps, c.block) for c in self.configs}) != 1:
            raise ValueError("a group shares backend, steps and block; these differ")
        check_memory_needs(self.configs)
        if lanes is None:
            from somarm import tasks

            lanes = tasks.threads()
        lane_of = share_lanes([c.n_trials for c in self.configs], check_int("lanes", lanes))
        keys = [(c.task, json.dumps(c.task_params, sort_keys=True), c.seed, lane)
                for c, lane in zip(self.configs, lane_of, strict=True)]
        distinct = list(dict.fromkeys(keys))
        self.tasks = []
        for key in distinct:
            members = [c for c, k in zip(self.configs, keys, strict=True) if k == key]
            self.tasks.append(make_task(members[0], np.concatenate([c.trial_ids_array() for c in members])))
        self.task = self.tasks[0]
        # Each config owns a slice of its task's trials and a slice of the curves' columns.
        self.owners, self.parts, self.columns = [], [], []
        offsets = np.cumsum([0] + [t.n_trials for t in self.tasks])
        filled = [0] * len(self.tasks)
        for key, config in zip(keys, self.configs, strict=True):
            i = distinct.index(key)
            self.owners.append(i)
            self.parts.append(slice(filled[i], filled[i] + config.n_trials))
            self.columns.append(slice(int(offsets[i]) + filled[i], int(offsets[i]) + filled[i] + config.n_trials))
            filled[i] += config.n_trials
        self.learners = [make_learner(c, self.tasks[i]) for c, i in zip(self.configs, self.owners, strict=True)]
        # The tasks (and so their learners) each thread steps; one lane when there is one thread.
        self.lanes = [lane for lane in ([i for i, key in enumerate(distinct) if key[3] == k]
                                        for k in range(max(lane_of) + 1)) if lane]

    def train(self, *, progress: bool = True, on_step: StepHook | None = None, label: str | None = None,
              snapshots_at: tuple[int, ...] = ()) -> list[RunResult]:
        """Train the built learners once (see ``train_group``); one ``RunResult`` per config.

        Raises:
          ValueError: ``on_step`` for a group of several tasks or seeds.
        """
        first = self.configs[0]
        if on_step is not None and len(self.lanes) > 1:
            raise ValueError("on_step needs a group in one lane (RunGroup(..., lanes=1))")
        curves = loop(self.tasks, self.learners, self.parts, owners=self.owners, n_steps=first.n_steps,
                      block=first.block, progress=progress, on_step=on_step,
                      label=label or f"{first.task}/{first.learner}", snapshots_at=snapshots_at,
                      lanes=self.lanes)
        results = []
        for config, learner, column, taken in zip(self.configs, self.learners, self.columns, curves.snapshots,
                                                  strict=True):
            own_task = self.task if len(self.configs) == 1 else make_task(config)
            own_task.set_step(curves.steps_done)  # its phase (four_goals) is the one the learner reached
            results.append(RunResult(
                config=config,
                learner=learner,
                task=own_task,
                block_means=curves.block_means[:, column].copy(),
                block_sq_means=curves.block_sq_means[:, column].copy(),
                steps_done=curves.steps_done,
                wall_time=curves.wall_time,
                interrupted=curves.interrupted,
                snapshots=taken,
            ))
        return results


# -- summary and folder -------------------------------------------------------------------------
def greedy_summary(result: RunResult, n_observations: int = 1000) -> dict[str, Any]:
    """The summary keys of a greedy evaluation on fresh observations (seeded by the run's seed).

    A failed evaluation gives ``{"greedy_error": message}`` instead, so the run is still written.
    """
    from somarm import evaluation

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
    if getattr(result.task, "episodic", False):  # whole greedy episodes from the task's start poses
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


def write(result: RunResult, out_dir: str | Path, *, figures: bool = True,
          extra_summary: dict[str, Any] | None = None) -> Path:
    """Write a run folder: learner.npz, config.json, curves.npz, summary.json, then PNG figures.

    Every file is written atomically, so an interrupted write leaves the previous file or none.
    The most valuable file goes first: with a full disk the trained learner (and the config that
    ``somarm evaluate`` needs beside it) are kept even when the figures no longer fit.

    Raises:
      ValueError: the folder cannot be created, or a file cannot be written (one line naming the
        file and the files already written, which are kept).
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"cannot create output folder {out}: {exc.strerror or exc}") from None
    config = result.config
    data = summary(result, extra_summary)
    steps = [
        ("learner.npz", lambda: result.learner.save(out / "learner.npz")),
        ("config.json", lambda: atomic_write_json(out / "config.json",
                                                  {**config.to_dict(), "somarm_version": __version__})),
        ("curves.npz", lambda: atomic_save_npz(out / "curves.npz", block_means=result.block_means,
                                               block_sq_means=result.block_sq_means, block=config.block,
                                               steps=result.steps, seed=config.seed)),
        ("summary.json", lambda: atomic_write_json(out / "summary.json", data)),
    ]
    if figures and result.steps_done > 0:
        from somarm import plots

        steps.append(("the figures", lambda: plots.run_figures(result, out)))
    written: list[str] = []
    for name, write_file in steps:
        try:
            write_file()
        except ValueError as exc:
            kept = f"kept {', '.join(written)}" if written else "nothing was written"
            raise ValueError(f"{exc} ({kept})") from None
        written.append(name)
    return out


def load(out_dir: str | Path) -> tuple[RunConfig, Learner]:
    """Read a run folder's config and final learner state.

    Raises:
      ValueError: not a run folder, or a damaged ``config.json`` or ``learner.npz``.
    """
    from somarm import learners

    out = Path(out_dir)
    for name in ("config.json", "learner.npz"):
        if not (out / name).is_file():
            raise ValueError(f"{out} is not a run folder: {name} is missing")
    try:
        data = json.loads((out / "config.json").read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{out / 'config.json'} is not readable JSON: {exc}") from None
    if isinstance(data, dict):
        data.pop("somarm_version", None)
    try:
        config = RunConfig.from_dict(data).resolved()  # the same checks as `train` (a seed >= 0, ...)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{out / 'config.json'}: {exc}") from None
    learner = learners.load(out / "learner.npz")
    _check_learner_fits(config, learner, out / "learner.npz")
    return config, learner


def _check_learner_fits(config: RunConfig, learner: Learner, path: Path) -> None:
    """Refuse a learner file that is not the one config.json describes (another kind, task or batch)."""
    where = f"{path} does not belong to {path.parent / 'config.json'}"
    if learner.kind != config.learner:
        raise ValueError(f"{where}: it holds a {learner.kind} learner, the config says {config.learner}")
    if learner.seed != config.seed or learner.trial_ids.tolist() != config.trial_ids_array().tolist():
        raise ValueError(f"{where}: its seed and trials ({learner.seed}, {learner.trial_ids.tolist()}) differ "
                         f"from the config's ({config.seed}, {config.trial_ids_array().tolist()})")
    task = make_task(config)
    for what, ours, theirs in (
        ("observation", (learner.observation_low, learner.observation_high),
         (task.observation_low, task.observation_high)),
        ("action", (learner.action_low, learner.action_high), (task.action_low, task.action_high)),
    ):
        if ours[0].shape != theirs[0].shape or not all(map(np.allclose, ours, theirs)):
            raise ValueError(f"{where}: its {what} bounds are not those of task {config.task!r} "
                             "(a learner of another task?)")


def task_for(config: RunConfig, learner: Learner) -> BatchedTask:
    """The task of a loaded run for all the learner's trials, in the learner's phase (four_goals)."""
    from somarm import tasks

    task = tasks.make(config.task, n_trials=learner.n_trials, seed=config.seed, backend=config.backend,
                      **tasks.parse_values(config.task_params))
    task.set_step(learner.t)
    return task
