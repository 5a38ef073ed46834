"""Headless training: one task, one learner, ``n_trials`` independent trials, one run folder.

Data flows one way each step: ``task.reset() -> observations -> learner.act -> actions ->
task.step (physics) -> rewards -> learner.learn``. The runner holds both ends and passes arrays.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import signal
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from somarm import __version__
from somarm.io import atomic_save_npz, atomic_write_json
from somarm.progress import Progress
from somarm.protocols import BatchedTask, Learner
from somarm.streams import trial_ids_for
from somarm.validation import check_int

__all__ = [
    "TASK_DEFAULTS",
    "RunConfig",
    "RunResult",
    "build",
    "build_task",
    "build_learner",
    "train",
    "train_group",
    "write_run",
    "load_run",
    "parse_assignments",
    "task_kwargs",
]

#: Per task: the paper's parameter table and this project's default run length (the paper gives
#: no run lengths except 4000 throws for Fig. 17; the others are this project's choice).
TASK_DEFAULTS: dict[str, tuple[str, int]] = {
    "reach2": ("table1", 50_000),
    "reach20": ("table1", 50_000),
    "four_goals": ("table2", 40_000),
    "throw": ("table4", 4_000),
    "throw_distance": ("table5", 10_000),
    "throw_wind": ("table7", 20_000),
    "throw_friction": ("table7", 20_000),
    "throw_mass": ("table7", 20_000),
}

LEARNER_KINDS = ("somq", "motoric")


@dataclass(frozen=True)
class RunConfig:
    """Everything needed to rerun a training run; saved as ``config.json`` beside its results."""

    task: str
    """Registered task name (``somarm tasks`` lists them)."""
    learner: str = "somq"
    """``somq`` (the paper's model) or ``motoric`` (the Motoric Map baseline of Fig. 13B)."""
    preset: str | None = None
    """Parameter table by name (``table1`` ...); None takes the task's default."""
    overrides: dict[str, str] = field(default_factory=dict)
    """Learner settings changed from the preset, as the CLI's ``--set KEY=VALUE``."""
    task_params: dict[str, Any] = field(default_factory=dict)
    """Task parameters changed from their defaults (``--task-set KEY=VALUE``)."""
    n_trials: int = 1
    """Independent trials advanced together (each has its own random streams)."""
    n_steps: int | None = None
    """Training steps (one-step episodes); None takes the task's default."""
    seed: int = 0
    """The run's seed: every random number of the run derives from it."""
    backend: str = "mujoco"
    """Where rewards are computed: ``mujoco`` (default) or ``analytic``."""
    block: int = 100
    """Steps per recorded point of the learning curves (mean reward over the block)."""
    trial_ids: list[int] | None = None
    """Which trials to run (default ``0 .. n_trials-1``); ``[7]`` replays trial 7 of a batch alone."""

    def trial_ids_array(self) -> np.ndarray:
        """The trial indices as an array, shape ``(n_trials,)``."""
        return trial_ids_for(self.n_trials, self.trial_ids)

    def resolved(self) -> RunConfig:
        """A copy with the task defaults filled in and every field checked."""
        if self.task not in TASK_DEFAULTS:
            raise ValueError(f"unknown task {self.task!r}; allowed: {', '.join(TASK_DEFAULTS)}")
        if self.learner not in LEARNER_KINDS:
            raise ValueError(f"unknown learner {self.learner!r}; allowed: {', '.join(LEARNER_KINDS)}")
        preset, n_steps = TASK_DEFAULTS[self.task]
        resolved = dataclasses.replace(
            self,
            preset=self.preset or preset,
            n_steps=self.n_steps if self.n_steps is not None else n_steps,
            overrides=dict(self.overrides),
            task_params=dict(self.task_params),
        )
        check_int("trials", resolved.n_trials)
        check_int("steps", resolved.n_steps)
        check_int("seed", resolved.seed, minimum=0)
        check_int("block", resolved.block)
        ids = resolved.trial_ids_array().tolist()
        if resolved.trial_ids is not None:
            if len(set(ids)) != len(ids):
                raise ValueError(f"trial ids must differ from each other (a trial runs once), got {ids}")
            resolved = dataclasses.replace(resolved, trial_ids=ids)
        return resolved

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RunConfig:
        """Inverse of ``to_dict``; ValueError naming a missing, unknown or mistyped setting."""
        names = {f.name for f in dataclasses.fields(cls)}
        if not isinstance(data, dict):
            raise ValueError(f"run settings must be a JSON object with keys {', '.join(sorted(names))}")
        unknown = set(data) - names
        if unknown:
            raise ValueError(f"unknown run settings {sorted(unknown)}; allowed: {', '.join(sorted(names))}")
        if "task" not in data:
            raise ValueError("run settings lack 'task'")
        for key in ("overrides", "task_params"):
            if not isinstance(data.get(key, {}), dict):
                raise ValueError(f"run setting {key!r} must be a JSON object of KEY: VALUE")
        return cls(**data)


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


def parse_assignments(items: list[str] | None, what: str) -> dict[str, str]:
    """``["a=1", "b=x"] -> {"a": "1", "b": "x"}``; one clear error for a malformed item."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise ValueError(f"{what} takes KEY=VALUE, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def task_kwargs(task_params: dict[str, Any]) -> dict[str, Any]:
    """Task parameters as the CLI gives them (``"4.5"``, ``"true"``) turned into values.

    A string that parses as JSON (a number, a boolean, a list) becomes that value; any other
    string stays as it is. Values that are not strings pass through.
    """
    out = {}
    for key, value in task_params.items():
        try:
            out[key] = json.loads(value) if isinstance(value, str) else value
        except json.JSONDecodeError:
            out[key] = value
    return out


def build_task(config: RunConfig, trial_ids: np.ndarray | None = None) -> BatchedTask:
    """The batched task of a (resolved) run config, for its trials or the given ``trial_ids``."""
    from somarm import tasks

    ids = config.trial_ids_array() if trial_ids is None else trial_ids
    return tasks.make(
        config.task,
        n_trials=len(ids),
        seed=config.seed,
        trial_ids=ids,
        backend=config.backend,
        **task_kwargs(config.task_params),
    )


def build_learner(config: RunConfig, task: BatchedTask) -> Learner:
    """The learner of a (resolved) run config, reading the task's observation and action bounds."""
    from somarm import learners, presets

    learner_config = presets.config_for(config.learner, config.preset).with_overrides(config.overrides)
    return learners.make_learner(
        config.learner,
        learner_config,
        observation_low=task.observation_low,
        observation_high=task.observation_high,
        action_low=task.action_low,
        action_high=task.action_high,
        n_trials=config.n_trials,
        seed=config.seed,
        trial_ids=config.trial_ids_array(),
    )


def build(config: RunConfig) -> tuple[BatchedTask, Learner]:
    """Make the task and the learner of a (resolved) run config."""
    task = build_task(config)
    return task, build_learner(config, task)


@contextlib.contextmanager
def _stop_between_steps():
    """Inside, Ctrl-C (SIGINT) and SIGTERM only raise a flag that the loop reads after each step.

    A run therefore stops between steps, never between a learner's ``act`` and ``learn``. Signals
    that were being ignored stay ignored; outside the main thread nothing changes.
    """
    stop = {"requested": False}
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def request(signum, frame):
        stop["requested"] = True

    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    for sig, handler in previous.items():
        if handler is not signal.SIG_IGN:
            signal.signal(sig, request)
    try:
        yield stop
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


StepHook = Callable[[int, np.ndarray, np.ndarray, np.ndarray], None]


def snapshot(learner: Learner) -> dict[str, np.ndarray]:
    """Copies of a learner's maps and values (whichever it has) for figures mid-run."""
    names = ("input_weights", "action_weights", "q", "values")
    return {n: np.array(getattr(learner, n)) for n in names if hasattr(learner, n)}


def train(
    config: RunConfig,
    *,
    progress: bool = True,
    on_step: StepHook | None = None,
    label: str | None = None,
    snapshots_at: tuple[int, ...] = (),
) -> RunResult:
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
    """
    return train_group([config], progress=progress, on_step=on_step, label=label, snapshots_at=snapshots_at)[
        0
    ]


def train_group(
    configs: list[RunConfig],
    *,
    progress: bool = True,
    on_step: StepHook | None = None,
    label: str | None = None,
    snapshots_at: tuple[int, ...] = (),
) -> list[RunResult]:
    """Train several learners in lockstep, with one physics call per step for all.

    The configs share backend, steps and block. Configs of one task, task parameters and seed
    share one batched task (they may differ in learner, preset, overrides and trials); configs of
    different tasks or seeds get one task each, stepped together by ``tasks.base.step_together`` (one
    batch of flights for several throw tasks). Each config's trials see the same observations and
    random numbers as when trained alone, so results equal ``train``'s. Comparisons (Figs. 13,
    21-24) and Fig. 25's four experiments run this way: the physics dominates their cost.

    Returns:
      One ``RunResult`` per config, in order. ``on_step`` sees the whole group's arrays (only for
      a group on one task).

    Raises:
      ValueError: the configs differ in backend, steps or block, or ``on_step`` is given for
        a group of several tasks.
    """
    from somarm.tasks.base import step_together

    configs = [c.resolved() for c in configs]
    if len({(c.backend, c.n_steps, c.block) for c in configs}) != 1:
        raise ValueError("a group shares backend, steps and block; these differ")
    keys = [(c.task, json.dumps(c.task_params, sort_keys=True), c.seed) for c in configs]
    distinct = list(dict.fromkeys(keys))
    if len(distinct) > 1 and on_step is not None:
        raise ValueError("on_step needs a group on one task and seed")
    first = configs[0]
    tasks = []
    for key in distinct:
        members = [c for c, k in zip(configs, keys, strict=True) if k == key]
        tasks.append(build_task(members[0], np.concatenate([c.trial_ids_array() for c in members])))
    # Each config owns a slice of its task's trials and a slice of the group's columns.
    owner, parts, columns = [], [], []
    offsets = np.cumsum([0] + [t.n_trials for t in tasks])
    filled = [0] * len(tasks)
    for key, config in zip(keys, configs, strict=True):
        i = distinct.index(key)
        parts.append(slice(filled[i], filled[i] + config.n_trials))
        columns.append(slice(offsets[i] + filled[i], offsets[i] + filled[i] + config.n_trials))
        owner.append(i)
        filled[i] += config.n_trials
    learners = [build_learner(c, tasks[i]) for c, i in zip(configs, owner, strict=True)]
    n_all = int(offsets[-1])
    n_blocks = first.n_steps // first.block
    block_means = np.zeros((n_blocks, n_all))
    block_sq_means = np.zeros((n_blocks, n_all))
    accumulated = np.zeros(n_all)
    accumulated_sq = np.zeros(n_all)
    actions = [np.empty((t.n_trials, t.action_low.size)) for t in tasks]
    snapshots: list[dict[int, dict[str, np.ndarray]]] = [{} for _ in configs]
    bar = Progress(first.n_steps, label=label or f"{first.task}/{first.learner}", enabled=progress)
    last_mean = float("nan")
    start = time.perf_counter()
    step = 0
    interrupted = False
    with _stop_between_steps() as stop:
        try:
            while step < first.n_steps:
                observations = [task.reset() for task in tasks]
                for learner, i, part in zip(learners, owner, parts, strict=True):
                    actions[i][part] = learner.act(observations[i][part])
                rewards_of = step_together(tasks, actions)
                for learner, i, part in zip(learners, owner, parts, strict=True):
                    learner.learn(rewards_of[i][part])
                rewards = rewards_of[0] if len(tasks) == 1 else np.concatenate(rewards_of)
                accumulated += rewards
                accumulated_sq += rewards * rewards
                step += 1
                if on_step is not None:
                    on_step(step, observations[0], actions[0], rewards)
                if step % first.block == 0:
                    index = step // first.block - 1
                    block_means[index] = accumulated / first.block
                    block_sq_means[index] = accumulated_sq / first.block
                    last_mean = float(block_means[index].mean())
                    accumulated[:] = 0.0
                    accumulated_sq[:] = 0.0
                    bar.update(step, last_mean)
                if step in snapshots_at:
                    for learner, taken in zip(learners, snapshots, strict=True):
                        taken[step] = snapshot(learner)
                if stop["requested"]:
                    interrupted = True
                    break
        except KeyboardInterrupt:  # raised by an on_step hook, or outside the main thread
            interrupted = True
    wall_time = time.perf_counter() - start
    bar.close(step, last_mean)
    done = step // first.block
    results = []
    for config, learner, column, taken in zip(configs, learners, columns, snapshots, strict=True):
        own_task = tasks[0] if len(configs) == 1 else build_task(config)
        if hasattr(own_task, "set_step"):
            own_task.set_step(step)  # its phase (four_goals) is the one the learner reached
        results.append(
            RunResult(
                config=config,
                learner=learner,
                task=own_task,
                block_means=block_means[:done, column].copy(),
                block_sq_means=block_sq_means[:done, column].copy(),
                steps_done=step,
                wall_time=wall_time,
                interrupted=interrupted,
                snapshots=taken,
            )
        )
    return results


def final_blocks(n_blocks: int, block: int, window: int) -> int:
    """How many of the last blocks make up a final window of about ``window`` steps (0 if none)."""
    return min(n_blocks, max(1, round(window / block)))


def final_rewards(block_means: np.ndarray, block: int, window: int) -> np.ndarray:
    """Each trial's mean reward over the last ``window`` steps (whole blocks), shape ``(n_trials,)``.

    NaN when no block is complete.
    """
    n = final_blocks(len(block_means), block, window)
    if n == 0:
        return np.full(block_means.shape[1], np.nan)
    return block_means[-n:].mean(axis=0)


def _number_or_none(x: float) -> float | None:
    """JSON has no NaN: a mean over nothing is written as null."""
    return float(x) if np.isfinite(x) else None


def write_run(
    result: RunResult,
    out_dir: str | Path,
    *,
    figures: bool = True,
    extra_summary: dict[str, Any] | None = None,
) -> Path:
    """Write a run folder: config.json, curves.npz, learner.npz, summary.json and PNG figures.

    Every file is written atomically, so an interrupted write leaves the previous file or none.
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"cannot create output folder {out}: {exc.strerror or exc}") from None
    config = result.config
    window = min(1000, max(config.block, config.n_steps // 10))
    final = final_rewards(result.block_means, config.block, window)
    window = final_blocks(len(result.block_means), config.block, window) * config.block
    summary = {
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
    }
    summary.update(extra_summary or {})
    atomic_write_json(out / "config.json", {**config.to_dict(), "somarm_version": __version__})
    atomic_save_npz(
        out / "curves.npz",
        block_means=result.block_means,
        block_sq_means=result.block_sq_means,
        block=config.block,
        steps=result.steps,
        seed=config.seed,
    )
    result.learner.save(out / "learner.npz")
    if figures and result.steps_done > 0:
        from somarm import plots

        plots.run_figures(result, out)
    atomic_write_json(out / "summary.json", summary)
    return out


def load_run(out_dir: str | Path) -> tuple[RunConfig, Learner]:
    """Read a run folder's config and final learner state."""
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
        config = RunConfig.from_dict(data)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{out / 'config.json'}: {exc}") from None
    return config, learners.load_learner(out / "learner.npz")
