"""Argument checks that fail with one clear line naming the argument and what is allowed."""

from __future__ import annotations

import argparse
import math
import re
import sys

import numpy as np

__all__ = [
    "OneLineParser",
    "parse_int",
    "parse_float",
    "whole_number",
    "number",
    "check_int",
    "check_int_list",
    "check_number",
    "check_array",
    "check_bounds",
    "check_periodic",
    "check_observation_box",
    "check_memory",
    "real_array",
]


class OneLineParser(argparse.ArgumentParser):
    """argparse that raises ``ValueError(message)`` on a usage error instead of printing usage and exiting.

    The command line's entry point turns it into its one line, ``somarm: error: ...``.
    """

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("allow_abbrev", False)  # `--seed` must never stand for `--seeds`
        super().__init__(*args, **kwargs)

    def error(self, message: str):  # noqa: D401 - argparse's signature
        raise ValueError(message)

    def parse_known_args(self, args=None, namespace=None):
        argv = list(sys.argv[1:] if args is None else args)
        self._refuse_repeats(argv)
        return super().parse_known_args(argv, namespace)

    def _refuse_repeats(self, argv: list[str]) -> None:
        """An option that takes one value, given twice, is refused (the last would win silently)."""
        single = {flag: action.dest for action in self._actions if type(action) is argparse._StoreAction
                  for flag in action.option_strings}
        seen: set[str] = set()
        for item in argv:
            if item == "--":
                break
            flag = item.split("=", 1)[0]
            if flag in single:
                if single[flag] in seen:
                    raise ValueError(f"{flag} is given twice; give it once")
                seen.add(single[flag])


#: Numbers as a user writes them: ASCII digits, no digit-group underscores (Python's int() and float()
#: also take ``1_000`` and other scripts' digits, which a typo or a pasted text can bring in).
_INT = re.compile(r"[+-]?[0-9]+")
_FLOAT = re.compile(r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)", re.IGNORECASE)


def parse_int(name: str, text: str) -> int:
    """``text`` as a whole number written with ASCII digits (``"12"``, ``"-3"``); ValueError naming ``name``."""
    if not isinstance(text, str) or not _INT.fullmatch(text.strip()):
        raise ValueError(f"{name} must be a whole number written with the digits 0-9, got {text!r}")
    return int(text)


def parse_float(name: str, text: str) -> float:
    """``text`` as a number written with ASCII digits (``"0.5"``, ``"1e-3"``); ValueError naming ``name``."""
    if not isinstance(text, str) or not _FLOAT.fullmatch(text.strip()):
        raise ValueError(f"{name} must be a number written with the digits 0-9 (such as 0.5 or 1e-3), got {text!r}")
    return float(text)


