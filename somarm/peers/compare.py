"""``somarm compare``: somarm's learners beside Stable-Baselines3's TD3 and SAC on one task.

Every learner trains on the same task with the same seeds (seed s: the task's observations of
``tasks.make(task, seed=s)``, one trial), and at each rung of a ladder of sample counts its greedy
policy is scored on the same fresh observations (the evaluation stream of ``--eval-seed``). The
error is minus the mean reward (a distance for the arms, ``|X - landing|`` for the throws). Wall
time counts training only, not the scoring. somarm's learners use the task's preset (tabular: its
own defaults); TD3 and SAC use SB3's defaults through ``somarm.peers.gym``, with torch on one thread
(somarm's learners use one core too), and every setting is written into ``compare.json``.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from somarm import __version__, tasks
from somarm.io import atomic_write_json
from somarm.run import evaluation

__all__ = ["OURS", "PEERS", "LEARNERS", "CompareConfig", "ladder", "check", "compare", "peers_missing",
           "task_defaults"]

OURS = ("somq", "motoric", "tabular")
PEERS = ("td3", "sac")
LEARNERS = OURS + PEERS
_PEER_FIELDS = ("learning_rate", "buffer_size", "learning_starts", "batch_size", "tau", "gamma", "train_freq",
                "gradient_steps", "action_noise", "policy_kwargs", "ent_coef", "target_entropy",
                "policy_delay", "target_policy_noise", "target_noise_clip", "device")


@dataclass(frozen=True)
class CompareConfig:
    """One comparison; saved in ``compare.json``."""

    task: str
    """Registered task name."""
    learners: tuple[str, ...] = LEARNERS
    """Learners to train, from somq, motoric, tabular, td3, sac."""
    samples: int = 10_000
    """Training samples (one-step episodes) for somarm's learners."""
    peer_samples: int | None = None
    """Training samples for TD3 and SAC (None = ``samples``); they cost about 20 ms each."""
    seeds: int = 3
    """How many seeds: ``seed .. seed + seeds - 1``, the same for every learner."""
    seed: int = 0
    """The first seed."""
    observations: int = 1000
    """Fresh observations each greedy policy is scored on."""
    eval_seed: int = 0
    """Seed of the fresh observations (the same for every learner, rung and seed)."""
    task_params: dict[str, Any] = field(default_factory=dict)
    """Task parameters changed from their defaults."""


def peers_missing() -> str | None:
    """Why TD3 and SAC cannot run here (the missing package), or None when they can."""
    try:
        import gymnasium  # noqa: F401
        import stable_baselines3  # noqa: F401
        import torch  # noqa: F401
    except ImportError as exc:
        return (f"td3 and sac need the optional extra 'peers' ({exc.name} is missing): "
                f"pip install -e \".[peers]\" (see the README for a CPU-only torch)")
    return None


def ladder(samples: int) -> list[int]:
    """Sample counts where the policies are scored: 100, 200, 500, 1000, ... below ``samples``, then it."""
    rungs = [m * 10**k for k in range(2, 12) for m in (1, 2, 5)]
    return [r for r in rungs if r < samples] + [int(samples)]


def _bounds(task) -> dict[str, np.ndarray]:
    return dict(observation_low=task.observation_low, observation_high=task.observation_high,
                action_low=task.action_low, action_high=task.action_high, action_periodic=task.action_periodic)


def task_defaults(task: str) -> tuple[str, int]:
    """The task's default preset and run length (somarm's learners train that long in the report)."""
    record = tasks.record(task)
    return record.preset, record.n_steps


def _our_config(kind: str, task: str):
    from somarm.learners import presets
    from somarm.learners.tabular import TabularConfig

    return TabularConfig() if kind == "tabular" else presets.config_for(kind, task_defaults(task)[0])


def check(config: CompareConfig) -> list[str]:
    """Fail fast: the learners that can run, or a one-line ValueError naming what cannot.

    Raises:
      ValueError: an unknown task or learner, bad counts, a learner that cannot take the task
        (tabular on reach20), or TD3/SAC without the ``peers`` extra.
    """
    from somarm import learners
    from somarm.validation import check_int

    for name in ("samples", "seeds", "observations"):
        check_int(f"--{name}", getattr(config, name))
    if config.peer_samples is not None:
        check_int("--peer-samples", config.peer_samples)
    check_int("--seed", config.seed, minimum=0)
    check_int("eval_seed", config.eval_seed, minimum=0)
    unknown = [k for k in config.learners if k not in LEARNERS]
    if unknown or not config.learners:
        raise ValueError(f"unknown learner(s) {', '.join(unknown) or '(none given)'}; allowed: {', '.join(LEARNERS)}")
    if tasks.record(config.task).episodic:
        one_step = [name for name in tasks.names() if not tasks.record(name).episodic]
        raise ValueError(f"{config.task} has multi-step episodes; compare takes the one-step tasks: "
                         f"{', '.join(one_step)}")
    task = tasks.make(config.task, **config.task_params)
    for kind in config.learners:
        if kind in OURS:
            try:
                learners.make(kind, _our_config(kind, config.task), **_bounds(task))
            except ValueError as exc:
                raise ValueError(f"{kind} cannot learn {config.task}: {exc}") from None
    if any(k in PEERS for k in config.learners) and (reason := peers_missing()):
        raise ValueError(reason)
    return list(config.learners)


def _score(predict, task, observations: np.ndarray) -> float:
    """Mean error (minus the mean reward) of a greedy policy on ``observations (n, obs_dim)``."""
    return float(-task.evaluate(observations, predict(observations)).mean())


