"""What a sweep searches: grid and random axes over ``--set`` keys and ``task.KEY`` parameters.

A *point* is one full run configuration (a ``RunConfig`` without its seed); the sweep runs every
point once per seed. Axis values stay text, exactly as ``somarm train --set KEY=VALUE`` takes
them, so the tables show and the best point reruns them as they were swept; ``SweepSpec.config``
reads them once into a typed ``RunConfig``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from somarm.run.config import RunConfig, parse_task_params
from somarm.validation import check_int, parse_float

__all__ = ["TASK_PREFIX", "Axis", "SweepSpec", "parse_grid", "parse_random", "preset_value", "same_value", "config_key"]

#: The most runs (points times seeds) one sweep holds: a row file each, and days of training long before.
MAX_RUNS = 100_000

#: Keys with this prefix are task parameters (``--task-set``); all others are learner settings (``--set``).
TASK_PREFIX = "task."


@dataclass(frozen=True)
class Axis:
    """One swept parameter: a list of grid values, or a random range ``[low, high]``."""

    key: str
    """A ``--set`` key (``alpha``, ``decay``, ``n_a.floor``) or ``task.KEY`` for a task parameter."""
    values: tuple[str, ...] = ()
    """Grid values as ``--set`` takes them (empty for a random axis)."""
    low: float = 0.0
    high: float = 0.0
    log: bool = False
    """Random axis: draw uniformly in log space (for rates and time constants)."""
    integer: bool = False
    """Random axis: both bounds were written as whole numbers, so whole numbers are drawn."""

    @property
    def is_random(self) -> bool:
        return not self.values

    def draw(self, rng: np.random.Generator) -> str:
        """One value of a random axis, as text (six significant digits, what the run uses)."""
        if self.log:
            value = math.exp(rng.uniform(math.log(self.low), math.log(self.high)))
        else:
            value = rng.uniform(self.low, self.high)
        return str(round(value)) if self.integer else f"{value:.6g}"


def _check_key(key: str, spec: str) -> str:
    key = key.strip()
    if not key or key == TASK_PREFIX or any(c.isspace() or c in ",:=" for c in key):
        raise ValueError(f"bad sweep key in {spec!r}: give a --set key (alpha, decay, n_a.floor) or task.KEY")
    return key


def parse_grid(spec: str) -> Axis:
    """``KEY=V1,V2,...`` as a grid axis.

    Raises:
      ValueError: no ``=``, an empty or repeated value (one line quoting the spec).
    """
    key, sep, text = spec.partition("=")
    if not sep:
        raise ValueError(f"--grid takes KEY=V1,V2,..., got {spec!r}")
    values = tuple(v.strip() for v in text.split(","))
    if not text.strip() or not all(values):
        raise ValueError(f"--grid {spec!r} has an empty value; write KEY=V1,V2,... with no empty item")
    if len(set(values)) != len(values):
        raise ValueError(f"--grid {spec!r} repeats a value; each value once")
    return Axis(_check_key(key, spec), values)


def parse_random(spec: str) -> Axis:
    """``KEY=LOW:HIGH`` or ``KEY=LOW:HIGH:log`` as a random axis (whole numbers if both bounds are).

    Raises:
      ValueError: a malformed range, ``LOW >= HIGH``, or ``log`` with ``LOW <= 0`` (one line).
    """
    key, sep, text = spec.partition("=")
    parts = text.split(":")
    if not sep or len(parts) not in (2, 3) or (len(parts) == 3 and parts[2].strip() != "log"):
        raise ValueError(f"--random takes KEY=LOW:HIGH or KEY=LOW:HIGH:log, got {spec!r}")
    try:
        low, high = parse_float(key, parts[0]), parse_float(key, parts[1])
    except ValueError:
        raise ValueError(f"--random {spec!r}: LOW and HIGH must be numbers") from None
    if not (math.isfinite(low) and math.isfinite(high)) or low >= high:
        raise ValueError(f"--random {spec!r}: LOW must be below HIGH (both finite)")
    log = len(parts) == 3
    if log and low <= 0:
        raise ValueError(f"--random {spec!r}: a log range needs LOW > 0")
    integer = all(p.strip().lstrip("+-").isdigit() for p in parts[:2])
    return Axis(_check_key(key, spec), low=low, high=high, log=log, integer=integer)


@dataclass(frozen=True)
class SweepSpec:
    """A whole sweep: the base run, the axes, the seeds. Saved as ``sweep.json`` in the sweep folder."""

    task: str
    learner: str = "somq"
    preset: str | None = None
    axes: tuple[Axis, ...] = ()
    n_samples: int = 0
    """Random draws (each combined with every grid point); needs at least one random axis."""
    overrides: dict[str, Any] = field(default_factory=dict)
    """Learner settings fixed for every point, typed (``RunConfig.overrides``)."""
    task_params: dict[str, Any] = field(default_factory=dict)
    """Task parameters fixed for every point, typed (``RunConfig.task_params``)."""
    n_trials: int = 1
    n_steps: int | None = None
    seed: int = 0
    """The first seed."""
    n_seeds: int = 1
    """Seeds ``seed .. seed+n_seeds-1``: each an independent set of trials, one row per point and seed."""
    backend: str = "mujoco"
    block: int = 100
    sample_seed: int = 0
    """Seed of the random draws (apart from the runs' seeds)."""

    def check(self) -> SweepSpec:
        """The spec with the run defaults filled in; ValueError (one line) for a bad combination."""
        keys = [a.key for a in self.axes]
        repeated = sorted({k for k in keys if keys.count(k) > 1})
        if repeated:
            raise ValueError(f"sweep key {repeated[0]!r} is given twice; give each key once")
        fixed = set(self.overrides) | {TASK_PREFIX + k for k in self.task_params}
        if fixed & set(keys):
            raise ValueError(f"{sorted(fixed & set(keys))[0]!r} is both swept and fixed; drop one")
        if not self.axes:
            raise ValueError("nothing to sweep: give --grid KEY=V1,V2,... or --random KEY=LOW:HIGH")
        has_random = any(a.is_random for a in self.axes)
        check_int("--samples", self.n_samples, minimum=1 if has_random else 0)
        if self.n_samples and not has_random:
            raise ValueError("--samples needs a --random axis")
        check_int("--seeds", self.n_seeds)
        self._check_size()
        base = self.base_config(self.seed).resolved()
        return dataclasses.replace(self, preset=base.preset, n_steps=base.n_steps)

    def _check_size(self) -> None:
        """Refuse, by arithmetic before any point is listed, a sweep of more than ``MAX_RUNS`` runs."""
        n_points = math.prod(len(a.values) for a in self.axes if not a.is_random) * max(self.n_samples, 1)
        if n_points * self.n_seeds > MAX_RUNS:
            raise ValueError(f"the sweep is {n_points} point(s) at {self.n_seeds} seed(s), {n_points * self.n_seeds} "
                             f"runs, more than the {MAX_RUNS} a sweep holds; give fewer values, --samples or --seeds")

    def seeds(self) -> range:
        """The run seeds of every point."""
        return range(self.seed, self.seed + self.n_seeds)

    @classmethod
    def around(cls, base: RunConfig, axes: tuple[Axis, ...], *, n_seeds: int = 1, n_samples: int = 0,
               sample_seed: int = 0) -> SweepSpec:
        """The sweep of ``axes`` around a run configuration (its seed is the first seed)."""
        return cls(task=base.task, learner=base.learner, preset=base.preset, axes=axes, n_samples=n_samples,
                   overrides=dict(base.overrides), task_params=dict(base.task_params), n_trials=base.n_trials,
                   n_steps=base.n_steps, seed=base.seed, n_seeds=n_seeds, backend=base.backend,
                   block=base.block, sample_seed=sample_seed)

    def base_config(self, seed: int) -> RunConfig:
        return RunConfig(
            task=self.task, learner=self.learner, preset=self.preset, overrides=dict(self.overrides),
            task_params=dict(self.task_params), n_trials=self.n_trials, n_steps=self.n_steps, seed=seed,
            backend=self.backend, block=self.block,
        )

    def points(self) -> list[dict[str, str]]:
        """Every point as ``{key: value}`` over the swept keys, grid order first, then the draws."""
        grid = [a for a in self.axes if not a.is_random]
        random = [a for a in self.axes if a.is_random]
        rng = np.random.default_rng(self.sample_seed)
        draws = [{a.key: a.draw(rng) for a in random} for _ in range(self.n_samples)] or [{}]
        combos = itertools.product(*(a.values for a in grid))
        return [{**dict(zip((a.key for a in grid), combo, strict=True)), **draw}
                for combo in combos for draw in draws]

    def config(self, point: dict[str, str], seed: int) -> RunConfig:
        """The resolved run configuration of ``point`` at ``seed``: its text values read here, once.

        Raises:
          ValueError: an unknown key or a bad value (one line, as ``somarm train`` gives it).
        """
        from somarm import learners
        from somarm.learners.settings import parse_settings

        overrides = parse_settings(learners.config_class(self.learner),
                                   {k: v for k, v in point.items() if not k.startswith(TASK_PREFIX)})
        task_params = parse_task_params(self.task, {k[len(TASK_PREFIX):]: v for k, v in point.items()
                                                    if k.startswith(TASK_PREFIX)}, "--grid task.KEY")
        base = self.base_config(seed)
        return dataclasses.replace(
            base, overrides={**base.overrides, **overrides}, task_params={**base.task_params, **task_params}
        ).resolved()

    def fixed_texts(self) -> dict[str, str]:
        """The settings fixed for every point as text by sweep key (``alpha``, ``task.radius``)."""
        from somarm import tasks
        from somarm.learners.settings import format_settings

        return {**format_settings(self.overrides),
                **{TASK_PREFIX + k: tasks.format_param(v) for k, v in self.task_params.items()}}

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (``sweep.json``): the fixed settings as their ``--set``/``--task-set`` text."""
        from somarm import tasks
        from somarm.learners.settings import format_settings

        return {**dataclasses.asdict(self), "overrides": format_settings(self.overrides),
                "task_params": {k: tasks.format_param(v) for k, v in self.task_params.items()}}


def config_key(config: RunConfig) -> str:
    """A short stable name of a resolved run configuration (the file name of its result).

    Named by the settings as ``somarm train`` takes them (the learner settings and task parameters
    as their text; the learner config follows from the preset and them), so one point keeps its
    name however it was written (``alpha=1`` and ``alpha=1.0``).
    """
    from somarm import tasks

    data = config.to_dict()
    data.pop("learner_config", None)
    data["task_params"] = {k: tasks.format_param(v) for k, v in config.task_params.items()}
    text = json.dumps(data, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def preset_value(spec: SweepSpec, key: str) -> str | None:
    """The value ``key`` has in the spec's preset (or the task's defaults), as ``--set`` text.

    None where the preset has no single value for it (e.g. ``decay`` when schedules differ).
    """
    from somarm import tasks
    from somarm.learners import presets
    from somarm.learners.schedules import Schedule

    if key.startswith(TASK_PREFIX):
        name = key[len(TASK_PREFIX):]
        fields = {f.name: f for f in dataclasses.fields(tasks.record(spec.task).params)}
        if name not in fields or fields[name].default is dataclasses.MISSING:
            return None
        return json.dumps(fields[name].default)
    config = presets.config_for(spec.learner, spec.preset)
    name, _, part = key.partition(".")
    if key == "decay":
        decays = {_decay_text(getattr(config, s).decay) for s in config.SCHEDULES}
        return decays.pop() if len(decays) == 1 else None
    value = getattr(config, name, None)
    if isinstance(value, Schedule):
        if part in ("", "scale"):
            return f"{value.scale:g}"
        return f"{value.floor:g}" if part == "floor" else _decay_text(value.decay)
    if isinstance(value, tuple) and name.endswith("_shape"):
        return "x".join(str(v) for v in value)
    return None if value is None else str(value).lower() if isinstance(value, bool) else str(value)


def _decay_text(decay) -> str:
    """A decay as the shortest ``--set`` text (``inv:1000``, not ``inv:1000.0``)."""
    from somarm.learners.settings import format_setting

    return format_setting(decay)


def same_value(a: str, b: str) -> bool:
    """Two ``--set`` values mean the same (``1`` and ``1.0``; ``inv:1000`` and ``inv:1000.0``)."""
    from somarm.learners.schedules import parse_decay

    for parse in (float, parse_decay):
        try:
            return parse(a) == parse(b)
        except ValueError:
            pass
    return a.strip().lower() == b.strip().lower()