def whole_number(text: str) -> int:
    """argparse ``type`` of a whole-number option (argparse puts the option's name before the message)."""
    try:
        return parse_int("it", text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def number(text: str) -> float:
    """argparse ``type`` of a number option."""
    try:
        return parse_float("it", text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def check_int_list(name: str, text: str, *, minimum: int = 1) -> list[int]:
    """``"1,20,100" -> [1, 20, 100]``, each >= ``minimum``; ValueError naming ``name`` otherwise."""
    try:
        values = [parse_int(name, part) for part in str(text).split(",")]
    except ValueError:
        raise ValueError(f"{name} takes comma-separated whole numbers, got {text!r}") from None
    return [check_int(name, value, minimum=minimum) for value in values]


def check_int(name: str, value: object, *, minimum: int = 1) -> int:
    """``value`` as an int >= ``minimum``; ValueError naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be a whole number >= {minimum}, got {value!r}")
    return int(value)


def check_number(
    name: str, value: object, *, minimum: float | None = None, maximum: float | None = None,
    strict_minimum: bool = False,
) -> float:
    """``value`` as a finite float inside the given range; ValueError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if minimum is not None and (value <= minimum if strict_minimum else value < minimum):
        sign = ">" if strict_minimum else ">="
        raise ValueError(f"{name} must be {sign} {minimum}, got {value!r}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name} must be <= {maximum}, got {value!r}")
    return value


def real_array(name: str, value: object) -> np.ndarray:
    """``value`` as a float64 array; ValueError for anything that is not real numbers.

    Complex numbers are refused (numpy would drop their imaginary part with only a warning).
    """
    try:
        array = np.asarray(value)
        if np.iscomplexobj(array):
            raise ValueError(f"{name} must be real numbers, got complex values")
        return np.asarray(array, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        if "complex" in str(exc):
            raise
        raise ValueError(f"{name} must be an array of numbers, got {type(value).__name__}") from None


def _available_memory() -> int | None:
    """Bytes a new allocation can get: the smaller of the memory free without swapping (psutil's
    ``available``: Linux's ``MemAvailable``) and what the address-space limit (``ulimit -v``,
    ``RLIMIT_AS``) leaves; or None."""
    limits = [n for n in (_free_memory(), _address_space_left()) if n is not None]
    return min(limits) if limits else None


def _free_memory() -> int | None:
    import psutil  # here, not at the top: ``somarm --help`` does not need it

    try:
        return int(psutil.virtual_memory().available)
    except (OSError, RuntimeError, AttributeError):
        return None


def _address_space_left() -> int | None:
    """``RLIMIT_AS`` less this process's address space now (psutil's ``vms``); None without a limit."""
    try:
        import resource

        import psutil

        limit = resource.getrlimit(resource.RLIMIT_AS)[0]
        if limit == resource.RLIM_INFINITY:
            return None
        used = psutil.Process().memory_info().vms
    except (ImportError, OSError, RuntimeError):
        return None
    return max(0, limit - used)


def check_memory(what: str, n_bytes: float, hint: str) -> None:
    """Refuse, before allocating, what would not fit in the memory available now.

    Args:
      what: what needs the memory, as the user set it (``input_shape=200x200 with 1 trial(s)``).
      n_bytes: the estimate.
      hint: what to change (``use smaller maps or fewer trials``).

    Raises:
      ValueError: one line naming ``what``, the size needed and the size available.
    """
    available = _available_memory()
    if available is not None and n_bytes > available:
        raise ValueError(f"{what} needs about {_gib(n_bytes)} of memory, more than the {_gib(available)} "
                         f"available; {hint}")


def _gib(n_bytes: float) -> str:
    return f"{n_bytes / 2**30:.1f} GiB" if n_bytes >= 2**30 else f"{n_bytes / 2**20:.0f} MiB"


def check_array(name: str, value: object, shape: tuple[int | None, ...]) -> np.ndarray:
    """``value`` as a finite float64 array of ``shape`` (None matches any length).

    Raises:
      ValueError: wrong shape (both shapes are named), or NaN/inf entries.
    """
    array = real_array(name, value)
    if array.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(array.shape, shape, strict=True)
    ):
        expected = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{name} must have shape {expected}, got {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite, got NaN or inf")
    return array


def check_bounds(name: str, low: object, high: object) -> tuple[np.ndarray, np.ndarray]:
    """Validate a box: 1-D finite ``low`` < ``high`` elementwise, same length."""
    low_arr = check_array(f"{name} low", np.atleast_1d(low), (None,))
    high_arr = check_array(f"{name} high", np.atleast_1d(high), low_arr.shape)
    if low_arr.size == 0:
        raise ValueError(f"{name} bounds must have at least one dimension")
    if not (low_arr < high_arr).all():
        raise ValueError(f"{name} bounds need low < high in every dimension, got {low_arr} and {high_arr}")
    return low_arr, high_arr


def check_periodic(value: object, size: int) -> np.ndarray:
    """Which dimensions of a box are periodic: ``(size,)`` bools; None means none of them.

    A periodic dimension's low and high are the same point (a joint angle in [-pi, pi]), so
    ``high - low`` is one period.

    Raises:
      ValueError: not ``size`` booleans (one line).
    """
    if value is None:
        return np.zeros(size, dtype=np.bool_)
    array = np.asarray(value)
    if array.shape != (size,) or array.dtype != np.bool_:
        raise ValueError(f"action_periodic must be {size} booleans (one per action dimension), got {value!r:.60}")
    return array.copy()


def check_observation_box(task: str, low: np.ndarray, high: np.ndarray) -> None:
    """Refuse an observation Box with a flat dimension (``low == high``): a value that never changes says
    nothing, and scaling it onto ``[0, 1]`` divides by zero (the non-finite observations it would give
    are not the environment's). Infinite bounds pass (they are estimated).

    Raises:
      ValueError: one line naming the task and the flat dimensions.
    """
    low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    flat = [int(k) for k in np.flatnonzero(np.isfinite(low) & (low == high))]
    if flat:
        shown = ", ".join(f"{low[k]:g}" for k in flat[:4])
        raise ValueError(f"{task}'s observation Box has low == high in dimension(s) {flat} ({shown}): such a "
                         "dimension never changes and cannot be scaled; wrap the environment to drop it "
                         "(gymnasium.wrappers), or give an environment whose every dimension varies")
