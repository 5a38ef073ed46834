"""``somarm compare``: somarm's learners beside Stable-Baselines3's TD3 and SAC on one task.

Every learner trains on the same task with the same seeds (seed s: the task's observations of
``tasks.make(task, seed=s)``, one trial), and at each rung of a ladder of sample counts its greedy
policy is scored on the same fresh observations (the evaluation stream of ``--eval-seed``). The
error is minus the mean reward (a distance for the arms, ``|X - landing|`` for the throws). Wall
time counts training only, not the scoring. somarm's learners use the task's preset (tabular: its
own defaults); TD3 and SAC use RL Baselines3 Zoo's tuned settings and budget for a ``gym:ID`` the Zoo
covers, else SB3's defaults (TD3 with Gaussian action noise 0.1; ``somarm.peers.zoo``), with torch on
one thread (somarm's learners use one core too), and every setting is written into ``compare.json``.
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from somarm import __version__, tasks
from somarm.io import atomic_write_json, make_folder, read_json
from somarm.run import evaluation
from somarm.tasks import gym_envs

__all__ = ["OURS", "PEERS", "LEARNERS", "CompareConfig", "Plan", "OurRunner", "PeerRunner", "make_plan", "ladder", "decisions",
           "check", "compare", "peers_missing", "peer_budget", "default_samples", "task_defaults", "run_unit",
           "engine_of_parts"]

OURS = ("somq", "somq+", "motoric", "tabular")
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
    """Training samples (steps) for somarm's learners."""
    peer_samples: int | None = None
    """Training samples for TD3 and SAC (None = the Zoo's budget for a ``gym:ID`` it covers, else ``samples``)."""
    episodes: int = 100
    """Fresh greedy episodes per score of a ``gym:ID`` task (the last rung's; earlier rungs use a fifth)."""
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
        from somarm.extras import install_command

        return f"td3 and sac need the optional extra 'peers' ({exc.name} is missing): {install_command('peers')}"
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


def _our_config(kind: str, preset: str):
    """A somarm learner's config from the task's ``preset``: the preset's (tabular: its own defaults
    with the preset's gamma, so that on a ``gym:ID`` task it learns returns, not the next reward). ``somq``
    answers with the winning action unit (the paper's response) even where the preset interpolates (the
    benchmarks' presets), so that its row and SOM-Q+'s differ; ``somq+`` takes the preset's ``+`` table
    where there is one (``table1+`` for reach2) with the interpolated response."""
    import dataclasses

    from somarm.learners import presets
    from somarm.learners.tabular import TabularConfig

    if kind == "tabular":  # its own exploration; the preset's discount (0 on the paper's one-step tasks)
        return TabularConfig(gamma=presets.get(preset).gamma)
    if kind == "somq+":
        plus = preset + "+" if preset + "+" in presets.PRESETS else preset
        return dataclasses.replace(presets.get(plus), response="interpolated")
    config = presets.config_for(kind, preset)
    return dataclasses.replace(config, response="winner") if kind == "somq" else config


@dataclass(frozen=True)
class OurRunner:
    """How one of somarm's learners trains and is scored in a comparison."""

    kind: str
    settings: Any  #: the learner's config (``SOMQConfig``, ``MotoricConfig`` or ``TabularConfig``)
    budget: int  #: training samples

    @property
    def rungs(self) -> list[int]:
        return ladder(self.budget)

    def described(self) -> dict[str, Any]:
        """What its training depends on besides the task and the seed: its config."""
        return self.settings.to_dict()

    def defaults(self) -> dict[str, Any]:
        """Its config's fields at their defaults: a field a record lacks, where it is at its default
        now, is a setting added since, which changes nothing the record holds."""
        return json.loads(json.dumps(type(self.settings)().to_dict(), default=repr))

    def fingerprint_params(self, params: dict[str, Any]) -> dict[str, Any]:
        """The task parameters its training reads: all of them (it learns on the scaled observations)."""
        return params

    def _make(self, task, seed: int):
        from somarm import learners

        return learners.make("somq" if self.kind == "somq+" else self.kind, self.settings, **_bounds(task), seed=seed)

    def run(self, plan: Plan, seed: int, score: _Scorer, *, warm_up: bool = False):
        """Train at ``seed``, scoring at every rung: ``(values, walls, settings)``; a rung's samples are the
        task's own steps (``decisions``)."""
        task = plan.task(seed)
        learner = self._make(task, seed)
        if warm_up:  # untimed: numba compiles SOM-Q's kernels on first use
            spare = self._make(task, seed)
            _train_ours(plan.task(seed), spare, 2)
            spare.predict(task.observation_low[None, None, :])
        values, walls, wall, done = [], [], 0.0, 0
        for rung in self.rungs:
            start = time.perf_counter()
            _train_ours(task, learner, decisions(rung, plan.params) - decisions(done, plan.params))
            wall += time.perf_counter() - start
            done = rung
            task.set_step(done)  # moving goals (four_goals): score in the phase reached
            score.task.set_step(done)
            values.append(score(lambda x: learner.predict(x[None])[0], last=rung == self.rungs[-1]))
            walls.append(wall)
        return values, walls, self.settings.to_dict()


