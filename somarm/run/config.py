"""A run's settings: ``RunConfig``, the one source of ``somarm train``'s options, defaults and help.

Each field's metadata holds its command-line form (``_option``); ``add_options`` turns the fields
into argparse options and ``from_options`` turns parsed options back into a resolved config, so a
new setting is one field here. Runs use it through ``somarm.run``.

A ``RunConfig`` holds typed values only: the command line's ``--set`` and ``--task-set`` text is
read once, in ``from_options`` (``learners.settings.parse_settings``, ``tasks.parse_params``), and
``config.json``'s in ``from_dict``; ``resolved`` then builds the learner's config (``SOMQConfig``
...) that the run uses. ``to_dict`` writes the learner settings as their ``--set`` text again, so
a run folder's ``config.json`` reads as the command that made it.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from somarm.streams import trial_ids_for
from somarm.tasks.record import BACKENDS
from somarm.validation import check_int, whole_number

__all__ = ["RunConfig", "add_options", "from_options", "parse_assignments", "parse_task_params"]


def _option(flag: str | None, help: str = "", **argparse_kwargs: Any) -> dict[str, Any]:
    """A field's command-line form: ``flag`` (or a positional name; None: no option), help, argparse keywords."""
    return {"flag": flag, "help": help, "argparse": argparse_kwargs}


