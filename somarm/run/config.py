"""A run's settings: ``RunConfig``, the one source of ``somarm train``'s options, defaults and help.

Each field's metadata holds its command-line form (``_option``); ``add_options`` turns the fields
into argparse options and ``from_options`` turns parsed options back into a resolved config, so a
new setting is one field here. Runs use it through ``somarm.run``.
"""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from somarm.streams import trial_ids_for
from somarm.validation import check_int

__all__ = ["RunConfig", "add_options", "from_options", "parse_assignments"]


def _option(flag: str, help: str, **argparse_kwargs: Any) -> dict[str, Any]:
    """A field's command-line form: ``flag`` (or a positional name), help, argparse keywords."""
    return {"flag": flag, "help": help, "argparse": argparse_kwargs}


@dataclass(frozen=True)
class RunConfig:
    """Everything needed to rerun a training run; saved as ``config.json`` beside its results.

    Each field's metadata gives its ``somarm train`` option; ``add_options`` reads them.
    """

    task: str = field(metadata=_option("task", "task name (see `somarm tasks`)"))
    """Registered task name (``somarm tasks`` lists them)."""
    learner: str = field(default="somq", metadata=_option(
        "--learner", "learner kind: somq (the paper's model), motoric (the Fig. 13 B baseline) or tabular (a fixed grid)",
        metavar="KIND"))
    """A kind of ``somarm.learners.KINDS``: ``somq`` (the paper's model), ``motoric`` (Fig. 13 B) or ``tabular``."""
    preset: str | None = field(default=None, metadata=_option(
        "--preset", "parameter table (see `somarm presets`); default: the task's", metavar="TABLE"))
    """Parameter table by name (``table1`` ...); None takes the task's default."""
    overrides: dict[str, str] = field(default_factory=dict, metadata=_option(
        "--set", "change a learner setting", action="append", metavar="KEY=VALUE"))
    """Learner settings changed from the preset, as the CLI's ``--set KEY=VALUE``."""
    task_params: dict[str, Any] = field(default_factory=dict, metadata=_option(
        "--task-set", "change a task parameter", action="append", metavar="KEY=VALUE"))
    """Task parameters changed from their defaults (``--task-set KEY=VALUE``)."""
    n_trials: int = field(default=1, metadata=_option("--trials", "independent trials", type=int, metavar="N"))
    """Independent trials advanced together (each has its own random streams)."""
    n_steps: int | None = field(default=None, metadata=_option(
        "--steps", "training steps; default: the task's", type=int, metavar="N"))
    """Training steps (one-step episodes); None takes the task's default."""
    seed: int = field(default=0, metadata=_option("--seed", "the run's seed", type=int, metavar="S"))
    """The run's seed: every random number of the run derives from it."""
    backend: str = field(default="mujoco", metadata=_option("--backend", "mujoco or analytic", metavar="NAME"))
    """Where rewards are computed: ``mujoco`` (default) or ``analytic``."""
    block: int = field(default=100, metadata=_option("--block", "steps per learning-curve point", type=int, metavar="N"))
    """Steps per recorded point of the learning curves (mean reward over the block)."""
    trial_ids: list[int] | None = field(default=None, metadata=_option(
        "--trial-ids", "run these trials only, e.g. 7 to replay trial 7 of a batch alone",
        type=int, nargs="+", metavar="I"))
    """Which trials to run (default ``0 .. n_trials-1``); ``[7]`` replays trial 7 of a batch alone."""

    def trial_ids_array(self) -> np.ndarray:
        """The trial indices as an array, shape ``(n_trials,)``."""
        return trial_ids_for(self.n_trials, self.trial_ids)

    def resolved(self) -> RunConfig:
        """A copy with the task's defaults (from its record) filled in and every field checked.

        Raises:
          ValueError: an unknown task or learner kind, or a setting out of range (one line).
        """
        from somarm import learners, tasks

        record = tasks.record(self.task)
        if self.learner not in learners.KINDS:
            raise ValueError(f"unknown learner {self.learner!r}; allowed: {', '.join(learners.KINDS)}")
        resolved = dataclasses.replace(
            self,
            preset=self.preset or record.preset,
            n_steps=self.n_steps if self.n_steps is not None else record.n_steps,
            overrides=dict(self.overrides),
            task_params=dict(self.task_params),
        )
        # Named by their somarm train flags: that is where a user meets them.
        check_int("--trials", resolved.n_trials)
        check_int("--steps", resolved.n_steps)
        check_int("--seed", resolved.seed, minimum=0)
        check_int("--block", resolved.block)
        _check_blocks(resolved.n_steps, resolved.block)
        for trial_id in resolved.trial_ids or []:
            check_int("--trial-ids", trial_id, minimum=0)
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


def _check_blocks(n_steps: int, block: int) -> None:
    """The learning curve is a point per whole block: refuse steps it would leave out."""
    if block > n_steps:
        raise ValueError(f"--block {block} is more than --steps {n_steps}: the learning curve would have no "
                         "point; give a --block of at most --steps")
    if n_steps % block:
        lower, upper = n_steps - n_steps % block, n_steps - n_steps % block + block
        raise ValueError(f"--steps {n_steps} is not a whole number of --block {block}: the last "
                         f"{n_steps % block} steps would be left out of the learning curve; give --steps "
                         f"{lower} or {upper}, or a --block that divides {n_steps}")


# -- the command line, derived from RunConfig ---------------------------------------------------
def add_options(parser: argparse.ArgumentParser) -> None:
    """Add one option per ``RunConfig`` field (flag, help and default from the field)."""
    for f in dataclasses.fields(RunConfig):
        option = f.metadata
        kwargs = dict(option["argparse"])
        default = None if f.default is dataclasses.MISSING else f.default
        text = option["help"]
        if default is not None and f.name != "n_trials":
            text += f" (default {default})"
        if not option["flag"].startswith("-"):
            parser.add_argument(option["flag"], help=text, **kwargs)
            continue
        if f.name == "n_trials":
            text += " (default 1, or the number of --trial-ids)"
            default = None  # so that --trial-ids alone sets the count
        parser.add_argument(option["flag"], dest=f.name, default=default, help=text, **kwargs)


def parse_assignments(items: list[str] | None, what: str) -> dict[str, str]:
    """``["a=1", "b=x"] -> {"a": "1", "b": "x"}``; one clear error for a malformed item."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise ValueError(f"{what} takes KEY=VALUE, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def from_options(args: argparse.Namespace) -> RunConfig:
    """The resolved ``RunConfig`` of parsed ``add_options`` arguments.

    Raises:
      ValueError: a malformed ``KEY=VALUE``, ``--trials`` disagreeing with ``--trial-ids``, or
        any error of ``RunConfig.resolved``.
    """
    values = {f.name: getattr(args, f.name) for f in dataclasses.fields(RunConfig)}
    values["overrides"] = parse_assignments(args.overrides, "--set")
    values["task_params"] = parse_assignments(args.task_params, "--task-set")
    trials, ids = args.n_trials, args.trial_ids
    if ids and trials is not None and trials != len(ids):
        raise ValueError(f"--trials {trials} disagrees with {len(ids)} --trial-ids; give one of them")
    values["n_trials"] = len(ids) if ids else (1 if trials is None else trials)
    return RunConfig(**values).resolved()
