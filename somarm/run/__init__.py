"""A training run: its settings, building, training, summary and folder.

``RunConfig`` (``somarm.run.config``) is the single source of a run's settings: the ``somarm
train`` options, their defaults and help are derived from its fields (as CleanRL derives its
command line from a dataclass), and it is saved as ``config.json``. ``train``/``train_group``
(``somarm.run.group``) build the task and the learners once (``somarm.run.build``) and hand them
to the loop in ``somarm.run.loop``; ``write`` and ``load`` (``somarm.run.folder``) own the run
folder. Settings are typed values: the command line's text is read once, at the front end::

    result = run.train(RunConfig(task="reach2", n_trials=20, overrides={"epsilon": 0.2},
                                 task_params={"radius": 0.2}))
    run.write(result, "runs/reach2", extra_summary=run.greedy_summary(result))
    run.train(RunConfig(task="reach2", learner_config=SOMQConfig(input_shape=(10, 10))))
"""

from somarm.run.build import check_memory_needs, make, make_learner, make_task, memory_needs
from somarm.run.config import RunConfig, add_options, from_options, parse_assignments
from somarm.run.folder import load, task_for, write, write_claimed
from somarm.run.group import RunFailed, RunGroup, RunResult, share_lanes, train, train_group
from somarm.run.loop import final_rewards
from somarm.run.summary import greedy_cost, greedy_measures, greedy_summary, summary

__all__ = [
    "write_claimed",
    "RunConfig",
    "RunResult",
    "RunFailed",
    "add_options",
    "from_options",
    "parse_assignments",
    "make_task",
    "share_lanes",
    "make_learner",
    "make",
    "memory_needs",
    "check_memory_needs",
    "train",
    "train_group",
    "RunGroup",
    "greedy_measures",
    "greedy_cost",
    "greedy_summary",
    "summary",
    "write",
    "load",
    "task_for",
    "final_rewards",
]