@dataclass(frozen=True)
class RunConfig:
    """Everything needed to rerun a training run; saved as ``config.json`` beside its results.

    Each field's metadata gives its ``somarm train`` option; ``add_options`` reads them.
    """

    task: str = field(metadata=_option("task", "task name (see `somarm tasks`), or gym:ID for a Gymnasium environment"))
    """Registered task name (``somarm tasks`` lists them)."""
    learner: str = field(default="somq", metadata=_option(
        "--learner", "learner kind: somq (the paper's model), motoric (the Fig. 13 B baseline) or tabular (a fixed grid)",
        metavar="KIND"))
    """A kind of ``somarm.learners.LEARNERS``: ``somq`` (the paper's model), ``motoric`` (Fig. 13 B) or ``tabular``."""
    preset: str | None = field(default=None, metadata=_option(
        "--preset", "parameter table (see `somarm presets`); default: the task's", metavar="TABLE"))
    """Parameter table by name (``table1`` ...); None takes the task's default."""
    overrides: dict[str, Any] = field(default_factory=dict, metadata=_option(
        "--set", "change a learner setting, e.g. epsilon=0.2, decay=inv:250, n_a.floor=1, input_shape=10x10",
        action="append", metavar="KEY=VALUE"))
    """Learner settings changed from the preset, typed, by ``--set`` key: ``{"epsilon": 0.2,
    "decay": InverseDecay(250.0)}`` (``SOMQConfig.with_changes`` lists the keys)."""
    learner_config: Any = field(default=None, metadata=_option(None))
    """The learner's own config (``SOMQConfig``, ``MotoricConfig``, ``TabularConfig``) that ``overrides``
    change; None takes the preset's. ``resolved`` fills it in with the overrides made (a Python
    caller may give a whole config here; the command line gives a preset and ``--set``)."""
    task_params: dict[str, Any] = field(default_factory=dict, metadata=_option(
        "--task-set", "change a task parameter, e.g. radius=0.2, punish_low=true", action="append",
        metavar="KEY=VALUE"))
    """Task parameters changed from their defaults, typed: ``{"radius": 0.2, "punish_low": True}``."""
    n_trials: int = field(default=1, metadata=_option("--trials", "independent trials", type=whole_number, metavar="N"))
    """Independent trials advanced together (each has its own random streams)."""
    n_steps: int | None = field(default=None, metadata=_option(
        "--steps", "training steps; default: the task's", type=whole_number, metavar="N"))
    """Training steps (one-step episodes); None takes the task's default."""
    seed: int = field(default=0, metadata=_option("--seed", "the run's seed", type=whole_number, metavar="S"))
    """The run's seed: every random number of the run derives from it."""
    backend: str | None = field(default=None, metadata=_option(
        "--backend", f"where rewards are computed: {', '.join(BACKENDS)} (a task's record says which it "
        "takes; default its first: mujoco, or gymnasium for gym:ID)", metavar="NAME"))
    """Where rewards are computed: ``mujoco``, ``analytic`` or ``gymnasium`` (``tasks.BACKENDS``; each
    task's record lists the ones it takes); None takes the task's first (``mujoco``; ``gymnasium`` for a
    ``gym:ID`` task)."""
    block: int = field(default=100, metadata=_option("--block", "steps per learning-curve point", type=whole_number, metavar="N"))
    """Steps per recorded point of the learning curves (mean reward over the block)."""
    trial_ids: list[int] | None = field(default=None, metadata=_option(
        "--trial-ids", "run these trials only, e.g. 7 to replay trial 7 of a batch alone",
        type=whole_number, nargs="+", metavar="I"))
    """Which trials to run (default ``0 .. n_trials-1``); ``[7]`` replays trial 7 of a batch alone."""

    def trial_ids_array(self) -> np.ndarray:
        """The trial indices as an array, shape ``(n_trials,)``."""
        return trial_ids_for(self.n_trials, self.trial_ids)

    def resolved(self) -> RunConfig:
        """A copy with the task's defaults (from its record) filled in, the learner config built and
        every field checked.

        Raises:
          ValueError: an unknown task, learner kind, preset or backend, a learner setting or task
            parameter of the wrong type or out of range, a setting out of range (one line).
        """
        from somarm import tasks
        from somarm.learners import presets

        for name in ("overrides", "task_params"):
            if not isinstance(getattr(self, name), dict):
                raise ValueError(f"{name} must be a dict of setting -> value, got {type(getattr(self, name)).__name__}")
        ids = self.trial_ids
        if ids is not None and (isinstance(ids, (str, bytes)) or not hasattr(ids, "__iter__")):
            raise ValueError(f"trial_ids must be a list of whole numbers or None, got {type(ids).__name__}")
        record = tasks.record(self.task)
        config_type = _config_class(self.learner)
        backend = tasks.check_backend(self.task, self.backend)
        if self.preset is not None:
            presets.get(self.preset)  # an unknown table is named even beside a learner_config
        if self.learner_config is None:
            preset = self.preset or record.preset
            base = presets.config_for(self.learner, preset)
        elif isinstance(self.learner_config, config_type):
            preset, base = self.preset, self.learner_config
        else:
            raise ValueError(f"learner_config of a {self.learner} learner must be a {config_type.__name__}, "
                             f"got {type(self.learner_config).__name__}")
        resolved = dataclasses.replace(
            self,
            preset=preset,
            learner_config=base.with_changes(self.overrides),
            n_steps=self.n_steps if self.n_steps is not None else record.n_steps,
            overrides=dict(self.overrides),
            task_params=record.complete(tasks.check_params(
                self.task, {**(presets.task_params_of(preset, self.task) if preset else {}), **self.task_params}),
                self.seed),
            backend=backend,
        )
        # Named by their somarm train flags: that is where a user meets them.
        check_int("--trials", resolved.n_trials)
        check_int("--steps", resolved.n_steps)
        check_int("--seed", resolved.seed, minimum=0)
        check_int("--block", resolved.block)
        _check_blocks(resolved.n_steps, resolved.block)
        for trial_id in [] if resolved.trial_ids is None else list(resolved.trial_ids):
            check_int("--trial-ids", trial_id, minimum=0)
        if resolved.trial_ids is not None:  # a list given is in memory already; range(n_trials) is never listed
            ids = resolved.trial_ids_array().tolist()
            if len(set(ids)) != len(ids):
                raise ValueError(f"trial ids must differ from each other (a trial runs once), got {ids}")
            resolved = dataclasses.replace(resolved, trial_ids=ids)
        return resolved

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (``config.json``): the overrides as their ``--set`` text, the task parameters
        as JSON values, and the learner config as its ``to_dict`` only where the preset and overrides
        do not give it (so a command-line run's file has the keys it always had); ``from_dict``
        reads it back to an equal config."""
        from somarm.learners.settings import format_settings

        data = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        data["overrides"] = format_settings(self.overrides)
        if self._derived_learner_config():
            del data["learner_config"]
        else:
            data["learner_config"] = self.learner_config.to_dict()
        data["task_params"] = json.loads(json.dumps(self.task_params))
        data["trial_ids"] = None if self.trial_ids is None else list(self.trial_ids)
        return data

    def _derived_learner_config(self) -> bool:
        """True if ``learner_config`` is unset or is its preset's with the overrides (so need not be written)."""
        from somarm import learners
        from somarm.learners import presets

        if self.learner_config is None:
            return True
        if self.learner not in learners.LEARNERS or self.preset not in presets.PRESETS:
            return False
        try:
            return presets.config_for(self.learner, self.preset).with_changes(self.overrides) == self.learner_config
        except ValueError:
            return False

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RunConfig:
        """Inverse of ``to_dict``: the text of overrides and task parameters read once, here.

        Reads every ``config.json`` written so far: one without ``learner_config`` (the preset and
        overrides give it) and one whose task parameters are text (``{"radius": "0.2"}``).

        Raises:
          ValueError: a missing, unknown or mistyped setting (one line naming it).
        """
        from somarm.learners.settings import parse_settings

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
        values = dict(data)
        config_type = _config_class(values.get("learner", "somq"))
        values["overrides"] = parse_settings(config_type, {k: _text(v) for k, v in data.get("overrides", {}).items()})
        values["task_params"] = parse_task_params(data["task"], data.get("task_params", {}), "task_params")
        if values.get("learner_config") is not None:
            if not isinstance(values["learner_config"], dict):
                raise ValueError("run setting 'learner_config' must be a JSON object of the learner's fields")
            values["learner_config"] = config_type.from_dict(values["learner_config"])
        return cls(**values)


def parse_task_params(task: str, texts: dict[str, Any], what: str) -> dict[str, Any]:
    """``tasks.parse_params``, with a value nested deeper than any task parameter refused in one line."""
    from somarm import tasks

    try:
        return tasks.parse_params(task, texts)
    except RecursionError:
        deep = next((k for k, v in texts.items() if isinstance(v, str) and v.lstrip()[:1] in "[{"), "?")
        raise ValueError(f"{what} {deep}: the value is nested too deeply to be a task parameter; give a number, "
                         "a word or a short list") from None


def _config_class(kind: str) -> type:
    """The config class of learner ``kind``; ValueError listing the kinds."""
    from somarm import learners

    if kind not in learners.LEARNERS:
        raise ValueError(f"unknown learner {kind!r}; allowed: {', '.join(learners.LEARNERS)}")
    return learners.config_class(kind)


def _text(value: Any) -> str:
    """A ``config.json`` override as ``--set`` text (a hand-written ``0`` or ``false`` too)."""
    return json.dumps(value) if isinstance(value, (bool, int, float)) else str(value)


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
def add_options(parser: argparse.ArgumentParser, *, leave_out: tuple[str, ...] = ()) -> None:
    """Add one option per ``RunConfig`` field (flag, help and default from the field), but the fields
    named in ``leave_out`` (a sweep has no ``trial_ids``)."""
    for f in dataclasses.fields(RunConfig):
        option = f.metadata
        if option["flag"] is None or f.name in leave_out:
            continue
        kwargs = dict(option["argparse"])
        default = None if f.default is dataclasses.MISSING else f.default
        text = option["help"]
        if default is not None and f.name != "n_trials":
            text += f" (default {default})"
        if not option["flag"].startswith("-"):
            parser.add_argument(option["flag"], help=text, **kwargs)
            continue
        if f.name == "n_trials":
            text += " (default 1" + (")" if "trial_ids" in leave_out else ", or the number of --trial-ids)")
            default = None  # so that --trial-ids alone sets the count
        parser.add_argument(option["flag"], dest=f.name, default=default, help=text, **kwargs)


def parse_assignments(items: list[str] | None, what: str) -> dict[str, str]:
    """``["a=1", "b=x"] -> {"a": "1", "b": "x"}``; one clear error for a malformed item."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise ValueError(f"{what} takes KEY=VALUE, got {item!r}")
        if key.strip() in out:
            raise ValueError(f"{what} {key.strip()} is given twice ({out[key.strip()]} and {value.strip()}); "
                             "give each key once")
        out[key.strip()] = value.strip()
    return out


def from_options(args: argparse.Namespace) -> RunConfig:
    """The resolved ``RunConfig`` of parsed ``add_options`` arguments: the one place the text of
    ``--set`` and ``--task-set`` is read.

    Raises:
      ValueError: a malformed ``KEY=VALUE``, an unknown key or a value of the wrong form,
        ``--trials`` disagreeing with ``--trial-ids``, or any error of ``RunConfig.resolved``.
    """
    from somarm import tasks
    from somarm.learners.settings import parse_settings

    values = {f.name: getattr(args, f.name) for f in dataclasses.fields(RunConfig)
              if f.metadata["flag"] and hasattr(args, f.name)}
    tasks.record(args.task)  # an unknown task is named before its parameters
    values["overrides"] = parse_settings(_config_class(args.learner), parse_assignments(args.overrides, "--set"))
    values["task_params"] = parse_task_params(args.task, parse_assignments(args.task_params, "--task-set"), "--task-set")
    trials, ids = args.n_trials, getattr(args, "trial_ids", None)
    if ids and trials is not None and trials != len(ids):
        raise ValueError(f"--trials {trials} disagrees with {len(ids)} --trial-ids; give one of them")
    values["n_trials"] = len(ids) if ids else (1 if trials is None else trials)
    return RunConfig(**values).resolved()
