"""Annealing schedules: a parameter's value at step t is ``max(floor, scale * f(t))``.

Every plastic or exploratory parameter of the paper (alpha, lambda_S, lambda_A, N_S, N_A,
p, epsilon) is a scale times a shared decay f(t), sometimes with a minimum value (Tables 2
and 4). ``t`` counts learning steps from 0, so the first step uses ``f(0) = 1``: the scale.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from somarm.validation import check_number, parse_float, parse_int

__all__ = [
    "Constant",
    "InverseDecay",
    "ExponentialDecay",
    "Decay",
    "Schedule",
    "parse_decay",
    "parse_bool",
    "parse_shape",
]


@dataclass(frozen=True)
class Constant:
    """f(t) = 1: the parameter keeps its scale for ever."""

    def __call__(self, t: Any) -> Any:
        return np.ones_like(np.asarray(t, dtype=np.float64))[()]

    def scalar(self, t: int) -> float:
        return 1.0

    def __str__(self) -> str:
        return "1"

    def to_text(self) -> str:
        return "const"


@dataclass(frozen=True)
class InverseDecay:
    """f(t) = 1 / (t/tau + 1), the schedule of Tables 1 and 2 (tau = 1000 and 500).

    Args:
      tau: steps until f has halved (> 0).
    """

    tau: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "tau", check_number("decay tau", self.tau, minimum=0.0, strict_minimum=True))

    def __call__(self, t: Any) -> Any:
        return (1.0 / (np.asarray(t, dtype=np.float64) / self.tau + 1.0))[()]

    def scalar(self, t: int) -> float:
        return 1.0 / (t / self.tau + 1.0)

    def __str__(self) -> str:
        return f"1/(t/{self.tau:g}+1)"

    def to_text(self) -> str:
        return f"inv:{self.tau!r}"


@dataclass(frozen=True)
class ExponentialDecay:
    """f(t) = c ** t, the schedule of Tables 4, 5 and 7 (c = 0.999, 0.9985, 0.9997).

    Args:
      c: the factor per step, in (0, 1].
    """

    c: float

    def __post_init__(self) -> None:
        c = check_number("decay c", self.c, minimum=0.0, maximum=1.0, strict_minimum=True)
        object.__setattr__(self, "c", c)

    def __call__(self, t: Any) -> Any:
        return np.power(self.c, np.asarray(t, dtype=np.float64))[()]

    def scalar(self, t: int) -> float:
        return math.pow(self.c, t)

    def __str__(self) -> str:
        return f"{self.c:g}^t"

    def to_text(self) -> str:
        return f"exp:{self.c!r}"


Decay = Constant | InverseDecay | ExponentialDecay


def parse_decay(text: str) -> Decay:
    """A decay from its text form: ``inv:TAU``, ``exp:C`` or ``const``.

    Raises:
      ValueError: anything else (the message lists the forms).
    """
    kind, _, number = str(text).strip().partition(":")
    try:
        if kind == "const" and not number:
            return Constant()
        if kind == "inv":
            return InverseDecay(parse_float("decay", number))
        if kind == "exp":
            return ExponentialDecay(parse_float("decay", number))
    except ValueError as exc:
        raise ValueError(f"bad decay {text!r}: {exc}") from None
    raise ValueError(f"bad decay {text!r}; allowed: inv:TAU (1/(t/TAU+1)), exp:C (C^t), const")


@dataclass(frozen=True)
class Schedule:
    """A parameter's value at step t: ``max(floor, scale * decay(t))``.

    Args:
      scale: the value at t = 0 (>= 0).
      decay: ``InverseDecay``, ``ExponentialDecay`` or ``Constant`` (default: constant).
      floor: the minimum value (>= 0; Tables 2 and 4 list one for some parameters).
    """

    scale: float
    decay: Decay = Constant()
    floor: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "scale", check_number("schedule scale", self.scale, minimum=0.0))
        object.__setattr__(self, "floor", check_number("schedule floor", self.floor, minimum=0.0))
        if not isinstance(self.decay, (Constant, InverseDecay, ExponentialDecay)):
            raise ValueError(
                f"schedule decay must be InverseDecay, ExponentialDecay or Constant, got {self.decay!r}"
            )

    def __call__(self, t: Any) -> Any:
        """The value at step ``t`` (an int, or an int array for a whole curve)."""
        steps = np.asarray(t)
        if not np.issubdtype(steps.dtype, np.integer) or (steps < 0).any():
            raise ValueError(f"schedule step t must be a whole number >= 0, got {t!r}")
        return np.maximum(self.floor, self.scale * self.decay(steps))[()]

    def value(self, t: int) -> float:
        """The value at a single step ``t >= 0`` as a Python float (what the learners use).

        Plain float arithmetic, no NumPy: cheap enough to call seven times per step, and the
        one path every learner (batched, compiled, reference) reads its parameters from.
        """
        return max(self.floor, self.scale * self.decay.scalar(t))

    def __repr__(self) -> str:
        body = f"{self.scale:g}" if isinstance(self.decay, Constant) else f"{self.scale:g} x {self.decay}"
        return f"Schedule({body}" + (f", floor {self.floor:g})" if self.floor else ")")

    def with_changes(self, *, scale: float | None = None, decay: Decay | None = None,
                     floor: float | None = None) -> Schedule:
        """A copy with some of the three parts replaced."""
        return Schedule(
            self.scale if scale is None else scale,
            self.decay if decay is None else decay,
            self.floor if floor is None else floor,
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form; ``Schedule.from_dict`` gives back an equal schedule."""
        return {"scale": self.scale, "decay": self.decay.to_text(), "floor": self.floor}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Schedule:
        """Inverse of ``to_dict``."""
        return cls(d["scale"], parse_decay(d["decay"]), d.get("floor", 0.0))


def parse_bool(name: str, text: str) -> bool:
    """``true``/``false`` (also 1/0, yes/no) as a bool; ValueError naming ``name`` otherwise."""
    lowered = str(text).strip().lower()
    if lowered in ("true", "1", "yes", "on"):
        return True
    if lowered in ("false", "0", "no", "off"):
        return False
    raise ValueError(f"{name} must be true or false, got {text!r}")


def parse_shape(name: str, text: str) -> tuple[int, ...]:
    """A map shape from ``"50"``, ``"50x1"`` or ``"10x10"``; ValueError naming ``name`` otherwise."""
    parts = str(text).lower().replace(" ", "").split("x")
    try:
        shape = tuple(parse_int(name, part) for part in parts)
    except ValueError:
        raise ValueError(f"{name} must look like 50 or 10x10, got {text!r}") from None
    if not 1 <= len(shape) <= 2 or min(shape) < 1:
        raise ValueError(f"{name} must be 1 or 2 whole numbers >= 1 (like 50 or 10x10), got {text!r}")
    return shape
