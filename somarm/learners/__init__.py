"""The learner registry: every learner kind, by name, and the one place that lists them.

``make`` builds a learner of a kind, ``load`` reopens a saved one whatever its kind, and
``memory_needed`` says what one would allocate. A new kind is its own module (a config
subclassing ``base.ConfigBase`` and a learner subclassing ``base.LearnerBase``, with its
``memory_needed``) plus one line in ``LEARNERS``.
"""

from __future__ import annotations

import os
from typing import Any

from somarm.learners.base import LearnerBase, initial_generator
from somarm.learners.file import read_file
from somarm.learners.motoric import MotoricConfig, MotoricMap
from somarm.learners.somq import SOMQConfig, SOMQLearner
from somarm.learners.tabular import TabularConfig, TabularQ

__all__ = ["LEARNERS", "config_class", "make", "load", "memory_needed", "initial_generator"]

#: kind -> (config class, learner class); the kinds are its keys.
LEARNERS: dict[str, tuple[type, type[LearnerBase]]] = {
    "somq": (SOMQConfig, SOMQLearner),
    "motoric": (MotoricConfig, MotoricMap),
    "tabular": (TabularConfig, TabularQ),
}


def _entry(kind: str) -> tuple[type, type]:
    if kind not in LEARNERS:
        raise ValueError(f"unknown learner kind {kind!r}; allowed: {', '.join(LEARNERS)}")
    return LEARNERS[kind]


def config_class(kind: str) -> type:
    """The config class of learner ``kind``.

    Raises:
      ValueError: an unknown kind (the message lists the kinds).
    """
    return _entry(kind)[0]


def make(kind: str, config: Any = None, **kwargs: Any):
    """Build a learner by kind.

    Args:
      kind: a key of ``LEARNERS``.
      config: its config (default: the config class's defaults).
      **kwargs: the learner's keywords (observation_low, ..., n_trials, seed, trial_ids).

    Raises:
      ValueError: an unknown kind (the message lists the kinds) or a config of the wrong class.
    """
    config_type, learner_type = _entry(kind)
    config = config_type() if config is None else config
    if not isinstance(config, config_type):
        raise ValueError(f"a {kind} learner needs a {config_type.__name__}, got {type(config).__name__}")
    return learner_type(config, **kwargs)


def load(path: str | os.PathLike):
    """Reopen a learner saved with ``save(path)``, whatever its kind.

    Raises:
      ValueError: the file is missing, damaged, or holds no known kind (the kinds are listed).
    """
    kind = read_file(path)[0]["kind"]
    if kind not in LEARNERS:
        raise ValueError(f"{path} holds no known learner kind; allowed: {', '.join(LEARNERS)}")
    return LEARNERS[kind][1].load(path)


def memory_needed(kind: str, config: Any, *, n_trials: int, obs_dim: int, action_dim: int) -> tuple[str, float]:
    """What a learner of ``kind`` would allocate, ``(description, bytes)``: its class's own estimate,
    the one it checks when built (``LearnerBase.memory_needed``).

    Args:
      kind: a key of ``LEARNERS``. config: its config. n_trials: trials.
      obs_dim, action_dim: the task's dimensions (1 and 1 give a lower bound).

    Raises:
      ValueError: an unknown kind (the kinds are listed), or settings a kind refuses outright.
    """
    return _entry(kind)[1].memory_needed(config, n_trials=n_trials, obs_dim=obs_dim, action_dim=action_dim)
