"""``SOMQ``: SOM-Q in the shape of a Stable-Baselines3 model, for people who come from SB3.

A thin layer over the run machinery (``somarm.run``): the environment is a task (``gym:ID`` for a
Gymnasium id, or one of this project's tasks), the learner is built from a preset as ``somarm
train`` builds it, ``learn`` runs the training loop, ``save`` writes a run folder that ``somarm
evaluate`` and ``somarm view`` read (or, given ``NAME.zip``, one zip file, as SB3 saves), and
``load`` reads either back::

    from somarm import SOMQ

    model = SOMQ("MlpPolicy", "Pendulum-v1", seed=0)   # or SOMQ("Pendulum-v1", seed=0)
    model.learn(total_timesteps=200_000)
    action, _ = model.predict(observation, deterministic=True)
    model.save("pendulum.zip")
    model = SOMQ.load("pendulum.zip")

Where it differs from SB3, and why:

- The policy is SOM-Q's maps: ``"MlpPolicy"`` is taken as SB3 code passes it and ignored, and other
  policies are refused (``SOMQ``'s docstring says why).

- ``n_trials`` independent learners train side by side (default 1), each on its own copy of the
  environment; ``total_timesteps`` counts the steps of each, and ``predict`` answers for ``trial``.
- ``predict`` is greedy only: SOM-Q's exploration (a random unit, a perturbed action) belongs to
  learning, so ``deterministic=False`` is refused rather than answered with something else.
- Observations are the environment's own; the model scales them as its task does
  (``somarm.tasks.gym_envs``). Actions come back in the action Box's dtype.
- Given an environment object, the model trains in it as given, wrappers and all (Monitor,
  TimeLimit, RecordEpisodeStatistics, observation wrappers that keep the observation's shape); more
  trials step copies of it. Its id and keywords go to ``config.json`` (time limit kept,
  ``render_mode`` dropped), so ``somarm evaluate`` remakes it without the wrappers; ``load(path,
  env=env)`` trains in a wrapped one again. Wrappers that change the action Box or the observation's
  shape are refused (the action map and the run folder hold those).
- ``learn`` takes SB3's callbacks (``somarm.callbacks``); ``num_timesteps`` counts the steps of one
  trial since ``learn`` last reset it, while the learner's schedules follow its own step ``learner.t``.
  A model saved by a callback in the middle of ``learn`` holds its curves so far (it learns on once
  loaded) and is written without the greedy evaluation.
- A loaded model learns on from the saved step: its episodes start from streams of their own for that
  step, and its curves (read back from the folder) go on where they stopped.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from somarm import run, tasks
from somarm.agent_env import bounds_of, check_preset_view, task_name, task_on
from somarm.io import read_json
from somarm.protocols import BatchedTask, Learner
from somarm.run import RunConfig
from somarm.run.loop import EpisodeLog, Episodes, loop

__all__ = ["SOMQ", "LearningInterrupted"]


class LearningInterrupted(UserWarning):
    """``SOMQ.learn`` was stopped by Ctrl-C or SIGTERM before it took every step asked for."""


class _Curves:
    """The training loop's ``on_step`` hook of ``learn``: the learning curve of the call in progress (so a
    model saved by a callback in the middle of it, or a call stopped mid-block, has a curve of every
    step), then the callbacks' hook if there is one."""

    def __init__(self, block: int, n_trials: int, then: Any = None) -> None:
        self.block, self.then = block, then
        self.step = 0
        self.means: list[np.ndarray] = []  # each whole block's mean reward per trial
        self.squares: list[np.ndarray] = []  # and mean squared reward
        self.total, self.total_sq = np.zeros(n_trials), np.zeros(n_trials)
        self.started = time.perf_counter()

    def __call__(self, step: int, observations: np.ndarray, actions: np.ndarray, rewards: np.ndarray) -> None:
        self.step = step
        self.total += rewards
        self.total_sq += rewards * rewards
        if step % self.block == 0:
            self.means.append(self.total / self.block)
            self.squares.append(self.total_sq / self.block)
            self.total, self.total_sq = np.zeros_like(self.total), np.zeros_like(self.total_sq)
        if self.then is not None:
            self.then(step, observations, actions, rewards)

    def parts(self) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """``(block size, means (n, n_trials), squares (n, n_trials))`` of the whole blocks so far, then
        of the steps since the last one, as a block of their own."""
        n_trials = self.total.size
        out = [(self.block, np.array(self.means).reshape(-1, n_trials), np.array(self.squares).reshape(-1, n_trials))]
        part = self.step % self.block
        if part:
            out.append((part, self.total[None] / part, self.total_sq[None] / part))
        return out


