"""A viewing session: goals, the learner's greedy answers, and how they are played or exported.

``somarm view`` builds a ``Session`` (from a run folder or an untrained learner), then either
plays it on a live meshcat server until Ctrl-C or records it into a static HTML animation.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from somarm.streams import trial_generators
from somarm.viewer import task_shows
from somarm.viewer.client import CommandSink
from somarm.viewer.motion import MotionShow, episode_describer, settle_describer
from somarm.viewer.shows import arm_animation

__all__ = ["Session", "load_session", "greedy_answers", "arm_animation", "record", "play", "sweep_order"]


@dataclass
class Session:
    """What one ``somarm view`` shows.

    Attributes:
      task_name: the task.
      observations: ``(n_goals, obs_dim)`` the goals shown, in sweep order.
      actions: ``(n_goals, action_dim)`` the learner's greedy actions for them.
      errors: ``(n_goals,)`` minus the task's reward for each (the distance missed).
      fan: ``(n_units, action_dim)`` every action unit of the shown trial (the throw fan), or None.
      show: the task's show (``task_shows.show_for_task``).
      paths: per goal, the joint angles ``(n_frames, nq)`` MuJoCo moved the arm through (actuated
        reach: from the start pose until the reward is read; reach2_obstacle: a whole greedy
        episode), or None where the arm is set, not driven.
      what: what the page shows, in a few words (its title says ``task: what``).
      learner: the learner's kind; trial: the shown trial's id; step: steps it has learned;
      run: the run folder it came from (None: an untrained learner of seed ``seed``).
    """

    task_name: str
    observations: np.ndarray
    actions: np.ndarray
    errors: np.ndarray
    fan: np.ndarray | None
    show: object
    paths: list[np.ndarray] | None = None
    what: str = "greedy answers"
    learner: str = ""
    trial: int = 0
    step: int = 0
    run: str | None = None
    seed: int = 0

    def title(self) -> str:
        """The overlay's first line: the task and what is shown."""
        return f"{self.task_name}: {self.what}"

    def lines(self) -> list[str]:
        """The overlay's lines about the learner: kind, trial, steps learned, and where it came from."""
        if self.run is None:
            return [f"untrained {self.learner} learner (no --run), seed {self.seed}"]
        return [f"{self.learner} learner, trial {self.trial}, after {self.step:,} training steps", f"run {self.run}"]