@dataclass(frozen=True)
class PeerRunner:
    """How Stable-Baselines3's TD3 or SAC trains and is scored in a comparison."""

    kind: str
    budget: int  #: training samples
    gym_id: str | None  #: the Gymnasium id of a ``gym:ID`` or ``dmc:`` task (None: a somarm task's)

    @property
    def rungs(self) -> list[int]:
        return ladder(self.budget)

    def described(self) -> dict[str, Any]:
        """What its training depends on besides the task and the seed: the Zoo's entry and SB3's version."""
        import stable_baselines3

        from somarm.peers import zoo

        entry = zoo.zoo_entry(self.kind, self.gym_id) if self.gym_id else None
        return {"zoo": entry, "stable_baselines3": stable_baselines3.__version__}

    def defaults(self) -> dict[str, Any]:
        """No setting of its own has a default a record could lack (its settings are the Zoo's entry)."""
        return {}

    def fingerprint_params(self, params: dict[str, Any]) -> dict[str, Any]:
        """The task parameters its training reads: not a ``gym:ID``'s observation scaling (``_peer_params``)."""
        return _peer_params(params) if self.gym_id else params

    def _env(self, task: str, params: dict[str, Any]):
        """The Gymnasium environment it trains on, and how it is described in ``compare.json``."""
        import gymnasium

        from somarm.peers.gym import env_id

        if self.gym_id:
            return gym_envs.make_env(task, **_peer_params(params)), self.gym_id + " (its own observations and actions)"
        return gymnasium.make(env_id(task), **params), env_id(task) + " (actions in [-1, 1] mapped to the task's box)"

    def run(self, plan: Plan, seed: int, score: _Scorer, *, warm_up: bool = False):
        """Train at ``seed``, scoring at every rung: ``(values, walls, settings)``."""
        import stable_baselines3
        import torch

        from somarm.peers import zoo
        from somarm.peers.gym import to_task_actions

        torch.set_num_threads(1)
        env, described = self._env(plan.config.task, plan.params_for(self.kind))
        algorithm = {"td3": stable_baselines3.TD3, "sac": stable_baselines3.SAC}[self.kind]
        if self.gym_id:
            keywords, _, source = zoo.settings(self.kind, self.gym_id, env.action_space.shape[0])
        else:
            keywords, source = zoo.defaults(self.kind, env.action_space.shape[0])
        if warm_up:  # untimed: torch builds its kernels on the first gradient step
            algorithm("MlpPolicy", env, seed=seed, device="cpu", learning_starts=1, batch_size=2).learn(3)
        model = algorithm("MlpPolicy", env, seed=seed, device="cpu", **keywords)
        task = score.task

        def predict(x: np.ndarray) -> np.ndarray:
            if task.episodic:  # a Gymnasium task: the model acts on the environment's own observations
                actions, _ = model.predict(task.unscale(x).astype(env.observation_space.dtype), deterministic=True)
                return np.clip(np.asarray(actions, dtype=np.float64), task.action_low, task.action_high)
            actions, _ = model.predict(x.astype(np.float32), deterministic=True)
            return to_task_actions(actions, task.action_low, task.action_high)

        values, walls, wall, done = [], [], 0.0, 0
        for rung in self.rungs:
            start = time.perf_counter()
            params = plan.params_for(self.kind)
            model.learn(total_timesteps=decisions(rung, params) - decisions(done, params), reset_num_timesteps=done == 0)
            wall += time.perf_counter() - start
            done = rung
            values.append(score(predict, last=rung == self.rungs[-1]))
            walls.append(wall)
        settings = {name: repr(getattr(model, name)) for name in _PEER_FIELDS if hasattr(model, name)}
        settings.update(policy="MlpPolicy", net_arch=repr(model.policy.net_arch if hasattr(model.policy, "net_arch")
                                                           else None), torch_threads=1, source=source,
                        stable_baselines3=stable_baselines3.__version__, torch=torch.__version__,
                        environment=described)
        env.close()
        return values, walls, settings


