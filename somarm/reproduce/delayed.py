"""Beyond the paper: delayed reward (gamma > 0) on reach2_obstacle, against gamma 0, random and the shortest path."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from somarm.plots import pyplot
from somarm.reproduce.common import Context, counted, fmt, preset_choices, run_group
from somarm.reproduce.figures import save
from somarm.reproduce.report import Claim, Section
from somarm.run import RunConfig, RunResult, evaluation
from somarm.tasks import obstacle, obstacle_search

__all__ = ["LABELS", "Trained", "groups", "train", "measure", "task_wall", "delayed_reward"]

plt = pyplot()

_EPISODES = 100  #: greedy episodes per trial, from the task's start distribution (20 when quick)
#: The two learners, in the order trained: the paper's delayed reward, and none.
LABELS = ("gamma 0.9", "gamma 0")


@dataclass(frozen=True)
class Trained:
    """Both runs, their greedy episodes, the yardsticks' episodes and trial 0's greedy fingertip paths."""

    results: list[RunResult]
    greedy: list[dict]  #: per run, ``evaluation.greedy_episodes``'s answer
    starts: np.ndarray  #: ``(n_episodes, 2)`` start angles of the evaluation stream
    random_runs: dict  #: episodes of random target changes from ``starts``
    distance_greedy: dict  #: episodes of the distance-greedy policy from ``starts``
    shortest_steps: list[int]  #: length of the shortest path from each of the first starts (when found)
    tips: list[np.ndarray]  #: per run, ``(n, 2)`` trial 0's fingertip along its greedy episode from ``starts[0]``


def _greedy_tips(task, learner, start: np.ndarray) -> np.ndarray:
    """The fingertip along trial 0's greedy episode from ``start`` ``(1, 2)``, to the episode's end."""
    def policy(angles):
        batch = np.broadcast_to(angles, (learner.n_trials, *angles.shape)).copy()
        return np.asarray(learner.predict(batch))[0]

    episodes = task.run_episodes(policy, start, paths=True)
    end = 1 + episodes["length"][0] * task.control_steps
    return obstacle.fingertips(episodes["path"][0, :end])


def groups(ctx: Context) -> dict[str, list[RunConfig]]:
    """The runs this experiment trains at ``ctx.seed``, by label: SOM-Q with gamma 0.9 and 0 on reach2_obstacle."""
    base = RunConfig(task="reach2_obstacle", preset="obstacle", n_trials=ctx.pick(10, 1),
                     n_steps=ctx.pick(20_000, 1_000), seed=ctx.seed, block=200)
    return {"reach2_obstacle gamma 0.9 / 0": [base, dataclasses.replace(base, overrides={"gamma": 0.0})]}


def train(ctx: Context) -> Trained:
    """SOM-Q with gamma 0.9 and 0 in lockstep (``groups``); greedy episodes of both and of the yardsticks.

    Args:
      ctx: where and how the experiment runs (its seed, quick mode and backend).

    Returns:
      Both runs, their greedy episodes and the yardsticks' (``Trained``).

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
    """
    [(label, configs)] = groups(ctx).items()
    results = run_group(ctx, label, configs)
    n_episodes = ctx.pick(_EPISODES, 20)
    greedy = [evaluation.greedy_episodes(r.learner, r.task, n_episodes=n_episodes, seed=ctx.seed) for r in results]
    task = results[0].task
    starts = task.sample_observations(evaluation.evaluation_rng(ctx.seed), n_episodes)
    rng = np.random.default_rng(ctx.seed)
    random_runs = task.run_episodes(obstacle_search.random_policy(task, rng), starts)
    distance_greedy = task.run_episodes(obstacle_search.distance_greedy_policy(task), starts)
    shortest = [obstacle_search.shortest_path(task, start) for start in starts[:ctx.pick(5, 1)]]
    shortest_steps = [len(plan) for plan in shortest if plan is not None]
    tips = [_greedy_tips(task, r.learner, starts[:1]) for r in results]
    return Trained(results, greedy, starts, random_runs, distance_greedy, shortest_steps, tips)


def measure(trained: Trained) -> dict:
    """Success rates (mean and worst trial), mean lengths and returns of each run, and the yardsticks'.

    Args:
      trained: ``train``'s answer.

    Returns:
      The numbers the claims read, by name (``rate``, ``worst``, ``length``, ``return``: one per run).
      A length is the mean over all greedy episodes, a failed one counting at the step limit; a
      return is the undiscounted return per episode, mean over episodes and trials.
    """
    random_runs = trained.random_runs
    return {
        "rate": [float(g["success_rate"].mean()) for g in trained.greedy],
        "worst": [float(g["success_rate"].min()) for g in trained.greedy],
        "length": [float(g["mean_length"].mean()) for g in trained.greedy],
        "return": [float(g["mean_return"].mean()) for g in trained.greedy],
        "random_rate": float(random_runs["success"].mean()),
        "random_length": float(random_runs["length"][random_runs["success"]].mean())
        if random_runs["success"].any() else float("nan"),
        "distance_rate": float(trained.distance_greedy["success"].mean()),
        "best": float(np.mean(trained.shortest_steps)) if trained.shortest_steps else float("nan"),
    }


def _when_arriving(length: float, arrived: str, never: str) -> str:
    """``arrived`` with the mean length of the episodes that reach the goal (NaN: none does: ``never``)."""
    return arrived.format(fmt(length, 3)) if np.isfinite(length) else never


def _claims(m: dict, n_trials: int, n_episodes: int, n_starts: int) -> list[Claim]:
    rate, length, best = m["rate"], m["length"], m["best"]
    return [
        Claim("Delayed reward: SOM-Q with gamma 0.9 learns to go around the wall to the goal (this project's "
              "target, not the paper's).",
              f"gamma 0.9: {fmt(100 * rate[0], 3)}% of {n_trials} x {n_episodes} greedy episodes reach the goal "
              f"(worst trial {fmt(100 * m['worst'][0], 3)}%); mean episode length {fmt(length[0], 3)} steps "
              f"(a failed episode counts at the step limit), mean return {fmt(m['return'][0], 3)} "
              f"(gamma 0: {fmt(m['return'][1], 3)}).",
              rate[0] >= 0.9, ">= 90% of greedy episodes from the task's start distribution reach the goal",
              values={"success gamma 0.9": rate[0], "return gamma 0.9": m["return"][0],
                      "return gamma 0": m["return"][1]}),
        Claim("Without delayed reward (gamma 0) SOM-Q follows the next reward into the wall and reaches the goal "
              "clearly less often.",
              f"gamma 0: {fmt(100 * rate[1], 3)}% (gamma 0.9: {fmt(100 * rate[0], 3)}%); random target changes: "
              f"{fmt(100 * m['random_rate'], 3)}%; the distance-greedy policy: {fmt(100 * m['distance_rate'], 3)}%.",
              rate[1] <= rate[0] - 0.5, "gamma 0 at least 50 points below gamma 0.9",
              values={"success gamma 0": rate[1], "success gamma 0.9": rate[0]}),
        Claim("Greedy episodes with gamma 0.9 are close to the shortest path.",
              f"mean {fmt(length[0], 3)} steps (over all greedy episodes, a failed one counting at the step "
              f"limit) against a shortest path of {fmt(best, 3)} steps (breadth-first search over the nine "
              f"corner/edge/null moves, {counted(n_starts, 'start')}); random target changes "
              + _when_arriving(m["random_length"], "take {} steps when they arrive", "never arrive") + ".",
              bool(np.isfinite(length[0]) and length[0] <= 2 * best), "mean length <= 2 x the shortest path",
              values={"mean length": length[0], "shortest path": best}),
    ]


def task_wall() -> tuple[tuple[float, float], tuple[float, float]]:
    """The wall's lower-left corner and (width, height) in the plane, read from the model."""
    import mujoco

    from somarm.tasks.assets import model_path

    model = mujoco.MjModel.from_xml_path(str(model_path("arm2_obstacle")))
    pos, size = model.geom("wall").pos, model.geom("wall").size
    return (float(pos[0] - size[0]), float(pos[1] - size[1])), (float(2 * size[0]), float(2 * size[1]))


