"""Which show draws a task: the dispatch from a task's record to the arm, sweep or throw show.

It sits above ``shows`` (the arm), ``postures`` (the sweep) and ``throws`` (the launcher), which
know nothing of each other's tasks.
"""

from __future__ import annotations

import numpy as np

from somarm import tasks
from somarm.viewer.postures import SweepShow
from somarm.viewer.shows import ArmShow, load_model
from somarm.viewer.task_readers import goal_reader
from somarm.viewer.throws import throw_show

__all__ = ["show_for_task"]


def show_for_task(task_name: str, task=None, *, sweep: int | None = None):
    """What ``somarm view`` and the live view draw for a task.

    Args:
      task_name: registered task name; its record names the model that draws it.
      task: the task object (it tells where goals and targets are); None builds a one-trial one.
      sweep: draw this many postures at once (Fig. 11's sweep, an arm task) instead of one arm.

    Raises:
      ValueError: unknown task name (the names are listed).
    """
    model_name = tasks.record(task_name).model
    task = tasks.make(task_name) if task is None else task
    model = load_model(model_name)
    if model_name == "launcher":
        return throw_show(task_name, task, model)
    if sweep is not None:
        return SweepShow(model, sweep, goal_of=goal_reader(task), prefix=f"/meshcat/{task_name}")
    if task.episodic:  # reach2_obstacle: the arm where it is and the episode's goal, both observed
        show = ArmShow(model, prefix=f"/meshcat/{task_name}", pose_of=lambda observation, action: np.asarray(
            observation)[:2])
        show.goal_of = task.goal_of
        return show
    return ArmShow(model, goal_of=goal_reader(task), prefix=f"/meshcat/{task_name}")