#: What a model keeps of its past when ``set_env`` gives it another environment.
_HISTORY = ("_blocks", "_squares", "_episodes", "_wall_time", "_origin", "_cannot_learn")


#: The policy names SB3 users pass first. SOMQ has one policy, its maps, and takes "MlpPolicy" (SB3's for
#: Box observations, the only kind SOMQ learns from) as a name of it; images and dicts it cannot learn from.
_POLICY_NAMES = ("MlpPolicy",)
_OTHER_POLICIES = ("CnnPolicy", "MultiInputPolicy")


def _env_of(policy: Any, env: Any) -> Any:
    """The environment of ``SOMQ(env)`` or SB3's ``SOMQ(policy, env)``.

    Raises:
      ValueError: a policy SOMQ cannot be, a policy name without an environment, or nothing (one line).
    """
    if env is None:
        if isinstance(policy, str) and policy in _POLICY_NAMES + _OTHER_POLICIES:
            raise ValueError(f"SOMQ({policy!r}) names a policy: give the environment too, "
                             f"SOMQ({policy!r}, \"Pendulum-v1\") or SOMQ(\"Pendulum-v1\")")
        if policy is None:
            raise ValueError("SOMQ needs an environment: give an environment, its Gymnasium id or a task name, "
                             "SOMQ(\"Pendulum-v1\")")
        return policy
    if policy is not None and not (isinstance(policy, str) and policy in _POLICY_NAMES):
        raise ValueError(f"SOMQ learns one policy, its maps, over Box observations: give policy 'MlpPolicy' (SB3's "
                         f"name for it) or none, got policy {policy!r}")
    return env


