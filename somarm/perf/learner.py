"""``somarm bench learner``: microseconds per trial-step of SOM-Q act + learn, beside the reference.

For the paper's map sizes and n_trials = 1, 20 and 100, the batched, compiled learner
(``somarm.learners.somq.SOMQLearner``) and the line-by-line reference (``somarm.learners.reference.ReferenceSOMQ``, one
trial) run the same number of steps from the same t in the same process, so their ratio is
meaningful even on a busy machine. Observations are uniform in the box and rewards are uniform
in [-1, 0): the learner's cost does not depend on where they come from, only on how often the
action map learns (about half the steps here). Each figure is the best of ``--repeats`` runs.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from somarm.helptext import PlainHelpFormatter
from somarm.learners.presets import get
from somarm.learners.reference import ReferenceSOMQ
from somarm.learners.somq import SOMQConfig, SOMQLearner, paper_representation
from somarm.validation import OneLineParser, check_int, check_int_list, whole_number

__all__ = ["Case", "CASES", "REPRESENTATIONS", "time_batched", "time_reference", "interpolated_rows",
           "representation_rows", "main"]


@dataclass(frozen=True)
class Case:
    """One benchmarked map size: a preset's config with given observation and action dimensions."""

    label: str
    config: SOMQConfig
    obs_dim: int
    action_dim: int


CASES = (
    Case("50x1 in, 50x1 act, 2-D (Table 1)", get("table1"), 2, 2),
    Case("50x1 in, 50x1 act, 20-D (Table 1)", get("table1"), 2, 20),
    Case("10x10 in, 8x1 act, 2-D (Table 2)", get("table2"), 2, 2),
    Case("30x1 in, 30x1 act, 2-D (Table 5)", get("table5"), 1, 2),
)


#: The input representations (``REPRESENTATION_SETTINGS``: ``input_groups``, ``k_nearest``, ``grow_every``,
#: ``local_linear``, ``shared_slopes``, ``action_slopes``, ``action_factored``, ``input_placement`` and the learning rules
#: ``action_gap``, ``n_step`` and ``plan``) at Reacher-v5's size: 10 observed dimensions, a 3x3 grid of torques, the
#: reacher preset otherwise (the planning row's map over the first two dimensions, its cost a step including
#: a solution of its model every 200 steps).
_ONE_MAP = {**paper_representation(), "input_shape": (20, 20)}
_PAIRS = {**_ONE_MAP, "input_groups": "pairs", "input_shape": (10, 10)}
REPRESENTATIONS = (
    ("one 20x20 map (the paper's)", _ONE_MAP),
    ("one 20x20 map, 3 nearest", {**_ONE_MAP, "k_nearest": 3}),
    ("45 pair maps of 10x10", _PAIRS),
    ("45 pair maps of 10x10, 3 nearest", {**_PAIRS, "k_nearest": 3}),
    ("45 pair maps growing to 10x10", {**_PAIRS, "grow_every": 1000}),
    ("5 maps of 10x10 (chunks:2)", {**_PAIRS, "input_groups": "chunks:2"}),
    ("10 singles of 20, 3 nearest, linear", {**_PAIRS, "input_groups": "singles", "input_shape": (20,),
                                             "k_nearest": 3, "local_linear": True}),
    ("45 pairs 10x10, 3 nearest, linear", {**_PAIRS, "k_nearest": 3, "local_linear": True}),
    ("45 pairs 5x5, 3 nearest, linear", {**_PAIRS, "input_shape": (5, 5), "k_nearest": 3, "local_linear": True}),
    ("45 pairs 10x10, 3 nearest, shared", {**_PAIRS, "k_nearest": 3, "local_linear": True, "shared_slopes": True}),
    ("45 pairs, 3 nearest, action slopes", {**_PAIRS, "k_nearest": 3, "local_linear": True,
                                            "shared_slopes": True, "action_slopes": True}),
    ("45 pairs 10x10, 3 nearest, factored", {**_PAIRS, "k_nearest": 3, "action_factored": True}),
    ("45 pairs 10x10, 3 nearest, gap 0.5", {**_PAIRS, "k_nearest": 3, "action_gap": 0.5}),
    ("one 20x20 map, action_gap 0.5", {**_ONE_MAP, "action_gap": 0.5}),
    ("45 pairs, 3 nearest, shared, 3-step", {**_PAIRS, "k_nearest": 3, "local_linear": True, "shared_slopes": True,
                                             "n_step": 3}),
    ("one 20x20 grid, 2 dims, plan 100/200", {**_ONE_MAP, "input_groups": "0,1", "input_placement": "grid",
                                              "plan": 100, "plan_every": 200, "gamma": 0.95}),
)