Runner = OurRunner | PeerRunner


@dataclass(frozen=True)
class Plan:
    """One comparison resolved once (``make_plan``): the task's parameters that every learner and seed
    shares, and a runner per learner, in the order asked."""

    config: CompareConfig
    params: dict[str, Any]  #: somarm's learners' task parameters: the preset's own, then the run's
    runners: dict[str, Runner]
    #: TD3's and SAC's task parameters: the run's alone (what a preset asks of its task, such as dm_control's
    #: ``action_repeat`` or ``angles``, is its learner's choice, not the task's), completed the same way
    #: (None: ``params``, where the preset asks nothing).
    peer_params: dict[str, Any] | None = None

    @property
    def seeds(self) -> list[int]:
        return list(range(self.config.seed, self.config.seed + self.config.seeds))

    def task(self, seed: int):
        """The task of one seed (one trial)."""
        return tasks.make(self.config.task, seed=seed, **self.params)

    def params_for(self, kind: str | None) -> dict[str, Any]:
        """The task parameters learner ``kind`` trains and is scored with (None: the task as the run gives it,
        TD3's and SAC's)."""
        if self.peer_params is None or (kind is not None and kind not in PEERS):
            return self.params
        return self.peer_params

    def scorer(self, kind: str | None = None) -> _Scorer:
        """A scorer of learner ``kind``'s greedy policies (None: on the task as the run gives it); each unit its
        own (a moving goal's phase is the scorer's state). Every learner's episodes start from the same reset
        seeds, so a preset's ``action_repeat`` or ``angles`` changes how its learner acts and sees, not the
        episodes it is scored on."""
        return _Scorer(self.config, self.params_for(kind))

    def fingerprint(self, kind: str, seed: int, score: _Scorer, described: dict[str, Any] | None = None) -> dict:
        """What one learner's training and scores at one seed depend on: a seed's record is reused only
        where all of it is the same."""
        runner = self.runners[kind]
        config = self.config
        scored = {"episodes": config.episodes} if score.episodic else {"observations": config.observations}
        return json.loads(json.dumps({
            "task": config.task, "task_params": runner.fingerprint_params(self.params_for(kind)), "learner": kind,
            "seed": seed, "rungs": runner.rungs, **scored, "eval_seed": config.eval_seed,
            "settings": runner.described() if described is None else described,
            "somarm_version": __version__}, default=repr))


def make_plan(config: CompareConfig) -> Plan:
    """Check ``config`` and resolve it once: the task's record and parameters, a runner per learner.

    Raises:
      ValueError: an unknown task or learner, bad counts, a learner that cannot take the task
        (tabular on reach20), or TD3/SAC without the ``peers`` extra.
    """
    from somarm.learners import presets
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
    check_int("--episodes", config.episodes)
    record = tasks.record(config.task)
    if record.episodic and not gym_envs.env_task(config.task):
        one_step = [name for name in tasks.names() if not tasks.record(name).episodic]
        raise ValueError(f"{config.task} has multi-step episodes; compare takes gym:ID, dmc:DOMAIN-TASK and the "
                         "one-step tasks: "
                         f"{', '.join(one_step)}")
    if any(k in PEERS for k in config.learners) and (reason := peers_missing()):
        raise ValueError(reason)
    preset_params = presets.task_params_of(record.preset, config.task) if record.preset else {}
    params = json.loads(_completed(config.task, json.dumps({**preset_params, **config.task_params}, sort_keys=True),
                                   config.seed))
    peer_params = json.loads(_completed(config.task, json.dumps(config.task_params, sort_keys=True), config.seed)) \
        if preset_params else None
    gym_id = gym_envs.env_id_of(config.task) if gym_envs.env_task(config.task) else None
    runners: dict[str, Runner] = {}
    task = tasks.make(config.task, seed=config.seed, **params)
    _check_sizes(config, task)
    for kind in config.learners:
        if kind in PEERS:
            runners[kind] = PeerRunner(kind, peer_budget(kind, config), gym_id)
            continue
        runners[kind] = OurRunner(kind, _our_config(kind, record.preset), config.samples)
        try:
            runners[kind]._make(task, config.seed)
        except ValueError as exc:
            raise ValueError(f"{kind} cannot learn {config.task}: {exc}") from None
    return Plan(config, params, runners, peer_params)


