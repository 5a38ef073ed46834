"""The learner file format: one ``.npz`` of arrays plus a JSON ``meta`` string, checked on reading.

``meta`` holds the kind, config, bounds, periodic action dimensions (files written before
them lack the key: none periodic), seed, trial ids, step count and random-stream positions
(``LearnerBase.save`` writes it). A damaged file (valid npz, wrong contents) is refused in one
line naming the file and the key, never with a KeyError or TypeError from deep inside a load.
"""

from __future__ import annotations

import json
import os
import zipfile
from typing import Any

import numpy as np

from somarm.io import atomic_save_npz

__all__ = ["write", "read_file", "check_meta", "restore"]

#: What a learner file's meta JSON holds: key -> (JSON type(s), what it is), checked on load.
_META_KEYS: dict[str, tuple[tuple[type, ...], str]] = {
    "kind": ((str,), "a learner kind"),
    "config": ((dict,), "a JSON object of learner settings"),
    "bounds": ((list,), "four lists: observation low, high, action low, high"),
    "n_trials": ((int,), "a whole number"),
    "seed": ((int,), "a whole number"),
    "trial_ids": ((list,), "a list of whole numbers"),
    "t": ((int,), "a whole number"),
    "pending": ((bool,), "true or false"),
    "streams": ((dict,), "a JSON object with width, block, pos and bit_generators"),
}
_STREAM_KEYS = ("width", "block", "pos", "bit_generators")


def write(learner: Any, path: str | os.PathLike, arrays: dict[str, np.ndarray]) -> None:
    """Write ``learner``'s meta (kind, config, bounds, seed, trial ids, step, streams) and ``arrays``
    atomically to ``path``: the one writer of the format that ``read_file`` reads."""
    streams = learner._streams.get_state()
    meta = {
        "kind": learner.kind,
        "config": learner.config.to_dict(),
        "bounds": [b.tolist() for b in (learner.observation_low, learner.observation_high,
                                        learner.action_low, learner.action_high)],
        "periodic": learner.action_periodic.tolist(),
        "n_trials": learner.n_trials,
        "seed": learner.seed,
        "trial_ids": learner.trial_ids.tolist(),
        "t": learner.t,
        "pending": learner._pending,
        "streams": {key: value for key, value in streams.items() if key != "buffer"},
    }
    atomic_save_npz(path, meta=np.array(json.dumps(meta)), stream_buffer=streams["buffer"], **arrays)


def check_meta(meta: Any, path: str | os.PathLike) -> dict[str, Any]:
    """The meta JSON of a learner file, checked key by key; ValueError naming the file and the key.

    The kind is checked to be a string only: the registry (``somarm.learners.load``) says whether
    it is a known one.

    Args:
      meta: the parsed JSON.
      path: the file, for the message.
    """
    if not isinstance(meta, dict):
        raise ValueError(f"{path} is a damaged learner file: its meta is a JSON {type(meta).__name__}, "
                         "not an object")
    for key, (types, what) in _META_KEYS.items():
        value = meta.get(key)
        if key not in meta or not isinstance(value, types) or (bool not in types and isinstance(value, bool)):
            found = "missing" if key not in meta else f"{value!r:.40}"
            raise ValueError(f"{path} is a damaged learner file: meta {key!r} must be {what}, got {found}")
    missing = [key for key in _STREAM_KEYS if key not in meta["streams"]]
    if missing:
        raise ValueError(f"{path} is a damaged learner file: meta 'streams' lacks {', '.join(missing)}")
    if len(meta["bounds"]) != 4:
        raise ValueError(f"{path} is a damaged learner file: meta 'bounds' must be four lists, "
                         f"got {len(meta['bounds'])}")
    return meta


def read_file(path: str | os.PathLike) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """``(meta, arrays)`` of a saved learner; ValueError for a missing, damaged or foreign file."""
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
        meta = json.loads(str(arrays.pop("meta")))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        reason = "not a learner file (or a damaged one)" if "pickle" in str(exc) else str(exc)
        raise ValueError(f"cannot read a learner from {path}: {reason}") from None
    except RecursionError:  # JSON nested beyond Python's limit
        raise ValueError(f"cannot read a learner from {path}: its meta is nested too deeply") from None
    return check_meta(meta, path), arrays


def restore(learner_class: type, path: str | os.PathLike):
    """A ``learner_class`` learner in the state saved at ``path`` (``LearnerBase.load``).

    Raises:
      ValueError: the file is missing, unreadable, damaged or holds another kind (one line naming it).
    """
    meta, arrays = read_file(path)
    if meta["kind"] != learner_class.kind:
        raise ValueError(f"{path} holds a {meta['kind']} learner, not {learner_class.kind}")
    try:
        return _restore(learner_class, meta, arrays, path)
    except (KeyError, TypeError, AttributeError, IndexError, OverflowError, ValueError) as exc:
        # Whatever a damaged file breaks, say which file and what, in one line.
        lines = str(exc).strip().splitlines()
        reason = f"lacks {exc}" if isinstance(exc, KeyError) else (lines[-1] if lines else type(exc).__name__)
        if str(path) in reason:
            raise ValueError(reason) from None
        raise ValueError(f"{path} is a damaged learner file: {reason}") from None


def _restore(cls: type, meta: dict[str, Any], arrays: dict[str, np.ndarray], path):
    low_s, high_s, low_a, high_a = meta["bounds"]
    learner = cls(cls.config_class.from_dict(meta["config"]), observation_low=low_s,
                  observation_high=high_s, action_low=low_a, action_high=high_a,
                  n_trials=meta["n_trials"], seed=meta["seed"], trial_ids=meta["trial_ids"],
                  action_periodic=meta.get("periodic"))
    for name in cls._STATE_ARRAYS + cls._PENDING_ARRAYS + ("stream_buffer",):
        if name not in arrays and name not in cls._OPTIONAL_ARRAYS:
            raise ValueError(f"{path} is a damaged learner file: array {name!r} is missing")
    for name in cls._STATE_ARRAYS + cls._PENDING_ARRAYS:
        if name not in arrays:  # an optional array the file predates: the fresh learner's value stays
            continue
        target = getattr(learner, name)
        if arrays[name].shape != target.shape:
            raise ValueError(f"{path}: {name} has shape {arrays[name].shape}, expected {target.shape}")
        allowed = {"b": "b", "i": "iu", "u": "iu", "f": "fiu"}.get(target.dtype.kind, arrays[name].dtype.kind)
        if arrays[name].dtype.kind not in allowed:
            what = {"b": "true or false", "iu": "whole numbers"}.get(allowed, "real numbers")
            raise ValueError(f"{path} is a damaged learner file: {name} must hold {what}, "
                             f"got {arrays[name].dtype}")
        if name in cls._STATE_ARRAYS and arrays[name].dtype.kind == "f" and not np.isfinite(arrays[name]).all():
            raise ValueError(f"{path} is a damaged learner file: {name} holds NaN or infinite values "
                             "(a learned state is finite)")
        target[...] = arrays[name]
    learner.t, learner._pending = int(meta["t"]), bool(meta["pending"])
    learner._streams.set_state({**meta["streams"], "buffer": arrays["stream_buffer"]})
    learner._check_restored()
    return learner
