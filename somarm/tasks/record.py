"""A task record: every fact about one registered task, kept next to the task's code.

Each task module lists its tasks in a module-level ``RECORDS`` tuple (as dm_control's suite
modules register their tasks); ``somarm.tasks`` collects them, and the runner, the plots and
the viewer read them instead of keeping tables of their own.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["TaskRecord", "BACKENDS", "OWN_BACKENDS"]

#: Where a task's rewards can be computed: MuJoCo, the closed forms of the kinematics and ballistics,
#: or a Gymnasium environment's own ``step`` (the ``gym:ID`` tasks).
BACKENDS = ("mujoco", "analytic", "gymnasium")
#: The backends of this project's own tasks (the reproductions take one of these).
OWN_BACKENDS = ("mujoco", "analytic")


@dataclass(frozen=True)
class TaskRecord:
    """One registered task."""

    name: str
    """The name ``somarm.tasks.make`` and the CLI take."""
    summary: str
    """One line: what is observed, what is acted, which figure or table of the paper."""
    params: type
    """The frozen dataclass of the task's parameters."""
    settable: tuple[str, ...]
    """The parameters a user may set (a task that draws a parameter per episode does not offer it)."""
    make: Callable[..., Any]
    """``make(params, n_trials=, seed=, trial_ids=, backend=)``: the batched task (``BatchedTask``)."""
    environment: Callable[[Any], tuple[Any, Any]]
    """``environment(batched) -> (physics, dm_control task)`` for the dm_env interface."""
    preset: str
    """The paper's parameter table this task trains with by default (``somarm.learners.presets``)."""
    n_steps: int
    """Default training steps (the paper gives run lengths only for Fig. 17: these are this
    project's choice elsewhere)."""
    model: str
    """The MJCF model (``models/<model>.xml``) that draws the task in the viewer."""
    observation_labels: tuple[str, ...]
    """Names of the observation dimensions, used as the run figures' axis labels."""
    action_labels: tuple[str, ...]
    """Axis labels of the first two (normalised) action dimensions in the run figures."""
    view: str = "goals"
    """How ``somarm view`` shows a trained learner: ``goals`` (one pose per goal, in turn),
    ``sweep`` (every goal's posture at once, as Fig. 11) or ``fan`` (every action unit thrown at
    once, as Fig. 16)."""
    backends: tuple[str, ...] = OWN_BACKENDS
    """Where the rewards can be computed (``make(..., backend=)``); a task without closed forms
    (contacts) has ``mujoco`` only."""
    episodic: bool = False
    """The task class's ``episodic`` (episodes last several steps: an ``EpisodicTask``), given from
    the class so that the record lists it without building a task; False for the one-step tasks
    (``somarm.peers.gym`` adapts those)."""

    def params_from(self, given: dict[str, Any]) -> Any:
        """The params of this task with ``given`` fields changed from their defaults.

        Raises:
          ValueError: a name that is not settable (the settable ones are listed) or a bad value.
        """
        self.check_settable(given)
        return self.params(**given)

    def check_settable(self, given: dict[str, Any]) -> None:
        """Refuse a parameter name that is not settable (ValueError listing the settable ones)."""
        unknown = sorted(set(given) - set(self.settable))
        if unknown:
            raise ValueError(f"unknown parameter(s) {', '.join(unknown)} for task {self.name}; "
                             f"its parameters: {', '.join(self.settable)}")

    def text_fields(self) -> tuple[str, ...]:
        """The parameters whose values are text (a ``str`` or ``Literal`` annotation), e.g. ``dynamics``."""
        return tuple(field.name for field in dataclasses.fields(self.params)
                     if any(word in str(field.type) for word in ("str", "Literal")))

    def check_values(self, params: dict[str, Any]) -> None:
        """Refuse typed parameters of the wrong type or range (``tasks.check_params``; one line).

        Text is refused where the params class wants a number, a bool or a list (read text with
        ``tasks.parse_params``); the params class checks the rest.
        """
        self.check_settable(params)
        texts = self.text_fields()
        kinds = {field.name: str(field.type) for field in dataclasses.fields(self.params)}
        for key, value in params.items():
            if isinstance(value, str) and key not in texts:
                kind = kinds[key]
                wanted = ("true or false" if "bool" in kind else "a JSON list, such as [[0.3, 0.7]]"
                          if "tuple" in kind or "list" in kind else "a number written with the digits 0-9"
                          if "float" in kind or "int" in kind else "a JSON value")
                raise ValueError(f"task parameter {key} of {self.name} takes {wanted}, got the text {value!r}")
        self.params_from(params)

    def complete(self, params: dict[str, Any], seed: int) -> dict[str, Any]:
        """``params`` with whatever a run must fix once and keep in its ``config.json`` filled in (a
        Gymnasium task's observation scaling); the registered tasks have nothing to add."""
        return dict(params)

    def fields(self) -> tuple[str, ...]:
        """Every field of the params class (settable or not)."""
        return tuple(field.name for field in dataclasses.fields(self.params))