#: The most units (learners times seeds) one comparison holds: a seed record each.
MAX_UNITS = 100_000


def _check_sizes(config: CompareConfig, task) -> None:
    """Refuse, by arithmetic before anything is listed or drawn, more units than a comparison holds and
    scoring observations (or episode starts) that cannot fit in memory."""
    from somarm.validation import check_memory

    n_units = len(config.learners) * config.seeds
    if n_units > MAX_UNITS:
        raise ValueError(f"--seeds {config.seeds} with {len(config.learners)} learner(s) is {n_units} units, more "
                         f"than the {MAX_UNITS} a comparison holds; give fewer --seeds")
    if task.episodic:
        check_memory(f"--episodes {config.episodes}", _EPISODE_BYTES * config.episodes, "give fewer --episodes")
    else:
        check_memory(f"--observations {config.observations}", _OBSERVATION_BYTES * config.observations,
                     "give fewer --observations")


#: Bytes one scoring observation costs at its peak (the policy's working arrays over all of them at
#: once; about 4 KiB measured for tabular on reach2), and one greedy episode (about 7 KiB measured on
#: gym:Pendulum-v1): twice that, as margin.
_OBSERVATION_BYTES = 8 * 2**10
_EPISODE_BYTES = 16 * 2**10


@functools.lru_cache(maxsize=8)
def _completed(task: str, params_json: str, seed: int) -> str:
    """The task parameters completed at ``seed`` (a ``gym:ID``'s observation scaling estimated), as JSON;
    kept, so that checking a comparison and then running it estimate the scaling once."""
    return json.dumps(tasks.record(task).complete(tasks.check_params(task, json.loads(params_json)), seed))


def check(config: CompareConfig) -> list[str]:
    """Fail fast: the learners that can run, or a one-line ValueError naming what cannot (``make_plan``)."""
    return list(make_plan(config).runners)


