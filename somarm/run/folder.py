"""The run folder, written and read here alone: ``learner.npz``, ``config.json``, ``curves.npz``,
``summary.json`` and the figures. Who may write a folder, and when results replace earlier ones, is
``somarm.run.claim``'s.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from somarm import __version__
from somarm.io import atomic_save_npz, atomic_write_json, read_json
from somarm.protocols import BatchedTask, Learner
from somarm.run.build import make_task
from somarm.run.claim import FolderClaim, writer_of
from somarm.run.config import RunConfig
from somarm.run.group import RunResult
from somarm.run.summary import summary
from somarm.tasks.loadable import check_loadable

__all__ = ["write", "write_claimed", "write_summary", "load", "task_for"]


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
    if result.failed is not None:  # a run the task cut short says so, beside its partial results
        extra_summary = {**(extra_summary or {}), "failed": result.failed}
    data = summary(result, extra_summary)
    steps = [
        ("learner.npz", lambda: result.learner.save(out / "learner.npz")),
        ("config.json", lambda: atomic_write_json(out / "config.json",
                                                  {**config.to_dict(), "somarm_version": __version__})),
        ("curves.npz", lambda: atomic_save_npz(out / "curves.npz", block_means=result.block_means,
                                               block_sq_means=result.block_sq_means, block=config.block,
                                               steps=result.steps, seed=config.seed, **_episode_arrays(result))),
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


def write_claimed(result: RunResult, owner: FolderClaim, **kwargs: Any) -> None:
    """``write`` a run into its claimed folder and make it the folder's run, unless it is incomplete (a
    failed write, or an interrupted run) and would replace an earlier run, which is then kept whole.

    Args:
      result: the run.
      owner: the claim on its folder (``somarm.run.claim.claim``); the caller releases it.
      **kwargs: ``write``'s (``figures``, ``extra_summary``).

    Raises:
      ValueError: a file cannot be written (one line; it says where the earlier run is kept), or the
        run failed mid-way (``RunResult.failed``: written, then said in one line).
    """
    try:
        write(result, owner.path, **kwargs)
    except ValueError as exc:
        owner.finish(False)
        if owner.replacing:
            raise ValueError(f"{exc}; the new run was dropped and the earlier run in {owner.folder} is kept") from None
        raise
    owner.finish(not result.interrupted)
    if result.failed is not None:
        kept = (f"the earlier run in {owner.folder} is kept" if owner.replacing else
                f"the {result.steps_done} steps before it are kept in {owner.folder}, marked failed in summary.json"
                if result.steps_done else f"no step was trained; {owner.folder} holds the run marked failed")
        raise ValueError(f"{result.failed}; {kept}")


def write_summary(result: RunResult, out_dir: str | Path, extra_summary: dict[str, Any] | None = None) -> Path:
    """Write (atomically) a written run's ``summary.json`` again with ``extra_summary``: its greedy
    evaluation, measured after the trained run was written (``write_claimed``).

    Raises:
      ValueError: the file cannot be written (one line; the run's other files are kept).
    """
    path = Path(out_dir) / "summary.json"
    atomic_write_json(path, summary(result, extra_summary))
    return path


def _episode_arrays(result: RunResult) -> dict[str, np.ndarray]:
    """A multi-step run's training episodes for ``curves.npz``: when each ended (step), its trial, its
    return and length, and the mean return per block and trial (NaN where none ended)."""
    if result.episodes is None:
        return {}
    episodes = result.episodes
    return {"episode_ends": episodes.ends, "episode_trials": episodes.trials, "episode_returns": episodes.returns,
            "episode_lengths": episodes.lengths, "block_returns": result.block_returns}


def load(out_dir: str | Path) -> tuple[RunConfig, Learner]:
    """Read a run folder's config and final learner state.

    Raises:
      ValueError: not a run folder, or a damaged ``config.json`` or ``learner.npz``.
    """
    from somarm import learners

    out = Path(out_dir)
    if not out.is_dir():
        what = "is a file" if out.exists() else "does not exist"
        raise ValueError(f"{out} {what}; give a run folder (one that `somarm train` wrote)")
    if (writer := writer_of(out)) is not None:
        raise ValueError(f"{out} is being written by a somarm process (pid {writer}); wait for it to finish")
    for name in ("config.json", "learner.npz"):
        if not (out / name).is_file():
            raise ValueError(f"{out} is not a run folder: {name} is missing")
    data = read_json(out / "config.json", max_bytes=_MAX_CONFIG_BYTES, follow_links=True)
    if isinstance(data, dict):
        data.pop("somarm_version", None)
        # A folder is data: its task name is checked before anything it names is imported.
        check_loadable(data.get("task"), where=str(out / "config.json"))
    try:
        config = RunConfig.from_dict(data).resolved()  # the same checks as `train` (a seed >= 0, ...)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{out / 'config.json'}: {exc}") from None
    learner = learners.load(out / "learner.npz")
    _check_learner_fits(config, learner, out / "learner.npz")
    _check_settings_fit(config.learner_config.to_dict(), learner.config.to_dict(), out / "learner.npz")
    return config, learner


#: A run's config.json holds its settings: a file far larger is not one.
_MAX_CONFIG_BYTES = 4 * 2**20


def _check_settings_fit(wanted: dict[str, Any], held: dict[str, Any], path: Path) -> None:
    """Refuse a learner file whose settings (map shapes, rates, ...) are not those config.json describes."""
    differ = sorted(key for key in wanted.keys() | held.keys() if wanted.get(key) != held.get(key))
    if differ:
        shown = ", ".join(f"{key} {held.get(key)!r} (config: {wanted.get(key)!r})" for key in differ[:3])
        raise ValueError(f"{path} does not belong to {path.parent / 'config.json'}: its settings differ: {shown}")


def _check_learner_fits(config: RunConfig, learner: Learner, path: Path) -> None:
    """Refuse a learner file that is not the one config.json describes (another kind, task or batch)."""
    where = f"{path} does not belong to {path.parent / 'config.json'}"
    if learner.kind != config.learner:
        raise ValueError(f"{where}: it holds a {learner.kind} learner, the config says {config.learner}")
    if learner.n_trials != config.n_trials:  # counted before any list of trials is built
        raise ValueError(f"{where}: it holds {learner.n_trials} trial(s), the config says {config.n_trials}")
    if learner.seed != config.seed or learner.trial_ids.tolist() != config.trial_ids_array().tolist():
        raise ValueError(f"{where}: its seed and trials ({learner.seed}, {learner.trial_ids.tolist()}) differ "
                         f"from the config's ({config.seed}, {config.trial_ids_array().tolist()})")
    if (what := _bounds_differ(learner, make_task(config))) is not None:
        raise ValueError(f"{where}: its {what} bounds are not those of task {config.task!r} "
                         "(a learner of another task?)")


def _bounds_differ(learner: Learner, task: BatchedTask) -> str | None:
    """"observation" or "action" if the learner's bounds of that side are not the task's; None if both fit."""
    for what, ours, theirs in (
        ("observation", (learner.observation_low, learner.observation_high),
         (task.observation_low, task.observation_high)),
        ("action", (learner.action_low, learner.action_high), (task.action_low, task.action_high)),
    ):
        if ours[0].shape != theirs[0].shape or not all(map(np.allclose, ours, theirs)):
            return what
    return None


def task_for(config: RunConfig, learner: Learner, task_params: dict[str, Any] | None = None) -> BatchedTask:
    """The task of a loaded run for all the learner's trials, in the learner's phase (four_goals).

    Args:
      config, learner: a run as ``load`` returns it.
      task_params: task parameters to change from the run's (typed, as ``tasks.parse_params`` reads
        ``--task-set``), to score the learner on another task: ``{"dynamics": "actuated"}`` replays a
        kinematic reach's targets through the servos.

    Raises:
      ValueError: an unknown parameter or a bad value, or parameters that change the observations or
        actions the learner was trained on (one line naming them).
    """
    from somarm import tasks

    params = {**config.task_params, **tasks.check_params(config.task, dict(task_params or {}))}
    task = tasks.make(config.task, n_trials=learner.n_trials, seed=config.seed, backend=config.backend, **params)
    if task_params and (what := _bounds_differ(learner, task)) is not None:
        changed = ", ".join(f"{key}={tasks.format_param(value)}" for key, value in task_params.items())
        raise ValueError(f"--task-set {changed} changes the task's {what} bounds from those the learner "
                         "was trained on; give parameters that keep them")
    task.set_step(learner.t)
    return task