class SOMQ:
    """SOM-Q (Smith 2002) on a Gymnasium environment or a somarm task, in SB3's shape.

    ``SOMQ(env)``, or SB3's ``SOMQ("MlpPolicy", env)``: SOM-Q's policy is its input and action maps
    and their Q-table, built from the preset, so the policy name only stands where SB3 code puts one.
    ``"MlpPolicy"`` (SB3's name for a policy over Box observations, the only observations SOM-Q
    learns from) is taken and ignored; ``"CnnPolicy"``, ``"MultiInputPolicy"`` and policy classes are
    refused, since no network is built.

    Budget in samples, as in SB3: ``total_timesteps`` counts the samples of each trial. SOM-Q takes
    far more samples than TD3 or SAC, each far cheaper (a fraction of a millisecond against tens).
    Each benchmark's preset was scored at its run length, and a shorter ``learn`` learns less:

    ======================== ========= =============================================================
    environment              samples   seconds (docs/benchmarks/*/REPORT.md: samples x ms per sample)
    ======================== ========= =============================================================
    Pendulum-v1              500,000   about 98; the mean return passes -200 after 200,000 (45 s)
    MountainCarContinuous-v0 200,000   about 27; the mean return passes 90 after 100,000 (13 s)
    InvertedPendulum-v5      400,000   about 39
    Reacher-v5               200,000   about 101; the mean return passes -6 after 100,000 (52 s)
    dmc:DOMAIN-TASK          100,000   13 to 56 (the six suite tasks with a preset; pendulum-swingup 100,000
                                       decisions of 5 suite steps, about 60 s)
    ======================== ========= =============================================================

    Args:
      policy: ``"MlpPolicy"`` (ignored) before the environment as SB3 writes it, or the environment
        itself when it comes first and alone.
      env: a Gymnasium id (``"Pendulum-v1"``), ``"gym:ID"``, a somarm task name (``"reach2"``) or a
        Gymnasium environment made with ``gymnasium.make``, wrapped or not (trained in as given).
      verbose: 0 (default) says nothing; 1 or 2 draws ``learn``'s progress line on stderr (the steps,
        the mean return of the last 100 episodes or the mean reward of the last block, the seconds;
        in place on a terminal, a line per tenth of the run in a log) and prints one line on stdout
        when ``learn`` ends.
      seed: the run's seed (every random number derives from it).
      n_trials: independent learners trained side by side.
      preset: a parameter table (``somarm presets``); default the task's.
      env_kwargs: keyword arguments of ``gymnasium.make`` (``{"g": 5.0}``).
      learner: ``somq`` (default), ``motoric`` or ``tabular``.
      **settings: learner settings changed from the preset, typed (``epsilon=0.2``, ``gamma=0.99``).

    Raises:
      ValueError: an unknown environment, a policy other than ``"MlpPolicy"``, a ``verbose`` other
        than 0, 1 or 2, wrappers that change the action Box or the observation's shape, an environment
        made without the keywords its preset sees the task through (``dmc_pendulum``: ``angles=[[0, 1]]``,
        ``action_repeat=5``), or a bad setting (one line); ``MissingExtra`` (an ``ImportError`` as well) where Gymnasium is not
        installed.
    """

    def __init__(self, policy: Any = None, env: Any = None, *, verbose: int = 0, seed: int = 0, n_trials: int = 1,
                 preset: str | None = None, env_kwargs: dict[str, Any] | None = None, learner: str = "somq",
                 **settings: Any) -> None:
        env = _env_of(policy, env)
        if isinstance(verbose, bool) or verbose not in (0, 1, 2):
            raise ValueError(f"verbose must be 0, 1 or 2 (SB3's levels), got {verbose!r}")
        task, kwargs, given = task_name(env)
        if given is not None:
            check_preset_view(given, task, kwargs, preset)
        params = {**kwargs, **(env_kwargs or {})}
        if given is not None and "observation_low" not in params:
            params.update(bounds_of(given, task, params, seed))
        config = RunConfig(task=task, learner=learner, preset=preset, overrides=dict(settings),
                           task_params=params, n_trials=n_trials, seed=seed)
        self.verbose = verbose  #: 0 quiet; 1 or 2: learn's progress line and a closing line
        self._start(config.resolved(), env=given)

    def _start(self, config: RunConfig, learner: Learner | None = None, env: Any = None) -> None:
        self.config = config
        self.given_env = env  #: the environment object given, trained in as it is (None: copies made from the id)
        self.task: BatchedTask = run.make_task(config) if env is None else task_on(config, env)
        self.learner: Learner = learner if learner is not None else run.make_learner(config, self.task)
        self.task.continue_at(self.learner.t)  # a loaded model meets new starts, not its first ones again
        self._blocks: list[tuple[int, np.ndarray]] = []
        self._squares: list[np.ndarray] = []
        self._episodes: list[Episodes] = []
        self._log = EpisodeLog([self.task]) if self.task.episodic else None  # episodes spanning two learn()s
        self._wall_time = 0.0
        self._cannot_learn: str | None = None
        self.interrupted = False  #: the last ``learn`` was stopped by Ctrl-C or SIGTERM before its end
        self._origin = 0  # the learner's step at which num_timesteps last started from 0
        self._learning: _Curves | None = None  # the curves of the learn() in progress
        self._vec_env = None
        self._logger = None

    @property
    def num_timesteps(self) -> int:
        """Steps each trial has taken since ``learn`` last reset the count (SB3's ``num_timesteps``, for
        one trial); the learner's own step, which its schedules follow, is ``learner.t``."""
        return int(self.learner.t) - self._origin

    def learn(self, total_timesteps: int, callback: Any = None, log_interval: int | None = None,
              tb_log_name: str | None = None, reset_num_timesteps: bool = True, progress_bar: bool = False) -> SOMQ:
        """Train every trial for ``total_timesteps`` more steps; returns the model (as SB3).

        Args:
          total_timesteps: steps to take, per trial.
          callback: Stable-Baselines3's callbacks (a ``BaseCallback``, ``EvalCallback``,
            ``CheckpointCallback``, ``CallbackList``, a list of them, or a function), called as SB3
            calls them (``somarm.callbacks``); an ``on_step`` that returns False ends ``learn``.
          log_interval, tb_log_name: SB3's, taken so that SB3 code runs, and not used (SOMQ writes no
            log files; its curves go to the run folder ``save`` writes, and ``verbose`` shows progress).
          progress_bar: draw a progress line on stderr (as ``verbose`` 1 or 2 does).
          reset_num_timesteps: count ``num_timesteps`` from 0 again (SB3's default); False goes on
            counting. The learner's schedules follow its own step either way.

        Ctrl-C or SIGTERM stops at the end of a step and keeps what was learned; the model says so
        with a ``LearningInterrupted`` warning and ``interrupted`` (True until the next ``learn``).

        Raises:
          ValueError: ``total_timesteps`` is not a whole number >= 1, a run that cannot fit in memory
            (the refusal ``somarm train`` gives), or the model was loaded from a folder whose curves do
            not cover every step it took (one line).
        """
        from somarm.callbacks import CallbackHook, as_callback
        from somarm.validation import check_int

        steps = check_int("total_timesteps", total_timesteps)
        if self._cannot_learn is not None:
            raise ValueError(self._cannot_learn)
        block = math.gcd(steps, 1000)
        run.check_memory_needs([dataclasses.replace(self.config, n_steps=steps, block=block)])
        if reset_num_timesteps:
            self._origin = int(self.learner.t)
        hook = None
        if callback is not None:
            hook = CallbackHook(as_callback(callback, self), self, self.num_timesteps + steps)
            hook.start()
        self._learning = _Curves(block, self.config.n_trials, hook)
        try:
            curves = loop(self.task, [self.learner], [slice(0, self.config.n_trials)], n_steps=steps, block=block,
                          progress=progress_bar or self.verbose > 0, label=f"{self.config.task}/SOMQ",
                          episode_log=self._log,
                          on_step=self._learning)
            parts = self._learning.parts()
        finally:
            self._learning = None
        if hook is not None:
            hook.end()
        done = self.learner.t
        for size, means, squares in parts:
            self._blocks.append((size, means))
            self._squares.append(squares)
        if curves.episodes is not None:
            shifted = dataclasses.replace(curves.episodes, ends=curves.episodes.ends + done - curves.steps_done)
            self._episodes.append(shifted)
        self._wall_time += curves.wall_time
        self.interrupted = curves.interrupted and not (hook is not None and hook.stopped)
        if self.verbose:
            default = tasks.record(self.config.task).n_steps  # the preset's run length: fewer steps learn less
            budget = f"; the task's preset is scored after {default:,}" if self.learner.t < default else ""
            print(f"SOMQ on {self.config.task}: {curves.steps_done} steps x {self.config.n_trials} trial(s) in "
                  f"{curves.wall_time:.1f} s (num_timesteps {self.num_timesteps}{budget})", flush=True)
        if self.interrupted:
            warnings.warn(f"SOMQ.learn was stopped by a signal after {curves.steps_done} of {steps} steps; the "
                          f"model keeps what it learned (num_timesteps {done})", LearningInterrupted, stacklevel=2)
        return self

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True,
                *, trial: int = 0) -> tuple[np.ndarray, None]:
        """The greedy action for an observation of the environment, as SB3's ``(action, state)``.

        Args:
          observation: ``(obs_dim,)`` or a batch ``(n, obs_dim)`` (a VecEnv's ``(n_envs, obs_dim)``),
            the environment's own values.
          state, episode_start: SB3's recurrent state, taken and not used (SOM-Q has none).
          deterministic: True (greedy); False is refused (SOM-Q explores only while it learns).
          trial: which trial's policy answers.

        Returns:
          ``(action, None)``: ``(action_dim,)`` or ``(n, action_dim)``, inside the action Box, of its
          dtype (float64 for this project's own tasks).

        Raises:
          ValueError: ``deterministic=False``, a wrong shape or a trial out of range (one line).
        """
        if not deterministic:
            raise ValueError("SOMQ.predict is greedy: give deterministic=True (SOM-Q explores only while it learns)")
        if isinstance(trial, bool) or not isinstance(trial, (int, np.integer)) or not 0 <= trial < self.config.n_trials:
            raise ValueError(f"trial must be a whole number in [0, {self.config.n_trials - 1}], got {trial!r}")
        x = np.asarray(observation, dtype=np.float64)
        single = x.ndim == 1
        x = x.reshape(-1, x.shape[-1]) if x.ndim else x
        if x.ndim != 2 or x.shape[1] != self.task.observation_dim:
            raise ValueError(f"observation must have shape ({self.task.observation_dim},) or "
                             f"(n, {self.task.observation_dim}), got {np.shape(observation)}")
        x = self.task.scale(x)  # a Gymnasium task maps onto [0, 1]; the others keep their units
        batch = np.broadcast_to(x, (self.config.n_trials, *x.shape))
        actions = np.asarray(self.learner.predict(np.ascontiguousarray(batch)))[trial]
        dtype = getattr(self.task, "action_dtype", np.float64)  # the Box's (float32 for most), as SB3's
        actions = np.clip(actions.astype(dtype), self.task.action_low.astype(dtype), self.task.action_high.astype(dtype))
        return (actions[0] if single else actions), None

    def evaluate(self, *, seed: int | None = None) -> dict[str, Any]:
        """The greedy keys of ``summary.json`` (``run.greedy_measures``): for a Gymnasium task the mean
        return of 100 fresh greedy episodes per trial, and its sd over trials."""
        return run.greedy_measures(self.learner, self.task, seed=self.config.seed if seed is None else seed)

    @property
    def env(self):
        """SB3's ``model.env``: ``get_env()``."""
        return self.get_env()

    def get_env(self):
        """The environment being trained, as SB3's ``VecEnv`` (a ``DummyVecEnv`` over trial 0's copy of a
        Gymnasium environment); None for this project's own tasks, which are no Gymnasium environments.

        Raises:
          MissingExtra: Stable-Baselines3 is not installed (the ``peers`` extra).
        """
        from somarm.tasks.gym_envs import GymTask

        if not isinstance(self.task, GymTask):
            return None
        if self._vec_env is None:
            try:
                from stable_baselines3.common.vec_env import DummyVecEnv
            except ImportError:
                from somarm.extras import missing

                raise missing("peers", "SOMQ.get_env gives Stable-Baselines3's VecEnv") from None
            env = self.task.env_of(0)
            self._vec_env = DummyVecEnv([lambda: env])
        return self._vec_env

    def set_env(self, env: Any) -> None:
        """Learn on from now on in ``env``: an environment of the same id (made with other keywords, such
        as another time limit, or wrapped), or its id. The learner and its scaling are kept.

        Raises:
          ValueError: an environment of another id, or one whose spaces differ (one line).
        """
        task, kwargs, given = task_name(env)
        if task != self.config.task:
            raise ValueError(f"set_env takes an environment of the model's task {self.config.task}, got {task}")
        if given is not None:
            check_preset_view(given, task, kwargs, self.config.preset)
        own = {key: self.config.task_params[key] for key in ("observation_low", "observation_high")
               if key in self.config.task_params}
        config = dataclasses.replace(self.config, task_params={**kwargs, **own})
        kept = {name: getattr(self, name) for name in _HISTORY}
        self._start(config.resolved(), self.learner, given)
        for name, value in kept.items():
            setattr(self, name, value)

    def get_vec_normalize_env(self) -> None:
        """None: SOMQ scales observations itself (SB3's callbacks ask for a ``VecNormalize``)."""
        return None

    @property
    def logger(self):
        """Stable-Baselines3's ``Logger``, writing nothing, for the callbacks that record to it."""
        if self._logger is None:
            from stable_baselines3.common.logger import Logger

            self._logger = Logger(folder=None, output_formats=[])
        return self._logger

    def _result(self) -> run.RunResult:
        # Each learn() recorded blocks of its own size: shown at their common divisor, a block's mean
        # standing for each of its parts. Saved in the middle of a learn() (a callback), with its curve so far.
        parts = list(zip(self._blocks, self._squares, strict=True))
        episodes_parts, wall_time = list(self._episodes), self._wall_time
        if self._learning is not None:
            parts += [((size, means), squares) for size, means, squares in self._learning.parts()]
            if self._log is not None:
                episodes_parts.append(self._pending_episodes())
            wall_time += time.perf_counter() - self._learning.started
        parts = [part for part in parts if len(part[0][1])]
        block = math.gcd(*(size for (size, _), _ in parts)) if parts else 1
        blocks = np.zeros((0, self.config.n_trials))
        squares = np.zeros((0, self.config.n_trials))
        for (size, means), sq in parts:
            blocks = np.concatenate([blocks, np.repeat(means, size // block, axis=0)])
            squares = np.concatenate([squares, np.repeat(sq, size // block, axis=0)])
        episodes = None
        if episodes_parts:
            episodes = Episodes(*(np.concatenate([getattr(e, name) for e in episodes_parts])
                                  for name in ("ends", "trials", "returns", "lengths")))
        config = dataclasses.replace(self.config, n_steps=max(block, len(blocks) * block), block=block)
        return run.RunResult(config=config, learner=self.learner, task=self.task, block_means=blocks,
                             block_sq_means=squares, steps_done=int(self.learner.t), wall_time=wall_time,
                             episodes=episodes)

    def _pending_episodes(self) -> Episodes:
        """The training episodes that ended so far in the learn() in progress, at the learner's steps."""
        ended = self._log.ended
        shift = int(self.learner.t) - self._learning.step
        if not ended:
            empty = np.zeros(0)
            return Episodes(empty.astype(np.int64), empty.astype(np.int64), empty, empty.astype(np.int64))
        return Episodes(np.concatenate([np.full(len(o), s + shift) for s, o, _, _ in ended]).astype(np.int64),
                        np.concatenate([o for _, o, _, _ in ended]).astype(np.int64),
                        np.concatenate([r for _, _, r, _ in ended]),
                        np.concatenate([n for _, _, _, n in ended]).astype(np.int64))

    def save(self, path: str | Path) -> Path:
        """Write the model: ``NAME.zip`` as one zip file, as SB3 saves, any other path as a run folder.

        A run folder holds ``learner.npz``, ``config.json``, ``curves.npz``, ``summary.json`` and the
        figures; ``SOMQ.load``, ``somarm evaluate`` and ``somarm view`` read it. It is claimed as
        ``somarm train --force`` claims it: locked while the files are written (another process
        writing there is refused), written beside the earlier results and swapped in only when
        complete, so a failed save keeps the earlier model whole; files somarm did not write stay.

        A ``.zip`` file holds the same files but the figures (``somarm.run.archive``); ``SOMQ.load``
        and ``somarm evaluate`` read it. It is written under a temporary name and renamed, so a failed
        save keeps the earlier file whole. Its folder is made where missing, as SB3 makes it.

        Returns:
          The folder or the file written.

        Raises:
          ValueError: an empty path, a folder or file that cannot be written, or a folder another
            process is writing (one line).
        """
        from somarm.run.claim import claim

        if not str(path).strip():
            raise ValueError("SOMQ.save needs a path: a folder (\"runs/pendulum\") or a file (\"pendulum.zip\"), "
                             f"got {str(path)!r}")
        path = Path(path)
        result = self._result()
        # Saved by a callback in the middle of learn (CheckpointCallback), the model is written without
        # the greedy evaluation, which would cost its episodes at every checkpoint.
        extra = run.greedy_summary(result) if result.steps_done and self._learning is None else {}
        if path.suffix == ".zip" and not path.is_dir():  # a folder of that name is an earlier save's: kept a folder
            import tempfile

            from somarm.run import archive

            with tempfile.TemporaryDirectory(prefix="somarm-save-") as folder:
                run.write(result, folder, figures=False, extra_summary=extra)
                return archive.pack(Path(folder), path)
        owner = claim(path, force=True, flag="path", what="a saved model")
        try:
            run.write_claimed(result, owner, extra_summary=extra)
        finally:
            owner.release()
        return owner.folder

    @classmethod
    def load(cls, path: str | Path, env: Any = None) -> SOMQ:
        """A model from a run folder (``save``'s, or ``somarm train``'s) or a ``.zip`` file ``save`` wrote;
        with ``env``, one that learns and is evaluated in that environment (``set_env``). As SB3's
        ``load``, ``NAME`` finds ``NAME.zip`` where there is no ``NAME``; and ``NAME.zip`` finds the
        folder ``NAME`` where there is no ``NAME.zip``.

        Raises:
          ValueError: neither a run folder nor a zip file of one, a damaged one, or an ``env``
            ``set_env`` refuses (one line).
        """
        from somarm.run import archive

        path = Path(path)
        if not path.exists() and path.suffix == ".zip" and path.with_suffix("").is_dir():
            path = path.with_suffix("")  # SB3's name for a folder SOMQ.save wrote without the suffix
        elif not path.exists() and path.suffix != ".zip" and path.with_name(path.name + ".zip").is_file():
            path = path.with_name(path.name + ".zip")  # SB3's load adds the suffix its save added
        if not archive.is_archive(path):
            return cls._load_folder(path, env)
        with archive.unpacked(path) as folder:
            try:
                model = cls._load_folder(folder, env)
            except ValueError as exc:  # named by the file the user gave, not the temporary folder
                raise ValueError(str(exc).replace(str(folder), str(path))) from None
        if model._cannot_learn is not None:
            model._cannot_learn = model._cannot_learn.replace(str(folder), str(path))
        return model

    @classmethod
    def _load_folder(cls, path: Path, env: Any) -> SOMQ:
        config, learner = run.load(path)
        model = cls.__new__(cls)
        model.verbose = 0
        model._start(config, learner)
        if learner.t:
            model._read_history(path)
        if env is not None:
            model.set_env(env)
        return model

    def _read_history(self, folder: Path) -> None:
        """The curves and wall time of the steps already taken, so that a model that learns on and is
        saved again writes curves over all its steps. Where they cannot be read, the model still
        predicts, evaluates and saves, and ``learn`` says why it cannot go on."""
        try:
            with np.load(folder / "curves.npz", allow_pickle=False) as data:
                block = int(data["block"])
                means, squares = np.asarray(data["block_means"], float), np.asarray(data["block_sq_means"], float)
                names = ("episode_ends", "episode_trials", "episode_returns", "episode_lengths")
                episodes = Episodes(*(np.asarray(data[n]) for n in names)) if self.task.episodic else None
            wall = float(read_json(folder / "summary.json", max_bytes=2**20)["wall_time_s"])
        except (OSError, EOFError, KeyError, TypeError, ValueError, zipfile.BadZipFile, zlib.error) as exc:
            self._cannot_learn = (f"{folder} holds no readable curves.npz and summary.json ({exc}); "
                                  "a loaded model learns on only from a complete run folder")
            return
        if means.shape != (len(means), self.config.n_trials) or squares.shape != means.shape or \
                block < 1 or len(means) * block != self.learner.t:
            self._cannot_learn = (f"{folder / 'curves.npz'} covers {len(means)} blocks of {block} steps, but the "
                                  f"learner took {self.learner.t} (a run stopped mid-block keeps no curve of "
                                  "that block); a loaded model learns on only from a run whose curves cover "
                                  "every step")
            return
        self._blocks, self._squares, self._wall_time = [(block, means)], [squares], wall
        if episodes is not None:
            self._episodes = [episodes]
