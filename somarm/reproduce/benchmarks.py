"""The benchmarks part: SOM-Q on Gymnasium's classic and MuJoCo environments beside TD3 and SAC
(``--only benchmarks``).

Not part of the default reproduction: TD3 and SAC train for the RL Baselines3 Zoo's budgets (up to
300,000 gradient steps per seed), so the part takes many hours. Every seed of every learner is kept as it finishes (``seeds/`` in each comparison's folder):
``reproduce --only benchmarks --resume`` goes on where a stopped run ended. Every learner runs
through ``somarm.peers.compare`` on the same seeds, scored by the mean undiscounted return of its
greedy policy over the same fresh episodes.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from somarm.io import atomic_write_json
from somarm.peers import compare, zoo
from somarm.peers.plot import NAMES, compare_figure
from somarm.reproduce import yardsticks
from somarm.reproduce.common import Context, fmt
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.report import Claim, Section

__all__ = ["ENVIRONMENTS", "LEARNERS", "BASELINES", "PARTS", "TARGETS", "SPEED", "TUNING_SEEDS", "FRESH", "ReportSeeds", "compare_groups", "reach", "budgets", "train",
           "measure", "Trained", "part", "benchmarks"]

#: The environments of the part, with this project's budget for TD3 and SAC where the Zoo has none.
#: At 20,000 samples SB3's default TD3 had not settled on InvertedPendulum-v5: greedy returns of 1000,
#: 224, 190, 89 and 139 at seeds 0-4, swinging between rungs; Reacher-v5 keeps improving for longer still.
ENVIRONMENTS: dict[str, int] = {
    "Pendulum-v1": 20_000,
    "InvertedPendulum-v5": 100_000,
    "Reacher-v5": 200_000,
    "MountainCarContinuous-v0": 50_000,
}
LEARNERS = ("somq", "somq+", "motoric", "tabular", "td3", "sac")
#: somarm's baselines: no target claim and no setting chosen on a seed, so they train on the peers' seeds.
BASELINES = ("motoric", "tabular")
#: Where a fixed grid cannot be built: Reacher-v5's 10 observation dimensions at 16 cells each make
#: 16^10 cells (the tabular learner refuses more than 1e7 table entries).
_NO_GRID = ("Reacher-v5",)
#: The greedy return each environment's target asks of SOM-Q (mean over the reported seeds).
TARGETS = {"Pendulum-v1": -200.0, "InvertedPendulum-v5": 950.0, "MountainCarContinuous-v0": 90.0, "Reacher-v5": -6.0}
#: How many times less wall time than the faster peer each response of SOM-Q may take to reach the target.
SPEED = {"Pendulum-v1": 5.0, "Reacher-v5": 5.0}
#: The seeds the presets were chosen on; no report scores them.
TUNING_SEEDS = range(100, 200)


@dataclass(frozen=True)
class ReportSeeds:
    """The seeds each side of a benchmark report trains and scores: somarm's learners (``ours``) and TD3
    and SAC (``peers``), each a ``range``. Every learner is scored on the same fresh episodes (the
    evaluation seed is the report's ``--seed``). A report may score somarm's learners on seeds no setting
    was scored on before its preset was fixed, and keep the peers' seed records where their settings were
    never chosen on any seed of ours."""

    ours: range
    peers: range

    def __post_init__(self) -> None:
        for side in ("ours", "peers"):
            seeds = getattr(self, side)
            if not isinstance(seeds, range) or seeds.step != 1 or len(seeds) < 1 or seeds.start < 0:
                raise ValueError(f"{side} seeds must be a range of consecutive seeds >= 0, got {seeds!r}")
            if set(seeds) & set(TUNING_SEEDS):
                raise ValueError(f"{side} seeds {seeds.start}-{seeds[-1]} overlap the tuning seeds 100-199")

    @classmethod
    def same(cls, first: int, count: int) -> ReportSeeds:
        """Seeds ``first .. first + count - 1`` for every learner."""
        return cls(range(first, first + count), range(first, first + count))

    def first(self) -> ReportSeeds:
        """The first seed of each side (what ``--quick`` keeps)."""
        return ReportSeeds(range(self.ours.start, self.ours.start + 1), range(self.peers.start, self.peers.start + 1))

    def text(self) -> str:
        """The seeds as the report's choices state them."""
        def span(seeds: range) -> str:
            return f"{seeds.start}" if len(seeds) == 1 else f"{seeds.start}-{seeds[-1]}"
        if self.ours == self.peers:
            return f"Seeds {span(self.ours)} for every learner; the presets were tuned on seeds 100-199."
        return (f"SOM-Q and SOM-Q+ at seeds {span(self.ours)}, which no setting was scored on before the preset "
                f"was fixed; TD3, SAC, the Motoric Map and tabular Q-learning at seeds {span(self.peers)} (no "
                "setting of theirs was chosen on a seed of ours: the peers take SB3's defaults or the Zoo's, the "
                "baselines make no target claim); the presets were tuned on seeds 100-199; every learner scored on "
                "the same fresh episodes.")


def budgets(ctx: Context, env_id: str) -> tuple[int, dict[str, int]]:
    """somarm's learners' samples (the preset's run length) and each peer's (the Zoo's, else ours)."""
    from somarm import tasks

    ours = ctx.pick(tasks.record("gym:" + env_id).n_steps, 400)
    peers = {}
    for kind in compare.PEERS:
        entry = zoo.zoo_entry(kind, env_id)
        peers[kind] = ctx.pick(int(entry["n_timesteps"]) if entry else ENVIRONMENTS[env_id], 300)
    return ours, peers


def train(ctx: Context, seeds: ReportSeeds, episodes: int,
          envs: tuple[str, ...] = tuple(ENVIRONMENTS)) -> dict[str, dict]:
    """Every learner on every environment through ``compare``: SOM-Q and SOM-Q+ together on ``seeds.ours``,
    the baselines (``BASELINES``) together and TD3 and SAC each alone with its own budget on ``seeds.peers``
    (``benchmarks/<env>/<learners>/``), then all of them in ``benchmarks/<env>/compare.json`` (each
    learner with its ``seeds``) and ``compare.png``.

    Raises:
      KeyboardInterrupt: a comparison was stopped (what finished is written).
    """
    results = {}
    for env_id in envs:
        ours, peers = budgets(ctx, env_id)
        somq = tuple(k for k in LEARNERS if k not in compare.PEERS + BASELINES)
        baselines = tuple(k for k in BASELINES if not (k == "tabular" and env_id in _NO_GRID))
        groups = [(somq, None, seeds.ours), (baselines, None, seeds.peers)]
        groups += [((k,), n, seeds.peers) for k, n in peers.items()]
        results[env_id] = compare_groups(ctx, "gym:" + env_id, groups, ctx.out_dir / "benchmarks" / env_id,
                                         samples=ours, episodes=episodes)
    return results


def compare_groups(ctx: Context, task: str, groups: list[tuple[tuple[str, ...], int | None, range]], folder: Path,
                   *, samples: int, episodes: int, task_params: dict | None = None) -> dict:
    """Each ``(learners, peer_samples, seeds)`` group through ``compare`` in ``folder/<learners>/``, then
    all of them merged (each learner with its ``seeds``) into ``folder/compare.json`` and ``compare.png``;
    ``{}`` (nothing written) for no group.

    Raises:
      KeyboardInterrupt: a comparison was stopped (what finished is written).
    """
    merged: dict = {}
    for learners, peer_samples, side in groups:
        config = compare.CompareConfig(task=task, learners=learners, samples=samples, peer_samples=peer_samples,
                                       seeds=len(side), seed=side.start, episodes=episodes, eval_seed=ctx.seed,
                                       task_params=task_params or {})
        # A fresh report folder holds no seed records; one given with --resume keeps its finished seeds.
        part = compare.compare(config, folder / "-".join(learners), progress=ctx.progress, resume=True)
        for data in part["learners"].values():
            data["seeds"] = part["seeds"]
        every = sorted(set(merged.get("seeds", [])) | set(part["seeds"]))
        merged = {**part, "seeds": every, "learners": {**merged.get("learners", {}), **part["learners"]}}
    if merged:
        atomic_write_json(folder / "compare.json", merged)
        compare_figure(merged, folder / "compare.png")
    return merged


def reach(data: dict, target: float, *, held: bool = False) -> tuple[int, float] | None:
    """The first rung where the mean return over seeds reaches ``target``: (samples, median seconds). With
    ``held``, the first rung from which it stays at or above ``target`` to the last (None if the last is
    below it): an early greedy policy can pass the target by chance and lose it as it learns."""
    means = np.mean(np.array(data["return"]), axis=1)
    if held:
        below = np.flatnonzero(means < target)
        reached = np.arange(below[-1] + 1 if below.size else 0, len(means))
    else:
        reached = np.flatnonzero(means >= target)
    if not reached.size:
        return None
    return data["samples"][reached[0]], float(np.median(np.array(data["wall_seconds"])[reached[0]]))


def measure(results: dict[str, dict]) -> dict:
    """Per environment: each learner's final return (mean, sd over seeds), the peers' converged return
    (the lower of TD3's and SAC's final means), and the samples and seconds each learner takes to reach
    it and the target; SOM-Q's and TD3's time to Pendulum-v1's target."""
    out = {}
    for env_id, result in results.items():
        learners = result["learners"]
        finals = {k: np.array(v["return"][-1]) for k, v in learners.items()}
        converged = min(finals[k].mean() for k in compare.PEERS if k in finals)
        out[env_id] = {
            "final": {k: (float(f.mean()), float(f.std())) for k, f in finals.items()},
            "seeds": {k: f.size for k, f in finals.items()},
            "converged": float(converged),
            "to_converged": {k: reach(v, converged) for k, v in learners.items()},
            "to_target": {k: reach(v, TARGETS[env_id]) for k, v in learners.items()},
            "per_sample": {k: float(np.median(v["seconds_per_sample"])) for k, v in learners.items()},
            "random": result["random_action_return"],
        }
    return out


def _ret(x: float) -> str:
    """A return for the report: one decimal (returns here run from about -1,700 to 1,000)."""
    return f"{x:.1f}"


def _reached(cell: tuple[int, float] | None) -> str:
    return "not reached" if cell is None else f"{fmt(cell[0])} samples, {fmt(cell[1], 2)} s"


def _table(m: dict) -> list[str]:
    lines = ["| environment | learner | final return (mean ± sd) | to the peers' converged return | "
             "to the target | ms per sample |", "|---|---|---|---|---|---|"]
    for env_id, data in m.items():
        for kind, (mean, sd) in data["final"].items():
            lines.append(f"| {env_id} | {NAMES[kind]} | {_ret(mean)} ± {_ret(sd)} | "
                         f"{_reached(data['to_converged'][kind])} | {_reached(data['to_target'][kind])} | "
                         f"{fmt(1e3 * data['per_sample'][kind], 3)} |")
    return lines


def _claims(m: dict, seeds: int | None = None) -> list[Claim]:
    """Each response of SOM-Q its own claims: the target return, and where ``SPEED`` names the
    environment, the wall time to the target against the faster of TD3 and SAC (samples beside seconds).
    ``seeds``: the seed count to state where ``m`` does not give each learner's own."""
    claims = []
    for env_id, target in TARGETS.items():
        if env_id not in m:
            continue
        data = m[env_id]
        for kind in ("somq", "somq+"):
            mean, sd = data["final"][kind]
            claims.append(Claim(
                f"Target (this project's): {NAMES[kind]} reaches a greedy return of at least {fmt(target)} on {env_id}.",
                f"{NAMES[kind]} ends at {_ret(mean)} ± {_ret(sd)} over {data.get('seeds', {}).get(kind, seeds)} seeds (random actions "
                f"{_ret(data['random'])}; the peers' converged return {_ret(data['converged'])}).",
                mean >= target, f"mean greedy return over the seeds >= {fmt(target)}"))
        if env_id not in SPEED:
            continue
        factor = SPEED[env_id]
        peers = {k: c for k in compare.PEERS if (c := data["to_target"].get(k)) is not None}
        faster = min(peers, key=lambda k: peers[k][1]) if peers else None
        for kind in ("somq", "somq+"):
            ours = data["to_target"][kind]
            peer = f"the faster peer, {NAMES[faster]}: {_reached(peers[faster])}" if faster else \
                "neither peer reaches it"
            claims.append(Claim(
                f"Target (this project's): {NAMES[kind]} reaches {fmt(target)} on {env_id} in at most 1/{fmt(factor)} "
                "of the faster peer's wall time.",
                f"{NAMES[kind]}: {_reached(ours)}; {peer} (training time only, each seed timed on the same machine).",
                # No peer at the target leaves nothing to compare with; SOM-Q short of it while a peer gets there fails.
                None if faster is None else ours is not None and ours[1] * factor <= peers[faster][1],
                f"SOM-Q's seconds x {fmt(factor)} <= the faster peer's"))
    return claims


def _published(envs: tuple[str, ...]) -> list[str]:
    # As published: 94.7 stays 94.7 (fmt would pad it to 94.700).
    published = [f"- {kind.upper()} on {env_id}: {mean:g}{'' if sd is None else f' ± {sd:g}'} after "
                 f"{fmt(steps)} steps" for (kind, env_id), (mean, sd, steps) in zoo.PUBLISHED.items() if env_id in envs]
    lines = (["RL Baselines3 Zoo's published results, as published (one trained agent each; mean ± sd of its "
              "evaluation episodes):", "", *published] if published else
             [f"RL Baselines3 Zoo publishes no TD3 or SAC result for {', '.join(envs)}."])
    thresholds = [f"{env_id} {fmt(v)}" for env_id, v in zoo.THRESHOLDS.items() if env_id in envs]
    if thresholds:
        lines += ["", "Gymnasium's reward thresholds: " + ", ".join(thresholds) + "."]
    return lines


@dataclass(frozen=True)
class Trained:
    """What a benchmarks part trained: its seeds and episodes (after ``--quick``) and each environment's results."""

    seeds: ReportSeeds
    episodes: int
    results: dict[str, dict]


def _trained(ctx: Context, *, envs: tuple[str, ...], seeds: ReportSeeds | None) -> Trained:
    """Every learner on ``envs`` at ``seeds`` (default: 5 from the report's ``--seed`` for every learner;
    quick mode keeps the first of each)."""
    seeds = ReportSeeds.same(ctx.seed, 5) if seeds is None else seeds
    seeds = ctx.pick(seeds, seeds.first())
    episodes = ctx.pick(100, 5)
    return Trained(seeds, episodes, train(ctx, seeds, episodes, envs))


def _reported(ctx: Context, trained: Trained, *, envs: tuple[str, ...], name: str) -> Section:
    """The section of a benchmarks part: greedy return against samples and wall time, final returns, time
    to the peers' converged return and to the targets, the yardsticks."""
    seeds, episodes, results = trained.seeds, trained.episodes, trained.results
    m = measure(results)
    title = "Gymnasium's environments" if len(envs) > 1 else envs[0]
    section = Section(name, f"Benchmarks: SOM-Q on {title} beside TD3 and SAC")
    section.figures += [ctx.out_dir / "benchmarks" / env_id / "compare.png" for env_id in envs]
    section.claims += _claims(m)
    section.notes += ["", *_table(m), "", *_published(envs)]
    # Where SOM-Q stops short: what a table of fixed torques costs a controller known to work.
    yard_episodes = ctx.pick(100, 2)
    section.notes += ["", *yardsticks.table(
        yardsticks.measure(envs, yard_episodes, ctx.seed, ctx.pick(None, 500)), yard_episodes)]
    own_budgets = [f"{fmt(ENVIRONMENTS[e])} on {e}" for e in envs if zoo.zoo_entry("td3", e) is None]
    section.choices += [
        seeds.text(),
        "somarm's learners train for their preset's run length, one trial per seed; TD3 and SAC for the Zoo's "
        "n_timesteps where the Zoo tunes the environment" + (", else " + ", ".join(own_budgets) if own_budgets else "")
        + ".",
        f"Scores: the mean undiscounted return of the greedy policy over {episodes} fresh episodes (the same reset "
        "seeds for every learner) at the last rung, a fifth of them at the earlier rungs.",
        "The peers' converged return is the lower of TD3's and SAC's final mean returns.",
        "SOM-Q answers with the winning action unit (the paper's response), SOM-Q+ with the interpolated one; both "
        "train with the environment's benchmark preset. The tabular learner takes the preset's gamma.",
    ]
    if "Reacher-v5" in envs:
        section.choices.append("No tabular learner on Reacher-v5: its 10 observation dimensions at 16 cells each "
                               "make 16^10 cells.")
    return section


#: The seeds each one-environment part reports on: somarm's learners at seeds no setting was scored on before
#: the environment's preset was fixed (every preset was chosen on seeds 100-199; 10-19 first, then 20-29,
#: 30-39, 40-49 or 50-59 for a preset fixed after the earlier seeds had been reported on), TD3 and SAC at seeds 0-4 (their
#: settings, SB3's defaults or the Zoo's, were never chosen on a seed of ours).
FRESH = {"Pendulum-v1": ReportSeeds(range(10, 20), range(0, 5)),
         "InvertedPendulum-v5": ReportSeeds(range(20, 30), range(0, 5)),
         "Reacher-v5": ReportSeeds(range(50, 60), range(0, 5)),
         "MountainCarContinuous-v0": ReportSeeds(range(10, 20), range(0, 5))}


def part(envs: tuple[str, ...], name: str, seeds: ReportSeeds | None = None) -> Experiment:
    """The benchmarks part on ``envs`` (from ``ENVIRONMENTS``), named ``name`` in the report: SOM-Q, SOM-Q+,
    the Motoric Map, tabular Q-learning, TD3 and SAC, at ``seeds`` (default: 5 from the report's ``--seed``
    for every learner)."""
    return Experiment(None, functools.partial(_trained, envs=envs, seeds=seeds),
                      functools.partial(_reported, envs=envs, name=name))


#: Every environment in one part (``--only benchmarks``).
benchmarks = part(tuple(ENVIRONMENTS), "benchmarks")

#: One environment at a time (``--only benchmarks_pendulum``), at its ``FRESH`` seeds: the same comparisons,
#: in the same folders, as the whole part's, so that with --resume the seeds one run finished count for the other.
PARTS = {name: part((env_id,), name, FRESH[env_id]) for name, env_id in (
    ("benchmarks_pendulum", "Pendulum-v1"), ("benchmarks_invertedpendulum", "InvertedPendulum-v5"),
    ("benchmarks_reacher", "Reacher-v5"), ("benchmarks_mountaincar", "MountainCarContinuous-v0"))}
