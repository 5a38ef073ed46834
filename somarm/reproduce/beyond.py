"""Beyond the paper: the interpolated response beside the paper's winner response.

Not one of the paper's experiments: its section 6 only suggests "a truly continuous response by
interpolating over the Q-table". Both responses learn side by side (in lockstep, same
observations and random numbers) on reach2, reach20, four_goals and throw_distance, under the
paper's table and, where the targets need it, the table with changed settings (``table1+``: a
lambda_A floor and periodic joint angles; ``table2+``: periodic joint angles and a slower epsilon; ``table5+``: schedules),
so that the gain of the response and of the settings show apart. Each run counts its failed trials
(``metrics.failed_trials``). The figures are drawn in ``beyond_figures``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from somarm.learners.somq import RESPONSES
from somarm.reproduce import beyond_figures, metrics
from somarm.reproduce.common import Context, final_error, fmt, preset_choices, run_group, typical_trial
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.report import Claim, Section
from somarm.run import RunConfig, RunResult, evaluation

__all__ = ["TARGETS", "Key", "Trained", "groups", "train", "unit_errors", "response_profiles", "beyond"]

#: This project's targets for the interpolated response: greedy error at most this (task: bound, preset).
TARGETS = {"reach2": (0.012, "table1+"), "four_goals": (0.015, "table2+"), "throw_distance": (0.15, "table5+")}
#: "Not worse than the winner response": the interpolated mean greedy error within 10% of the winner's.
_NOT_WORSE = 1.10
#: A run's key: (task, preset, response).
Key = tuple[str, str, str]


def _plan(ctx: Context) -> list[tuple[str, tuple[str, ...], int, int]]:
    """(task, presets, trials, steps) of each comparison."""
    return [
        ("reach2", ("table1", "table1+"), ctx.pick(20, 2), ctx.pick(50_000, 1_000)),
        ("reach20", ("table1",), ctx.pick(10, 2), ctx.pick(50_000, 1_000)),
        ("four_goals", ("table2", "table2+"), ctx.pick(20, 2), ctx.pick(40_000, 1_000)),
        ("throw_distance", ("table5", "table5+"), ctx.pick(20, 2), ctx.pick(25_000, 1_000)),
    ]


@dataclass(frozen=True)
class Trained:
    """Every run of the plan and what its greedy response does, keyed by (task, preset, response)."""

    results: dict[Key, RunResult]
    greedy: dict[Key, np.ndarray]  #: ``(n_trials,)`` greedy error on fresh observations
    own: dict[Key, tuple[np.ndarray, np.ndarray]]  #: the targets' runs: ``unit_errors``
    profiles: dict  #: ``response_profiles``'s answer


def groups(ctx: Context) -> dict[str, list[RunConfig]]:
    """The runs this experiment trains at ``ctx.seed``, by label: for each task of the plan, both
    responses under each of its presets (one lockstep group per task)."""
    return {
        f"beyond {task}": [
            RunConfig(task=task, preset=preset, overrides={"response": response}, n_trials=n_trials,
                      n_steps=n_steps, seed=ctx.seed)
            for preset in preset_names
            for response in RESPONSES
        ]
        for task, preset_names, n_trials, n_steps in _plan(ctx)
    }


def _train_runs(ctx: Context) -> tuple[dict[Key, RunResult], dict[Key, np.ndarray]]:
    """Both responses under each preset of the plan (``groups``: a task's runs in lockstep); each run's
    greedy error on fresh observations (1000 for the arms, 500 for the throws; 100 when quick)."""
    results, greedy = {}, {}
    for label, configs in groups(ctx).items():
        group = run_group(ctx, label, configs)
        task = configs[0].task
        n_obs = ctx.pick(500 if task.startswith("throw") else 1000, 100)
        for config, result in zip(configs, group, strict=True):
            key = (task, config.preset, config.overrides["response"])
            results[key] = result
            greedy[key] = -evaluation.evaluate_greedy(result.learner, result.task, n_observations=n_obs,
                                                      seed=ctx.seed)
    return results, greedy


def train(ctx: Context) -> Trained:
    """Train every run of the plan and evaluate its greedy response (see ``Trained``).

    Args:
      ctx: where and how the experiment runs (its seed, quick mode and backend).

    Returns:
      The runs and their evaluations (``Trained``).

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
    """
    results, greedy = _train_runs(ctx)
    own = {key: unit_errors(result) for key, result in results.items() if key[0] in TARGETS}
    return Trained(results, greedy, own, response_profiles(results, greedy, ctx.quick))


def unit_errors(result: RunResult) -> tuple[np.ndarray, np.ndarray]:
    """Per trial ``(n_trials,)``: the mean error of each input unit's own greedy action at the unit
    itself, and how many distinct action units are greedy somewhere.

    Args:
      result: a run of the SOM-Q learner.

    Returns:
      ``(own, distinct)``, each ``(n_trials,)``.
    """
    learner, task = result.learner, result.task
    winners, units = learner.greedy_units(learner.input_weights)
    index = np.arange(learner.n_trials)[:, None]
    actions = learner.action_weights[index, units]
    own = -task.evaluate(learner.input_weights, actions).mean(axis=1)
    distinct = np.array([len(np.unique(row)) for row in units])
    return own, distinct


def response_profiles(results: dict[Key, RunResult], greedy: dict[Key, np.ndarray], quick: bool) -> dict:
    """The targets' typical trials under each response: reach2's greedy fingertip error around the
    goal circle (1441 goal angles, 181 when quick) and throw_distance's landing point against the
    target (361 targets from 0 to 9, 46 when quick).

    Args:
      results, greedy: ``_train_runs``'s answer.
      quick: the shorter sweeps.

    Returns:
      ``{"reach2": (trial, angles, {response: errors}), "throw_distance": (trial, targets,
      {response: landing})}``, each profile ``(n_points,)``.
    """
    from somarm.tasks import throw as throw_task
    from somarm.tasks.reach import goal_circle_points

    preset = TARGETS["reach2"][1]
    trial = typical_trial(greedy[("reach2", preset, "interpolated")])
    angles = np.linspace(0.0, 2 * np.pi, 181 if quick else 1441)
    reach = {}
    for response in RESPONSES:
        result = results[("reach2", preset, response)]
        goals = goal_circle_points(result.task.params, angles)
        batch = np.broadcast_to(goals, (result.learner.n_trials, *goals.shape))
        reach[response] = -result.task.evaluate(batch, result.learner.predict(np.ascontiguousarray(batch)))[trial]
    preset = TARGETS["throw_distance"][1]
    throw_trial = typical_trial(greedy[("throw_distance", preset, "interpolated")])
    targets = np.linspace(0.0, 9.0, 46 if quick else 361)
    throws = {}
    for response in RESPONSES:
        learner = results[("throw_distance", preset, response)].learner
        batch = np.broadcast_to(targets[:, None], (learner.n_trials, targets.size, 1))
        actions = learner.predict(np.ascontiguousarray(batch))[throw_trial]
        throws[response] = throw_task.landing_x(actions[:, 0], actions[:, 1])
    return {"reach2": (trial, angles, reach), "throw_distance": (throw_trial, targets, throws)}


def _sd(x: float) -> str:
    return f"{x:.2g}"


def _table(results, greedy) -> list[str]:
    lines = ["| task | preset | response | trials x steps | greedy error (sd) | training error, last 10% |",
             "|---|---|---|---|---|---|"]
    for (task, preset, response), errors in greedy.items():
        result = results[(task, preset, response)]
        window = max(result.config.block, result.config.n_steps // 10)
        train = final_error(result, window)
        lines.append(f"| {task} | {preset} | {response} | {result.config.n_trials} x {result.config.n_steps} | "
                     f"{fmt(errors.mean(), 4)} ({_sd(errors.std())}) | {fmt(train.mean(), 4)} |")
    return ["Greedy error of every run (minus the mean reward of the greedy response):", "", *lines]


def _target_claims(greedy) -> list[Claim]:
    claims = []
    for task, (bound, preset) in TARGETS.items():
        interpolated, winner = greedy[(task, preset, "interpolated")], greedy[(task, preset, "winner")]
        measured = (f"{preset}: interpolated {fmt(interpolated.mean(), 4)} (sd {_sd(interpolated.std())}), "
                    f"winner {fmt(winner.mean(), 4)} (sd {_sd(winner.std())})")
        gap = interpolated.mean() - bound
        measured += "." if gap <= 0 else f"; misses the target by {fmt(gap, 2)}."
        measured += " " + _outliers(interpolated)
        claims.append(Claim(f"Beyond the paper (this project's target): {task} greedy error <= {bound} with "
                            "the interpolated response.", measured, bool(interpolated.mean() <= bound),
                            f"mean greedy error over trials <= {bound} ({preset})",
                            values={"interpolated": float(interpolated.mean()),
                                    "failed trials": int(metrics.failed_trials(interpolated).sum())}))
    return claims


def _not_worse_claims(greedy) -> list[Claim]:
    claims = []
    for task in ("reach20", "four_goals"):
        for name in sorted({p for (t, p, _) in greedy if t == task}):
            interpolated, winner = greedy[(task, name, "interpolated")], greedy[(task, name, "winner")]
            claims.append(Claim(
                f"Beyond the paper (this project's target): on {task} ({name}) the interpolated response is not "
                "worse than the winner response.",
                f"{name}: interpolated {fmt(interpolated.mean(), 4)} (sd {_sd(interpolated.std())}), winner "
                f"{fmt(winner.mean(), 4)} (sd {_sd(winner.std())}); failed trials {_failed(interpolated)} and "
                f"{_failed(winner)}.",
                bool(interpolated.mean() <= _NOT_WORSE * winner.mean()),
                f"interpolated mean <= {_NOT_WORSE:.2f} x winner mean",
                values={"interpolated": float(interpolated.mean()), "winner": float(winner.mean())},
            ))
    return claims


def _failed(errors: np.ndarray) -> int:
    """How many trials failed (``metrics.failed_trials``)."""
    return int(metrics.failed_trials(errors).sum())


def _outliers(errors: np.ndarray) -> str:
    """Median, the failed trials (``metrics.failed_trials`` of the greedy errors) and the mean without them."""
    median = float(np.median(errors))
    failed = np.flatnonzero(metrics.failed_trials(errors))
    text = f"Median over trials {fmt(median, 4)}"
    if failed.size == 0:
        return text + "; no trial failed (none above twice the median)."
    rest = np.delete(errors, failed)
    listed = ", ".join(f"trial {i} ({fmt(errors[i], 3)})" for i in failed)
    return (f"{text}; {failed.size} of {errors.size} trials failed (above twice the median): {listed}; "
            f"the other {rest.size} trials average {fmt(rest.mean(), 4)} (max {fmt(rest.max(), 4)}).")


def _diagnosis(trained: Trained) -> list[str]:
    """Why a target is missed: how far the action units themselves sit from their input units' solutions."""
    lines = ["", "What limits the interpolated response (the blend can be no better than the actions it blends): "
             "the error of each input unit's own greedy action at the unit itself, and how many distinct action "
             "units the input units use:", ""]
    for key, (own, distinct) in trained.own.items():
        task, preset, response = key
        n_units = trained.results[key].learner.q.shape[1]
        lines.append(f"- {task}, {preset}, {response}: greedy {fmt(trained.greedy[key].mean(), 4)}; a unit's own "
                     f"action misses by {fmt(own.mean(), 4)}; {distinct.mean():.1f} distinct greedy action units "
                     f"for {n_units} input units.")
    return lines


def report(ctx: Context, trained) -> Section:
    """Train and compare both responses on the four tasks; figures, targets and notes."""
    results, greedy = trained.results, trained.greedy
    section = Section("beyond", "Beyond the paper: a truly continuous SOM-Q response")
    section.choices += preset_choices("table1+", "table2+", "table5+")
    section.choices += [
        "Greedy error: mean distance (reach, four_goals) or |landing - target| (throw_distance) of the greedy "
        "response on fresh observations (1000 for the arms, 500 for the throws), per trial; mean and sd over trials.",
        f"'Not worse than the winner response': the interpolated mean greedy error at most {_NOT_WORSE:.2f} times "
        "the winner's (a 10% margin for the spread between trials).",
    ]
    section.notes += _table(results, greedy)
    section.claims += _target_claims(greedy) + _not_worse_claims(greedy)
    section.notes += _diagnosis(trained)
    section.counts.update({f"failed trials (greedy error above twice the median), {task} {preset} {response}":
                           int(metrics.failed_trials(errors).sum())
                           for (task, preset, response), errors in greedy.items() if task != "throw_distance"})
    section.figures += beyond_figures.figures(ctx, results, greedy, trained.profiles, TARGETS)
    return section


beyond = Experiment(groups, train, report)
