"""Registered tasks: the reaching arms and the projectile launcher of Smith (2002), and a delayed-reward arm.

Two interfaces to the same tasks:

- ``load(name, seed=0, **params)``: a dm_control ``control.Environment`` (dm_env) whose
  episodes are one step long, as users of ``suite.load`` expect (``reach2_obstacle``'s last
  until the goal or the step limit);
- ``make(name, n_trials=1, seed=0, ...)``: a batched task (``somarm.protocols.BatchedTask``)
  for experiments, evaluated in MuJoCo (default) or by the closed forms (``backend="analytic"``).

Episode k of ``load(name, seed=s)`` sees the same observation as trial 0 at step k of
``make(name, seed=s)``. Each task module registers its tasks as ``TaskRecord``s in its
``RECORDS``; everything else (run defaults, figures, viewer) reads the records. Importing this
package is light: the task modules, and with them MuJoCo and dm_control, load on first use.
"""

from __future__ import annotations

import importlib
import json
from typing import Any

from somarm.tasks.record import BACKENDS, TaskRecord

__all__ = ["names", "record", "records", "parse_params", "format_param", "check_params",
           "check_backend", "load", "make", "set_threads", "threads", "TaskRecord", "BACKENDS"]

#: The modules holding task records (each defines ``RECORDS``); a new task module adds one line.
_MODULES = ("reach", "four_goals", "throw", "obstacle")
_RECORDS: dict[str, TaskRecord] = {}


def records() -> dict[str, TaskRecord]:
    """Every registered task's record by name (imports the task modules, and MuJoCo, on first use)."""
    if not _RECORDS:
        for module in _MODULES:
            for entry in importlib.import_module(f"somarm.tasks.{module}").RECORDS:
                _RECORDS[entry.name] = entry
    return _RECORDS


def names() -> list[str]:
    """Names of the registered tasks."""
    return list(records())


def record(name: str) -> TaskRecord:
    """The record of task ``name``: the one place an unknown task name is reported.

    Raises:
      ValueError: unknown name (the names are listed).
    """
    if isinstance(name, str) and name.startswith(("gym:", "dmc:")):
        from somarm.tasks import gym_envs

        return gym_envs.record_for(name)
    if name not in records():
        raise ValueError(f"unknown task {name!r}; tasks: {', '.join(records())}, gym:ID for a "
                         "Gymnasium environment (gym:Pendulum-v1) or dmc:DOMAIN-TASK for a DeepMind Control "
                         "Suite task (dmc:reacher-easy)")
    return _RECORDS[name]


def parse_params(name: str, texts: dict[str, str]) -> dict[str, Any]:
    """Task parameters as text (``--task-set KEY=VALUE``) read once into values.

    A text that reads as JSON (``4.5``, ``true``, ``[[0.1, 0.2]]``) becomes that value, any other
    text stays text (``dynamics=actuated``); ``check_params`` then checks the values' types and ranges.

    Raises:
      ValueError: an unknown task or parameter (the settable ones are listed).
    """
    record(name).check_settable(texts)
    out = {}
    for key, text in texts.items():
        try:
            out[key] = json.loads(text) if isinstance(text, str) else text
        except json.JSONDecodeError:
            out[key] = text
    return out


def format_param(value: Any) -> str:
    """A task parameter as ``--task-set`` text that ``parse_params`` reads back (``0.2``, ``true``, ``actuated``)."""
    return value if isinstance(value, str) else json.dumps(value)


def check_params(name: str, params: dict[str, Any]) -> dict[str, Any]:
    """Typed task parameters checked against task ``name``'s params dataclass; returns a copy.

    Raises:
      ValueError: an unknown parameter, text where a value is wanted (``"0.2"`` for ``0.2``: read
        text with ``parse_params``) or a value the params class refuses (one line).
    """
    record(name).check_values(params)
    return dict(params)


def check_backend(name: str, backend: str | None) -> str:
    """``backend`` if task ``name`` can compute its rewards there (its record's ``backends``); None gives
    the task's first.

    Raises:
      ValueError: an unknown backend, or one the task lacks (one line naming the task's backends).
    """
    entry = record(name)
    if backend is None:
        return entry.backends[0]
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; backends: {', '.join(BACKENDS)}")
    if backend not in entry.backends:
        raise ValueError(f"{name} needs the {' or '.join(entry.backends)} backend, got backend {backend!r}")
    return backend


def make(name: str, *, n_trials: int = 1, seed: int = 0, trial_ids=None, backend: str | None = None,
         **params: Any):
    """A batched task (``somarm.protocols.BatchedTask``) for ``n_trials`` independent trials.

    Args:
      name: a registered task (see ``names()``).
      n_trials: independent trials stepped together.
      seed: the run's seed; trial i's observations come from stream (seed, "task", trial id).
      trial_ids: explicit trial indices (e.g. ``[7]`` replays trial 7 alone).
      backend: "mujoco", "analytic" (closed forms) or "gymnasium" (``gym:ID``); default the task's first
        (its record's ``backends``).
      **params: fields of the task's params dataclass (``record(name).params``).

    Raises:
      ValueError: unknown task, unknown parameter, parameter out of range, unknown backend.
    """
    entry = record(name)
    backend = check_backend(name, backend)
    return entry.make(entry.params_from(params), n_trials=n_trials, seed=seed, trial_ids=trial_ids,
                      backend=backend)


def load(name: str, *, seed: int = 0, **params: Any):
    """A dm_env environment (``dm_control.rl.control.Environment``).

    Episodes are one step long, except ``reach2_obstacle``'s, which end at the goal (discount 0)
    or at the step limit (discount 1).

    Args:
      name: a registered task. seed: the seed of the observations (as trial 0 of ``make``).
      **params: fields of the task's params dataclass.

    Returns:
      A ``control.Environment``; ``reset()`` draws the observation (or start pose), ``step(action)``
      ends a one-step episode.

    Raises:
      ValueError: as for ``make``; actions of the wrong shape, non-finite or out of bounds at ``step``.
    """
    from dm_control.rl import control

    physics, task = record(name).environment(make(name, seed=seed, **params))
    # A driven arm integrates several timesteps per action (actuated reach, reach2_obstacle).
    return control.Environment(physics, task, n_sub_steps=task.sub_steps)


def threads() -> int:
    """Threads the MuJoCo backend may use for a batch from this thread: ``set_threads``'s, or 1 under
    ``pool.single_threaded`` (a share of a group split over processes)."""
    from somarm.tasks import flight
    from somarm.tasks.pool import threads_here

    return threads_here(flight.THREADS)


def set_threads(n: int) -> None:
    """Threads the MuJoCo backend uses for large batches (default 2).

    Raises:
      ValueError: ``n`` is not a whole number >= 1.
    """
    from somarm.tasks import arms, flight
    from somarm.validation import check_int

    arms.THREADS = flight.THREADS = check_int("n", n)