def _figure(ctx: Context, trained: Trained):
    """Learning curves of both runs (left); trial 0's greedy fingertip paths around the wall (right)."""
    fig, (curves, paths) = plt.subplots(1, 2, figsize=(11, 4.6))
    for result, label in zip(trained.results, LABELS, strict=True):
        means = result.block_means
        curves.plot(result.steps, means.mean(axis=1), label=label)
        curves.fill_between(result.steps, means.min(axis=1), means.max(axis=1), alpha=0.2)
    curves.set_xlabel("training step (one control interval in every trial)")
    curves.set_ylabel("mean reward per step (-(1 + distance))")
    curves.set_title("Learning: mean reward of the exploring policy")
    curves.legend()
    wall = task_wall()
    paths.add_patch(plt.Rectangle(wall[0], *wall[1], color="0.35", label="wall"))
    paths.plot(*obstacle.GOAL, "o", color="green", markersize=9, label="goal")
    for tips, label, color in zip(trained.tips, LABELS, ("C0", "C1"), strict=True):
        paths.plot(tips[:, 0], tips[:, 1], color=color, label=f"{label}: fingertip, greedy episode")
    paths.plot(*obstacle.fingertips(trained.starts[0]), "ks", label="start")
    paths.set_aspect("equal")
    paths.set_xlim(0.1, 1.2)
    paths.set_ylim(0.2, 0.9)
    paths.set_title("Trial 0's greedy episode from the first start")
    paths.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    return save(ctx, fig, "delayed_reward.png", crop=False)


def delayed_reward(ctx: Context) -> Section:
    """SOM-Q with gamma 0.9 and 0 on reach2_obstacle; greedy success and length; yardsticks.

    Args:
      ctx: where and how the experiment runs (``ctx.quick``: reduced trial counts and run lengths).

    Returns:
      The report's section: claims with their verdicts, notes, this project's choices, the figures.

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
      ValueError: a figure cannot be written (a full disk), in one line naming it.
    """
    trained = train(ctx)
    config = trained.results[0].config
    notes = [
        "The task: the actuated two-link arm starts right of a wall, the goal lies just left of it. Each step "
        "moves the joint targets by at most 0.4 rad, the servos track them for 0.3 s with MuJoCo contacts, "
        "and the reward is -(1 + d), d the fingertip's distance to the goal. Going straight at the goal ends "
        "at the wall (d = 0.21); going around folds the elbow under the wall, first moving away.",
        f"Both learners trained in lockstep on the same start poses, {counted(config.n_trials, 'trial')} of "
        f"{config.n_steps} steps; episodes that end (goal, or 20 steps) restart in their own trial at the next step.",
    ]
    claims = _claims(measure(trained), config.n_trials, len(trained.starts), len(trained.shortest_steps))
    return Section(
        "delayed_reward",
        "Beyond the paper: delayed reward around a wall (reach2_obstacle)",
        figures=[_figure(ctx, trained)],
        claims=claims,
        notes=notes,
        choices=preset_choices("obstacle"),
    )