class _Scorer:
    """How a greedy policy is scored, the same for every learner, rung and seed.

    A one-step task: the error (minus the mean reward) on fixed fresh observations. A ``gym:ID`` task:
    the mean undiscounted return of whole greedy episodes from fixed reset seeds (a fifth of them at
    the rungs before the last). ``policy`` maps the task's observations ``(n, obs_dim)`` (scaled, for
    a Gymnasium task) to actions ``(n, action_dim)``.
    """

    def __init__(self, config: CompareConfig, params: dict[str, Any]) -> None:
        self.task = tasks.make(config.task, seed=config.seed, **params)
        self.episodic = self.task.episodic
        rng = evaluation.evaluation_rng(config.eval_seed)
        if self.episodic:
            self.starts = self.task.sample_starts(rng, config.episodes)
        else:
            self.observations = self.task.sample_observations(rng, config.observations)

    @property
    def metric(self) -> str:
        return "return" if self.episodic else "error"

    def __call__(self, policy, *, last: bool = True) -> float:
        if self.episodic:
            starts = self.starts if last else self.starts[:max(1, len(self.starts) // 5)]
            return float(self.task.run_episodes(policy, starts)["returns"].mean())
        return float(-self.task.evaluate(self.observations, policy(self.observations)).mean())

    def random(self, seed: int) -> float:
        """The score of uniformly random actions."""
        rng = np.random.default_rng(seed)
        low, high = self.task.action_low, self.task.action_high
        return self(lambda x: rng.uniform(low, high, (len(x), low.size)))


def decisions(samples: int, params: dict[str, Any]) -> int:
    """The decisions ``samples`` of the task's own steps make where ``params`` hold a suite task's actions for
    ``action_repeat`` K steps each: ``samples // K``, so that every learner's samples count the suite's steps."""
    return samples // int(params.get("action_repeat", 1))


def _train_ours(task, learner, steps: int) -> None:
    """``steps`` training steps of one learner on its task (one trial)."""
    if task.episodic:
        for _ in range(steps):
            actions = learner.act(task.reset())
            rewards = task.step(actions)
            learner.learn(rewards, task.next_observations, task.terminal)
    else:
        for _ in range(steps):
            learner.learn(task.step(learner.act(task.reset())))


def _peer_params(params: dict[str, Any]) -> dict[str, Any]:
    """What TD3 and SAC read of a ``gym:ID`` task's parameters: not the observation scaling, since they
    train and act on the environment's own observations (the scorer's scale-and-unscale round trip
    differs from them by round-off in float64, below the float32 the networks read)."""
    return {k: v for k, v in params.items() if k not in ("observation_low", "observation_high")}


def default_samples(task: str) -> int:
    """somarm's learners' samples when none are given: a ``gym:ID``'s run length (its benchmark
    preset's steps, which the held-out results use), else 10,000."""
    if gym_envs.env_task(task):
        return tasks.record(task).n_steps
    return 10_000


def peer_budget(kind: str, config: CompareConfig) -> int:
    """TD3's or SAC's training samples: ``peer_samples``, else the Zoo's budget for a ``gym:ID`` it
    covers, else ``samples``."""
    if config.peer_samples:
        return config.peer_samples
    if gym_envs.env_task(config.task):
        from somarm.peers import zoo

        entry = zoo.zoo_entry(kind, gym_envs.env_id_of(config.task))
        if entry is not None:
            return int(entry["n_timesteps"])
    return config.samples


def _earlier_seed(path: Path, fingerprint: dict, progress: bool, n_rungs: int, defaults: dict[str, Any]):
    """A seed's scores from an earlier run of the same comparison (``path``), or None where there is
    none, it was made with other settings, or it is damaged (then the seed is trained again).

    A setting the record lacks counts as the same where it is at its default now (``defaults``): a
    learner option added since at its default trains exactly as before."""
    if not os.path.lexists(path):
        return None
    try:
        found = _seed_record(path, n_rungs)
    except ValueError as exc:
        print(f"{exc}; training that seed again", file=sys.stderr, flush=True)
        return None
    if _with_new_defaults(found[0], fingerprint, defaults) != fingerprint:
        if progress:
            print(f"{path} was made with other settings; training that seed again", file=sys.stderr, flush=True)
        return None
    return found[1:]


def _with_new_defaults(found: dict, fingerprint: dict, defaults: dict[str, Any]) -> dict:
    """``found`` with the settings it lacks filled in from ``fingerprint`` where they are at their defaults."""
    settings, now = found.get("settings"), fingerprint.get("settings")
    if not isinstance(settings, dict) or not isinstance(now, dict):
        return found
    added = {k: v for k, v in now.items() if k not in settings and k in defaults and defaults[k] == v}
    return {**found, "settings": {**settings, **added}} if added else found


def _seed_record(path: Path, n_rungs: int) -> tuple[dict, list[float], list[float], dict]:
    """A seed record's fingerprint, scores, training seconds and settings, checked as a whole: an object
    with those four entries, ``n_rungs`` finite scores and as many finite, non-negative seconds.

    Raises:
      ValueError: one line naming the file and what is wrong with it.
    """
    where = f"{path} is damaged"
    try:
        record = read_json(path, max_bytes=_MAX_RECORD_BYTES)
    except ValueError as exc:
        raise ValueError(f"{where}: it {str(exc).removeprefix(str(path)).strip()}") from None
    if not isinstance(record, dict):
        raise ValueError(f"{where}: it holds a {type(record).__name__}, not a seed record (an object)")
    missing = [k for k in ("fingerprint", "values", "walls", "settings") if k not in record]
    if missing:
        raise ValueError(f"{where}: it has no {', '.join(missing)}")
    for name in ("fingerprint", "settings"):
        if not isinstance(record[name], dict):
            raise ValueError(f"{where}: its {name} is a {type(record[name]).__name__}, not an object")
    for name, least in (("values", -math.inf), ("walls", 0.0)):
        numbers = record[name]
        if not (isinstance(numbers, list) and len(numbers) == n_rungs
                and all(isinstance(x, (int, float)) and not isinstance(x, bool) and least <= x < math.inf
                        for x in numbers)):
            what = "finite numbers" if name == "values" else "finite numbers >= 0"
            raise ValueError(f"{where}: its {name} are not {n_rungs} {what}")
    return record["fingerprint"], record["values"], record["walls"], record["settings"]


#: A seed record holds a few scores and settings: one far larger is not one.
_MAX_RECORD_BYTES = 4 * 2**20


#: The engine (and Ray address) of a comparison that names none: ``engine_of_parts`` sets it for
#: the comparisons that the parts of ``somarm reproduce --engine ray`` make.
_engine: tuple[str, str | None] = ("local", None)


@contextlib.contextmanager
def engine_of_parts(engine: str, address: str | None):
    """Within it, every comparison made without an engine runs on ``engine`` (at ``address``)."""
    global _engine
    before, _engine = _engine, (engine, address)
    try:
        yield
    finally:
        _engine = before


#: The learners whose compiled code or kernels this process has warmed up (``run_unit``).
_WARMED: set[str] = set()


def run_unit(plan: Plan, kind: str, seed: int):
    """One learner at one seed, in whatever process runs it (this one, or a Ray worker): its scores at
    the rungs, its training seconds and its settings, ``(values, walls, settings)``. The first unit of
    a learner in a process warms it up first, untimed (numba compiles SOM-Q's kernels, torch builds
    its own); the scores do not depend on it."""
    warm_up = kind not in _WARMED
    _WARMED.add(kind)
    return plan.runners[kind].run(plan, seed, plan.scorer(kind), warm_up=warm_up)


def compare(config: CompareConfig | Plan, out: Path, *, progress: bool = True, resume: bool = False,
            engine: str | None = None, address: str | None = None) -> dict[str, Any]:
    """Train every learner on every seed, write ``out/compare.json`` and ``out/compare.png``.

    The comparison is resolved once (``make_plan``; a ``Plan`` may be given); each learner at each seed
    is then a unit (``run_unit``); its scores are kept in ``out/seeds/<learner>-<seed>.json`` with
    everything they depend on, written by this process as the unit comes back, and ``compare.json`` is
    rewritten (atomically) with every learner whose seeds are all in, so an interruption keeps what
    finished (``"complete": false``). With ``resume`` a seed whose record there matches is read back
    instead of trained again (a long comparison goes on where it stopped). ``engine="ray"`` runs the
    units on the Ray cluster at ``address`` (None: a local one; ``somarm.cluster``); the scores and
    settings are the same as here, unit for unit. ``engine=None``: "local", or what ``engine_of_parts`` set.

    Returns:
      The ``compare.json`` content: per learner ``samples`` (the ladder), ``error`` (rung x seed; for a
      ``gym:ID`` task ``return``), ``wall_seconds`` (rung x seed, training only),
      ``seconds_per_sample`` and ``settings``.

    Raises:
      ValueError: as ``make_plan``; an unknown engine or Ray missing; units that failed on the cluster
        (after the others were kept). KeyboardInterrupt: after writing what finished.
    """

    from somarm import cluster
    from somarm.peers.plot import compare_figure  # matplotlib loads only when a figure is drawn

    if engine is None:
        engine, address = _engine
    cluster.check_engine(engine, address)
    plan = config if isinstance(config, Plan) else make_plan(config)
    config = plan.config
    score = plan.scorer()
    result: dict[str, Any] = {
        "task": config.task, "task_params": plan.params, "seeds": plan.seeds,
        "eval_seed": config.eval_seed, "metric": score.metric,
        f"random_action_{score.metric}": score.random(config.eval_seed),
        "somarm_version": __version__, "complete": False, "learners": {},
    }
    if plan.peer_params is not None:  # TD3 and SAC train and are scored on the task without the preset's own
        result["peer_task_params"] = plan.peer_params
    result.update({"episodes": config.episodes} if score.episodic else {"observations": config.observations})
    make_folder(out / "seeds", within=out)
    found: dict[tuple[str, int], tuple] = {}  # (kind, seed) -> (values, walls, settings)
    todo: list[tuple[str, int, dict]] = []  # (kind, seed, fingerprint)
    for kind, runner in plan.runners.items():
        described, defaults = runner.described(), runner.defaults()
        for seed in plan.seeds:
            fingerprint = plan.fingerprint(kind, seed, score, described)
            earlier = (_earlier_seed(out / "seeds" / f"{kind}-{seed}.json", fingerprint, progress, len(runner.rungs),
                                     defaults) if resume else None)
            if earlier is None:
                todo.append((kind, seed, fingerprint))
            else:
                found[kind, seed] = tuple(earlier)
                _said(plan, kind, seed, score.metric, found[kind, seed], kept=True, progress=progress)

    def keep(kind: str, seed: int, fingerprint: dict, unit_result) -> None:
        """A unit's result: its seed record, its line, and compare.json with every learner now complete."""
        v, w, settings = unit_result
        atomic_write_json(out / "seeds" / f"{kind}-{seed}.json",
                          {"fingerprint": fingerprint, "values": v, "walls": w, "settings": settings}, within=out)
        found[kind, seed] = (v, w, settings)
        _said(plan, kind, seed, score.metric, found[kind, seed], kept=False, progress=progress)
        _fill(result, found, plan, score.metric)
        atomic_write_json(out / "compare.json", result, within=out)

    if engine == "ray":
        units = [cluster.Unit(f"{kind} seed {seed}", run_unit, (plan, kind, seed), kind=kind)
                 for kind, seed, _ in todo]
        fingerprints = {f"{kind} seed {seed}": (kind, seed, fingerprint) for kind, seed, fingerprint in todo}
        failed = cluster.run_units(units, on_done=lambda unit, r: keep(*fingerprints[unit.name], r), address=address,
                                   progress=progress)
        if failed:
            unit, why = failed[0]
            raise ValueError(f"{len(failed)} of {len(units)} unit(s) failed on the cluster ({unit.name}: {why}); "
                             f"the units that came back are kept in {out / 'seeds'}: rerun with --resume for the rest")
    else:
        for kind, seed, fingerprint in todo:
            keep(kind, seed, fingerprint, run_unit(plan, kind, seed))
    _fill(result, found, plan, score.metric)
    result["complete"] = True
    atomic_write_json(out / "compare.json", result, within=out)
    compare_figure(result, out / "compare.png")
    return result


def _said(plan: Plan, kind: str, seed: int, metric: str, found: tuple, *, kept: bool, progress: bool) -> None:
    """A unit's line: its learner and seed, its samples, training seconds and last score."""
    if progress:
        values, walls, _ = found
        again = " (kept from the earlier run)" if kept else ""
        print(f"{plan.config.task}/{kind} seed {seed}: {plan.runners[kind].budget} samples in {walls[-1]:.1f} s, "
              f"greedy {metric} {values[-1]:.4g}{again}", file=sys.stderr, flush=True)


def _fill(result: dict[str, Any], found: dict[tuple[str, int], tuple], plan: Plan, metric: str) -> None:
    """``result["learners"]``: every learner whose seeds are all in, in the order asked."""
    result["learners"] = {}
    for kind, runner in plan.runners.items():
        if not all((kind, seed) in found for seed in result["seeds"]):
            continue
        per_seed = [found[kind, seed] for seed in result["seeds"]]
        walls = np.array([w for _, w, _ in per_seed])
        result["learners"][kind] = {
            "samples": runner.rungs,
            metric: np.array([v for v, _, _ in per_seed]).T.tolist(),
            "wall_seconds": walls.T.tolist(),
            "seconds_per_sample": (walls[:, -1] / runner.budget).tolist(),
            "settings": per_seed[-1][2],
        }
