"""TD3's and SAC's settings for a Gymnasium environment: RL Baselines3 Zoo's tuned ones where the Zoo
has them, else Stable-Baselines3's defaults (with Gaussian action noise of 0.1 for TD3).

The Zoo's hyperparameters are read from the YAML files that the ``rl-zoo3`` package ships (the
package itself is never imported). ``settings(kind, env_id)`` turns an entry into the keywords of
``stable_baselines3.TD3``/``SAC`` and the Zoo's training budget; what each value is and where it
came from goes into ``compare.json``.

The Zoo's published results for the environments of the benchmarks part, quoted as the Zoo's
benchmark table gives them (mean return ± sd over its evaluation episodes, after n_timesteps):
``PUBLISHED``.
"""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["PUBLISHED", "THRESHOLDS", "zoo_entry", "defaults", "settings"]

#: RL Baselines3 Zoo's benchmark table: (algorithm, env) -> (mean return, sd, timesteps), as published.
PUBLISHED: dict[tuple[str, str], tuple[float, float, int]] = {
    ("td3", "Pendulum-v1"): (-152.0, 90.0, 20_000),
    ("sac", "Pendulum-v1"): (-157.0, 89.0, 20_000),
    ("sac", "MountainCarContinuous-v0"): (94.7, None, 50_000),
    ("td3", "MountainCarContinuous-v0"): (93.5, None, 300_000),
}
#: Gymnasium's reward thresholds (``env.spec.reward_threshold``) where it sets one, as registered.
THRESHOLDS = {"InvertedPendulum-v5": 950.0, "Reacher-v5": -3.75, "MountainCarContinuous-v0": 90.0}

#: Zoo keys that change the environment or the training loop rather than the algorithm. The peers train
#: one copy of the environment as Gymnasium makes it, so these are not applied; an entry that sets one
#: says so in its source (``"rl-zoo3 2.x, without its normalize"``), which ``compare.json`` keeps.
_NOT_APPLIED = ("normalize", "env_wrapper", "callback", "frame_stack", "n_envs")
#: Zoo keys that are not keywords of the algorithm: read here (budget, noise) or not applied.
_NOT_KEYWORDS = ("n_timesteps", "policy", "noise_type", "noise_std") + _NOT_APPLIED


class LinearSchedule:
    """The Zoo's ``lin_X`` learning rate: X times the fraction of training still to go (SB3 calls it
    with that fraction, 1 at the start and 0 at the end). Written as the Zoo writes it."""

    def __init__(self, initial: float):
        self.initial = float(initial)

    def __call__(self, progress_remaining: float) -> float:
        return progress_remaining * self.initial

    def __repr__(self) -> str:
        return f"lin_{self.initial:g}"


def _learning_rate(value: Any, kind: str, env_id: str) -> Any:
    """A Zoo learning rate: a number as it is, ``lin_X`` as a ``LinearSchedule``.

    Raises:
      ValueError: any other text (one line).
    """
    if not isinstance(value, str):
        return value
    try:
        if value.startswith("lin_"):
            return LinearSchedule(float(value[4:]))
    except ValueError:
        pass
    raise ValueError(f"the Zoo's learning_rate for {kind} on {env_id} is {value!r}; "
                     "this reader takes a number or lin_NUMBER")


def _zoo_folder() -> Path | None:
    spec = importlib.util.find_spec("rl_zoo3")
    if spec is None or spec.origin is None:
        return None
    return Path(spec.origin).parent / "hyperparams"


def zoo_entry(kind: str, env_id: str) -> dict[str, Any] | None:
    """The Zoo's hyperparameters of algorithm ``kind`` (td3, sac) for ``env_id``, or None if it has none.

    Raises:
      ValueError: rl-zoo3 or pyyaml is not installed (one line naming the extra).
    """
    folder = _zoo_folder()
    try:
        import yaml
    except ImportError:
        folder = None
    if folder is None:
        from somarm.extras import missing

        raise missing("peers", "the Zoo's hyperparameters need the optional extra 'peers' (rl-zoo3 and pyyaml)")
    with open(folder / f"{kind}.yml") as handle:
        table = yaml.safe_load(handle)
    return table.get(env_id)


def _policy_kwargs(text: str) -> dict[str, Any]:
    """A Zoo ``policy_kwargs`` string such as ``"dict(net_arch=[400, 300])"`` read as literals only."""
    tree = ast.parse(text, mode="eval").body
    if not (isinstance(tree, ast.Call) and getattr(tree.func, "id", None) == "dict" and not tree.args):
        raise ValueError(f"cannot read the Zoo's policy_kwargs {text!r}")
    return {k.arg: ast.literal_eval(k.value) for k in tree.keywords}


def defaults(kind: str, action_dim: int) -> tuple[dict[str, Any], str]:
    """SB3's defaults, with Gaussian action noise of sd 0.1 for TD3 (SB3's TD3 adds none by default,
    and without it TD3 explores only through its initial random steps), and their description."""
    from stable_baselines3.common.noise import NormalActionNoise

    if kind == "td3":
        return ({"action_noise": NormalActionNoise(np.zeros(action_dim), 0.1 * np.ones(action_dim))},
                "SB3 defaults with Gaussian action noise 0.1")
    return {}, "SB3 defaults"


def settings(kind: str, env_id: str, action_dim: int) -> tuple[dict[str, Any], int | None, str]:
    """The keywords of ``stable_baselines3.TD3``/``SAC`` for ``env_id``, the Zoo's budget (None where
    the Zoo has no entry) and where they came from (``"rl-zoo3 <version>"`` or ``"SB3 defaults"``).

    Raises:
      ValueError: as ``zoo_entry``; a Zoo entry this reader does not understand (one line).
    """
    from stable_baselines3.common.noise import NormalActionNoise, OrnsteinUhlenbeckActionNoise

    entry = zoo_entry(kind, env_id)
    if entry is None:
        keywords, source = defaults(kind, action_dim)
        return keywords, None, source
    keywords = {key: value for key, value in entry.items() if key not in _NOT_KEYWORDS}
    if isinstance(keywords.get("policy_kwargs"), str):
        keywords["policy_kwargs"] = _policy_kwargs(keywords["policy_kwargs"])
    if "learning_rate" in keywords:
        keywords["learning_rate"] = _learning_rate(keywords["learning_rate"], kind, env_id)
    for key in ("buffer_size", "learning_starts", "batch_size", "tau", "gamma"):
        if isinstance(keywords.get(key), str):
            raise ValueError(f"the Zoo's {key} for {kind} on {env_id} is {keywords[key]!r}; "
                             "this reader takes numbers")
    noise, std = entry.get("noise_type"), entry.get("noise_std")
    if noise == "normal":
        keywords["action_noise"] = NormalActionNoise(np.zeros(action_dim), std * np.ones(action_dim))
    elif noise == "ornstein-uhlenbeck":
        keywords["action_noise"] = OrnsteinUhlenbeckActionNoise(np.zeros(action_dim), std * np.ones(action_dim))
    elif noise is not None:
        raise ValueError(f"the Zoo's noise_type {noise!r} for {kind} on {env_id} is not one this reader knows")
    from importlib.metadata import version

    skipped = [key for key in _NOT_APPLIED if key in entry and not (key == "n_envs" and entry[key] == 1)]
    source = f"rl-zoo3 {version('rl-zoo3')}" + (f", without its {', '.join(skipped)}" if skipped else "")
    return keywords, int(entry["n_timesteps"]), source