def _bounds(case: Case) -> dict[str, np.ndarray]:
    return dict(observation_low=np.zeros(case.obs_dim), observation_high=np.ones(case.obs_dim),
                action_low=np.full(case.action_dim, -np.pi), action_high=np.full(case.action_dim, np.pi))


def _inputs(case: Case, n_trials: int, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    return rng.random((n_steps, n_trials, case.obs_dim)), -rng.random((n_steps, n_trials))


def time_batched(case: Case, n_trials: int, n_steps: int, *, t0: int = 0, chained: bool = False) -> float:
    """Seconds per trial-step of ``SOMQLearner.act`` + ``learn``, starting at step ``t0``; ``chained``: each step
    learns towards the next step's observation, not terminal (as an episode's steps do: delayed reward
    bootstraps, n-step targets wait), else every step is terminal."""
    # Warm up first: numba picks (or loads) a specialisation per array layout, and a batch of one
    # trial has other layouts than a batch of many.
    warm = SOMQLearner(case.config, n_trials=n_trials, **_bounds(case))
    for x, r in zip(*_inputs(case, n_trials, 3), strict=True):
        warm.act(x)
        warm.learn(r)
    learner = SOMQLearner(case.config, n_trials=n_trials, **_bounds(case))
    learner.t = t0
    observations, rewards = _inputs(case, n_trials, n_steps + 1)
    going = np.zeros(n_trials, dtype=np.bool_)
    start = time.perf_counter()
    for i in range(n_steps):
        learner.act(observations[i])
        if chained:
            learner.learn(rewards[i], observations[i + 1], going)
        else:
            learner.learn(rewards[i])
    return (time.perf_counter() - start) / (n_steps * n_trials)


def time_reference(case: Case, n_steps: int, *, t0: int = 0) -> float:
    """Seconds per step of the one-trial reference, starting at step ``t0``."""
    reference = ReferenceSOMQ(case.config, **_bounds(case))
    reference.t = t0
    observations, rewards = _inputs(case, 1, n_steps)
    start = time.perf_counter()
    for x, r in zip(observations[:, 0], rewards[:, 0], strict=True):
        reference.act(x)
        reference.learn(r)
    return (time.perf_counter() - start) / n_steps


def interpolated_rows(n_steps: int, repeats: int, *, n_trials: int = 100, late: int = 50_000) -> list[float]:
    """Print the interpolated response's cost beside the winner's, measured in turns; returns the ratios.

    Both run at ``t0 = 0`` (mostly exploring steps) and at ``t0 = late`` (mostly greedy steps, where
    the blend is computed), ``n_trials`` trials, best of ``repeats``; this project's target is <= 2x.
    """
    print(f"\ninterpolated response (somarm.learners.interpolation) against the winner's, {n_trials} trials")
    print(f"{'maps':36s} {'from t':>7s} {'winner us':>10s} {'interpolated us':>16s} {'ratio':>7s}")
    ratios = []
    for case in CASES:
        blended = dataclasses.replace(case, config=dataclasses.replace(case.config, response="interpolated"))
        for t0 in (0, late):
            times = {"winner": [], "interpolated": []}
            for _ in range(repeats):  # alternate, so a busy moment hits both
                times["winner"].append(time_batched(case, n_trials, n_steps, t0=t0))
                times["interpolated"].append(time_batched(blended, n_trials, n_steps, t0=t0))
            winner, interpolated = min(times["winner"]), min(times["interpolated"])
            ratios.append(interpolated / winner)
            print(f"{case.label:36s} {t0:7d} {winner * 1e6:10.3f} {interpolated * 1e6:16.3f} {ratios[-1]:6.2f}x")
    worst = max(ratios)
    print(f"target (interpolated within 2x of the winner response): worst {worst:.2f}x -> "
          f"{'met' if worst <= 2.0 else 'NOT met'}")
    return ratios


def representation_rows(n_steps: int, repeats: int, *, trial_counts: tuple[int, ...] = (1, 5)) -> list[float]:
    """Print each input representation's memory and cost per trial-step at Reacher-v5's size; returns the
    microseconds (one per representation and trial count, best of ``repeats``)."""
    from somarm.learners import memory_needed
    from somarm.learners.presets import get as preset

    print("\ninput representations at Reacher-v5's size (10 observed dimensions, 3x3 torques, the reacher "
          "preset), from t = 0")
    print(f"{'representation':36s} {'n_trials':>8s} {'us/trial-step':>14s} {'MB per trial':>13s}")
    micros = []
    for label, changes in REPRESENTATIONS:
        case = Case(label, preset("reacher").with_changes(changes), 10, 2)
        bytes_one = memory_needed("somq", case.config, n_trials=1, obs_dim=10, action_dim=2)[1]
        bytes_two = memory_needed("somq", case.config, n_trials=2, obs_dim=10, action_dim=2)[1]
        for n_trials in trial_counts:
            micros.append(1e6 * min(time_batched(case, n_trials, n_steps, chained=True) for _ in range(repeats)))
            print(f"{label:36s} {n_trials:8d} {micros[-1]:14.2f} {(bytes_two - bytes_one) / 1e6:13.3f}")
    return micros


def main(argv: list[str] | None = None) -> int:
    """Print the table; returns 0 (the targets are reported, not enforced)."""
    parser = OneLineParser(prog="somarm bench learner", description=__doc__.splitlines()[0], formatter_class=PlainHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer steps (a smoke run)")
    parser.add_argument("--steps", type=whole_number, help="steps per timing (default 2000, quick 200)")
    parser.add_argument("--t0", type=whole_number, default=0, help="step the schedules start at (default 0)")
    parser.add_argument("--repeats", type=whole_number, help="best of this many runs (default 3, quick 1)")
    parser.add_argument("--trials", default="1,20,100", help="comma-separated n_trials (default 1,20,100)")
    args = parser.parse_args(argv)
    n_steps = check_int("--steps", args.steps if args.steps is not None else (200 if args.quick else 2000))
    repeats = check_int("--repeats", args.repeats if args.repeats is not None else (1 if args.quick else 3))
    check_int("--t0", args.t0, minimum=0)
    trial_counts = check_int_list("--trials", args.trials)
    print(f"SOM-Q act + learn, {n_steps} steps from t = {args.t0}, best of {repeats}; "
          "reference = line-by-line single trial (somarm.learners.reference)")
    print(f"{'maps':36s} {'n_trials':>8s} {'batched us/trial-step':>22s} {'reference us/step':>18s} "
          f"{'ratio':>7s}")
    verdict = None
    for case in CASES:
        reference = min(time_reference(case, max(n_steps // 4, 50), t0=args.t0) for _ in range(repeats))
        for n_trials in trial_counts:
            batched = min(time_batched(case, n_trials, n_steps, t0=args.t0) for _ in range(repeats))
            ratio = reference / batched
            print(f"{case.label:36s} {n_trials:8d} {batched * 1e6:22.3f} {reference * 1e6:18.1f} "
                  f"{ratio:6.0f}x")
            if case is CASES[0] and n_trials == 100:
                verdict = (batched * 1e6, ratio)
    if verdict is not None:
        met = verdict[0] <= 1.0 and verdict[1] >= 20.0
        print(f"target (n_trials = 100, 50x50 maps, 2-D actions: <= 1 us per trial-step and >= 20x the "
              f"reference): {verdict[0]:.3f} us, {verdict[1]:.0f}x -> {'met' if met else 'NOT met'}")
    interpolated_rows(n_steps, repeats)
    representation_rows(n_steps, repeats)
    return 0