def _run_ours(kind: str, config: CompareConfig, seed: int, rungs: list[int], observations: np.ndarray,
              *, warm_up: bool = False):
    from somarm import learners

    task = tasks.make(config.task, seed=seed, **config.task_params)
    settings = _our_config(kind, config.task)
    learner = learners.make(kind, settings, **_bounds(task), seed=seed)
    if warm_up:  # untimed: numba compiles SOM-Q's kernels on first use
        spare = learners.make(kind, settings, **_bounds(task), seed=seed)
        spare.learn(task.evaluate(observations[:1], spare.act(observations[:1])))
        spare.predict(observations[None, :2])
    errors, walls, wall, done = [], [], 0.0, 0
    for rung in rungs:
        start = time.perf_counter()
        for _ in range(rung - done):
            learner.learn(task.step(learner.act(task.reset())))
        wall += time.perf_counter() - start
        done = rung
        task.set_step(done)  # moving goals (four_goals): score in the phase reached
        errors.append(_score(lambda x: learner.predict(x[None])[0], task, observations))
        walls.append(wall)
    return errors, walls, settings.to_dict()


def _run_peer(kind: str, config: CompareConfig, seed: int, rungs: list[int], observations: np.ndarray,
              *, warm_up: bool = False):
    import gymnasium
    import stable_baselines3
    import torch

    from somarm.peers.gym import env_id, to_task_actions

    torch.set_num_threads(1)
    env = gymnasium.make(env_id(config.task), **config.task_params)
    algorithm = {"td3": stable_baselines3.TD3, "sac": stable_baselines3.SAC}[kind]
    if warm_up:  # untimed: torch builds its kernels on the first gradient step
        algorithm("MlpPolicy", env, seed=seed, device="cpu", learning_starts=1, batch_size=2).learn(3)
    model = algorithm("MlpPolicy", env, seed=seed, device="cpu")
    task = env.unwrapped.task

    def predict(x: np.ndarray) -> np.ndarray:
        actions, _ = model.predict(x.astype(np.float32), deterministic=True)
        return to_task_actions(actions, task.action_low, task.action_high)

    errors, walls, wall, done = [], [], 0.0, 0
    for rung in rungs:
        start = time.perf_counter()
        model.learn(total_timesteps=rung - done, reset_num_timesteps=done == 0)
        wall += time.perf_counter() - start
        done = rung
        errors.append(_score(predict, env.unwrapped.task, observations))
        walls.append(wall)
    settings = {name: repr(getattr(model, name)) for name in _PEER_FIELDS if hasattr(model, name)}
    settings.update(policy="MlpPolicy", net_arch=repr(model.policy.net_arch if hasattr(model.policy, "net_arch")
                                                       else None), torch_threads=1,
                    stable_baselines3=stable_baselines3.__version__, torch=torch.__version__,
                    environment=env_id(config.task) + " (actions in [-1, 1] mapped to the task's box)")
    env.close()
    return errors, walls, settings


def compare(config: CompareConfig, out: Path, *, progress: bool = True) -> dict[str, Any]:
    """Train every learner on every seed, write ``out/compare.json`` and ``out/compare.png``.

    ``compare.json`` is rewritten (atomically) after each learner, so an interruption keeps what
    finished (``"complete": false``).

    Returns:
      The ``compare.json`` content: per learner ``samples`` (the ladder), ``error`` (rung x seed),
      ``wall_seconds`` (rung x seed, training only), ``seconds_per_sample`` and ``settings``.

    Raises:
      ValueError: as ``check``. KeyboardInterrupt: after writing what finished.
    """

    from somarm.peers.figure import compare_figure  # matplotlib loads only when a figure is drawn

    learners = check(config)
    eval_task = tasks.make(config.task, **config.task_params)
    observations = eval_task.sample_observations(evaluation.evaluation_rng(config.eval_seed), config.observations)
    rng = np.random.default_rng(config.eval_seed)
    random_actions = rng.uniform(eval_task.action_low, eval_task.action_high, (len(observations), eval_task.action_dim))
    result: dict[str, Any] = {
        "task": config.task, "task_params": config.task_params, "seeds": list(range(config.seed, config.seed + config.seeds)),
        "observations": config.observations, "eval_seed": config.eval_seed,
        "random_action_error": float(-eval_task.evaluate(observations, random_actions).mean()),
        "somarm_version": __version__, "complete": False, "learners": {},
    }
    out.mkdir(parents=True, exist_ok=True)
    for kind in learners:
        samples = config.peer_samples if kind in PEERS and config.peer_samples else config.samples
        rungs = ladder(samples)
        runner = _run_peer if kind in PEERS else _run_ours
        errors, walls, settings = [], [], {}
        for seed in range(config.seed, config.seed + config.seeds):
            e, w, settings = runner(kind, config, seed, rungs, observations, warm_up=seed == 0)
            errors.append(e)
            walls.append(w)
            if progress:
                print(f"{config.task}/{kind} seed {seed}: {samples} samples in {w[-1]:.1f} s, "
                      f"greedy error {e[-1]:.4g}", file=sys.stderr, flush=True)
        walls_array = np.array(walls)
        result["learners"][kind] = {
            "samples": rungs,
            "error": np.array(errors).T.tolist(),
            "wall_seconds": walls_array.T.tolist(),
            "seconds_per_sample": (walls_array[:, -1] / samples).tolist(),
            "settings": settings,
        }
        atomic_write_json(out / "compare.json", result)
    result["complete"] = True
    atomic_write_json(out / "compare.json", result)
    compare_figure(result, out / "compare.png")
    return result