def greedy_answers(task, learner, observations: np.ndarray, *, trial: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The learner's greedy actions ``(n, action_dim)`` for ``observations`` ``(n, obs_dim)`` and their errors."""
    batch = np.broadcast_to(observations, (learner.n_trials, *observations.shape)).copy()
    actions = np.asarray(learner.predict(batch))[trial]
    errors = -np.asarray(task.evaluate(observations, actions), dtype=np.float64)
    return actions, errors


def sweep_order(observations: np.ndarray) -> np.ndarray:
    """Goals sorted by angle about their mean, so a cycle (or Fig. 11's sweep) moves smoothly."""
    if observations.shape[1] < 2:
        return np.argsort(observations[:, 0])
    centred = observations[:, :2] - observations[:, :2].mean(axis=0)
    return np.argsort(np.arctan2(centred[:, 1], centred[:, 0]))


def load_session(task_name: str, *, run: str | Path | None = None, n_goals: int = 12, seed: int = 0,
                 trial: int | None = None, task_set: dict[str, Any] | None = None) -> Session:
    """Goals drawn from the task (the ``viewer`` random stream of ``seed``) and the learner's answers.

    Args:
      task_name: registered task.
      run: a run folder (config.json + learner.npz); None shows an untrained learner.
      n_goals: how many goals are cycled through (or swept, for reach20).
      seed: seed of the goals (and of the untrained learner).
      trial: which trial of the run's learner is shown, by its trial id (a run of ``--trial-ids 7``
        holds trial 7); None shows the run's first trial.
      task_set: task parameters changed over the run's, typed (``--task-set`` read by
        ``tasks.parse_params``), e.g. ``{"dynamics": "actuated", "settle_time": 0.5}``.

    Raises:
      ValueError: the run is for another task, or ``trial`` is not one of its trials.
    """
    from somarm import run as runs  # `run` is this function's folder argument
    from somarm import tasks

    if run is not None:
        config, learner = runs.load(run)
        if config.task != task_name:
            raise ValueError(f"--run {run} trained task {config.task!r}, not {task_name!r}")
        task_params = config.task_params
    else:
        config = runs.RunConfig(task=task_name, seed=seed).resolved()
        _, learner = runs.make(config)
        task_params = {}
    ids = [int(i) for i in learner.trial_ids]
    if trial is not None and trial not in ids:
        if run is None:
            raise ValueError(f"--trial picks a trial of a trained run: give --run DIR with it (got --trial {trial})")
        allowed = f"0..{ids[-1]}" if ids == list(range(len(ids))) else ", ".join(map(str, ids))
        raise ValueError(f"--trial must be one of this run's trials ({allowed}), got {trial}")
    about = {"learner": learner.kind, "trial": ids[0] if trial is None else trial, "step": int(learner.t),
             "run": None if run is None else str(run), "seed": seed}
    trial = ids.index(ids[0] if trial is None else trial)  # from here on: the index in the batch
    task_params = {**task_params, **(task_set or {})}
    task = tasks.make(task_name, n_trials=1, seed=seed, **task_params)
    task.set_step(int(learner.t))  # four_goals: the goals of the learner's phase
    rng = trial_generators(seed, np.array([0]), "viewer")[0]
    observations = np.asarray(task.sample_observations(rng, n_goals), dtype=np.float64)
    if task.episodic:
        return _episode_session(task_name, task, learner, observations, trial, about)
    observations = observations[sweep_order(observations)]
    actions, errors = greedy_answers(task, learner, observations, trial=trial)
    view = tasks.record(task_name).view
    fan = None
    if view == "fan" and learner.has_maps:
        fan = np.asarray(learner.action_weights)[trial]
    if task.actuated:  # from the start pose (all zeros) to where the reward is read
        moving = task.reached_angles(actions, path=True)
        paths = [np.vstack([np.zeros((1, task.n_links)), path]) for path in moving]
        arm = task_shows.show_for_task(task_name, task)
        describe = settle_describer(task, observations, errors, float(arm.model.opt.timestep))
        return Session(task_name, observations, actions, errors, None, MotionShow(arm, describe), paths,
                       what="the servos drive the arm to each greedy pose", **about)
    show = task_shows.show_for_task(task_name, task, sweep=len(observations) if view == "sweep" else None)
    what = {"sweep": "greedy postures for a sweep of goals (as Fig. 11)",
            "fan": "every action unit thrown at once (the fan)"}.get(view, "greedy answer for each goal")
    if tasks.record(task_name).model == "launcher" and fan is None:
        what = "greedy throw for each target"
    return Session(task_name, observations, actions, errors, fan, show, what=what, **about)


def _episode_session(task_name: str, task, learner, starts: np.ndarray, trial: int, about: dict) -> Session:
    """Greedy episodes of a multi-step task from ``starts`` ``(n, obs_dim)``, with their MuJoCo paths."""

    def policy(observations: np.ndarray) -> np.ndarray:
        batch = np.broadcast_to(observations, (learner.n_trials, *observations.shape)).copy()
        return np.asarray(learner.predict(batch))[trial]

    episodes = task.run_episodes(policy, starts, paths=True)
    ends = 1 + episodes["length"] * task.control_steps
    paths = [episodes["path"][k, :ends[k]] for k in range(len(starts))]
    finals = np.array([path[-1] for path in paths])
    goals = task.goal_of(starts)
    return Session(task_name, starts, finals, task.distances(finals, goals), None,
                   MotionShow(task_shows.show_for_task(task_name, task), episode_describer(task, lambda k: goals[k])), paths,
                   what="greedy episodes from different starts", **about)


def record(session: Session, sink: CommandSink) -> None:
    """Everything of a session a static page needs (the show decides: animation, sweep or fan)."""
    session.show.record(session, sink)


def play(session: Session, sink: CommandSink, *, interval_s: float = 1.5, once: bool = False,
         log=print) -> None:
    """Stream a session to a live server, goal after goal, until Ctrl-C (or one pass if ``once``)."""
    session.show.play(session, sink, interval_s=interval_s, once=once, log=log)
