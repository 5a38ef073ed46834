"""``somarm bench tasks``: evaluations per second of every task, MuJoCo beside the closed forms.

For every registered task the same observations and actions (uniform in the task's bounds)
are evaluated in one batched call through MuJoCo (the default backend) and through the
analytic backend, in the same run, so their ratio is meaningful on a busy machine. Beside them:
the largest difference between the two (the landing error for the throws, the fingertip
error for the arms), for the throws MuJoCo's CPU per projectile-step in the large batch (its
native rollouts' thread CPU over the RK4 steps the throws need; ``benchmarks.rollouts``), the
cost of one dm_env episode (``tasks.load``), and the cost of one
training step (``reset`` + ``step``) of 100 and of 20 trials, which is what an experiment pays,
also as a multiple of the large batch's cost per evaluation (all measured in the same run).
Each rate is the best of ``--repeats`` runs; ``--json FILE`` writes every figure. ``--threads 1`` gives the one-core figures, whose ratio
to the default two threads shows how much of the machine the run actually got.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from somarm import tasks
from somarm.helptext import PlainHelpFormatter
from somarm.io import atomic_write_json
from somarm.perf.rollouts import RolloutClock
from somarm.tasks import flight
from somarm.tasks import throw as throw_module
from somarm.validation import OneLineParser, check_int, whole_number

__all__ = ["TARGETS", "measure", "main"]

#: This project's targets for batched MuJoCo evaluations per second on a 2-core machine.
TARGETS: dict[str, float] = {"reach2": 1e6, "reach20": 3e5, "throw": 5e4, "throw_distance": 5e4,
                             "throw_wind": 5e4, "throw_friction": 5e4, "throw_mass": 5e4}
_SIZES = {"reach2": 400_000, "reach20": 100_000, "four_goals": 400_000}
_THROWS = 60_000


def _best_rate(fn, n: int, repeats: int) -> float:
    """Best evaluations per wall-clock second.

    Wall-clock, not CPU time: in this sandbox the process CPU clocks count the main thread only.
    """
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return n / best


def _difference(name: str, task, observations: np.ndarray, actions: np.ndarray) -> float:
    """Largest |MuJoCo - analytic| of the physical outcome: landing x, or fingertip position."""
    if name.startswith("throw"):
        c = task.conditions(observations)
        kwargs = {"params": task.params, "Fr": c["Fr"], "W": c["W"], "M": c["M"]}
        mj = throw_module.landing_x(actions[:, 0], actions[:, 1], backend="mujoco", **kwargs)
        an = throw_module.landing_x(actions[:, 0], actions[:, 1], backend="analytic", **kwargs)
        return float(np.abs(mj - an).max())
    from somarm.tasks import arms, kinematics

    n_links = actions.shape[1]
    return float(np.abs(arms.fingertips(actions, n_links) - kinematics.forward(actions, arms.LINK_LENGTHS[n_links])).max())


def measure(name: str, *, n: int, repeats: int, episodes: int, steps: int) -> dict[str, float]:
    """Figures of one task: rates of both backends, their difference, dm_env and 100-trial costs."""
    rng = np.random.default_rng(0)
    mujoco_task = tasks.make(name)
    analytic_task = tasks.make(name, backend="analytic")
    observations = mujoco_task.sample_observations(rng, n)
    actions = rng.uniform(mujoco_task.action_low, mujoco_task.action_high, (n, mujoco_task.action_low.size))
    warm = slice(0, min(n, 2000))
    mujoco_task.evaluate(observations[warm], actions[warm])  # build the batch models outside the timing
    figures = {
        "mujoco": _best_rate(lambda: mujoco_task.evaluate(observations, actions), n, repeats),
        "analytic": _best_rate(lambda: analytic_task.evaluate(observations, actions), n, repeats),
        "difference": _difference(name, mujoco_task, observations, actions),
    }
    if name.startswith("throw"):
        figures["projectile_step_us"], figures["projectile_steps"] = _projectile_step_us(
            mujoco_task, observations, actions, repeats)
    env = tasks.load(name)
    env_actions = actions[:episodes]

    def episodes_run():
        for action in env_actions:
            env.reset()
            env.step(action)

    figures["dm_env_us"] = 1e6 / _best_rate(episodes_run, len(env_actions), repeats)
    for n_trials in (100, 20):
        figures[f"step{n_trials}_ms"] = _step_ms(name, n_trials, steps, rng, repeats)
    return figures


def _projectile_step_us(task, observations: np.ndarray, actions: np.ndarray, repeats: int) -> tuple[float, float]:
    """MuJoCo's CPU per projectile-step when the task evaluates the batch: the thread CPU of its native
    rollouts over the RK4 steps its throws need (each throw's model steps), best of ``repeats``; and
    those steps per throw."""
    c = task.conditions(observations)
    n = len(actions)
    throws = [np.broadcast_to(np.asarray(v, dtype=np.float64), (n,))
              for v in (actions[:, 0], actions[:, 1], c["Fr"], c["W"], c["M"])]
    needed = float(flight._plan(*throws, G=task.params.G, tolerance=task.params.tolerance, workers=1).flat[-1].sum())
    best = float("inf")
    for _ in range(repeats):
        with RolloutClock() as clock:
            task.evaluate(observations, actions)
        best = min(best, clock.us_per_projectile_step(needed))
    return best, needed / n


def _step_ms(name: str, n_trials: int, steps: int, rng: np.random.Generator, repeats: int) -> float:
    """Milliseconds per training step (``reset`` + ``step``) of ``n_trials`` trials, best of ``repeats``."""
    batch = tasks.make(name, n_trials=n_trials)
    trial_actions = rng.uniform(batch.action_low, batch.action_high, (steps, n_trials, batch.action_low.size))
    batch.reset()
    batch.step(trial_actions[0])  # this thread's batch models are built here, outside the timing

    def run():
        for a in trial_actions:
            batch.reset()
            batch.step(a)

    return 1e3 / _best_rate(run, steps, repeats)


def main(argv: list[str] | None = None) -> int:
    """Print the table (and write ``--json``); returns 0 (a benchmark reports, it does not fail)."""
    parser = OneLineParser(prog="somarm bench tasks", description=__doc__.splitlines()[0], formatter_class=PlainHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="small batches, one repeat (a smoke run)")
    parser.add_argument("--repeats", type=whole_number, default=3, help="timed runs per figure, best kept (3)")
    parser.add_argument("--only", nargs="+", metavar="TASK",
                        help="benchmark only these tasks ('driven': the actuated and obstacle rows)")
    parser.add_argument("--threads", type=whole_number, default=2, help="threads of the MuJoCo backend (2)")
    parser.add_argument("--json", type=Path, metavar="FILE", help="also write every figure to FILE (JSON)")
    args = parser.parse_args(argv)
    check_int("--repeats", args.repeats)
    if args.json is not None and not args.json.parent.is_dir():
        raise ValueError(f"--json {args.json}: the folder {args.json.parent} does not exist")
    tasks.set_threads(check_int("--threads", args.threads))
    names = args.only or [name for name in tasks.names() if name != "reach2_obstacle"]
    driven = args.only is None or "driven" in names or "reach2_obstacle" in names
    names = [name for name in names if name not in ("driven", "reach2_obstacle")]
    for name in names:
        tasks.record(name)  # unknown names fail here, in one line
    scale = 20 if args.quick else 1
    repeats = 1 if args.quick else max(1, args.repeats)
    episodes, steps = (30, 5) if args.quick else (300, 40)
    print(f"{'task':15s} {'MuJoCo/s':>10s} {'analytic/s':>10s} {'ratio':>6s} {'|MJ-exact|':>10s} "
          f"{'dm_env us':>9s} {'step100 ms':>10s} {'x batch':>7s} {'step20 ms':>9s} {'x batch':>7s} "
          f"{'us/proj-step':>12s}  target")
    results = {}
    for name in names:
        n = max(1000, (_SIZES.get(name, _THROWS)) // scale)
        f = measure(name, n=n, repeats=repeats, episodes=episodes, steps=steps)
        # Cost per evaluation in a training step, as a multiple of its cost in the large batch.
        f["step100_x"] = f["step100_ms"] * 1e-3 / 100 * f["mujoco"]
        f["step20_x"] = f["step20_ms"] * 1e-3 / 20 * f["mujoco"]
        results[name] = f
        target = TARGETS.get(name)
        verdict = ""
        if target is not None:
            verdict = f">= {target:.0e}/s: {'met' if f['mujoco'] >= target else 'MISSED'}"
            if name.startswith("throw"):
                verdict += f"; error <= 1e-6: {'met' if f['difference'] <= 1e-6 else 'MISSED'}"
                verdict += (f"; steps <= 1.5x/4x: {'met' if f['step100_x'] <= 1.5 else 'MISSED'}/"
                            f"{'met' if f['step20_x'] <= 4 else 'MISSED'}")
        print(f"{name:15s} {f['mujoco']:10.3g} {f['analytic']:10.3g} {f['analytic'] / f['mujoco']:6.0f} "
              f"{f['difference']:10.1e} {f['dm_env_us']:9.0f} {f['step100_ms']:10.2f} {f['step100_x']:7.2f} "
              f"{f['step20_ms']:9.2f} {f['step20_x']:7.2f} "
              f"{format(f['projectile_step_us'], '12.3f') if 'projectile_step_us' in f else '-':>12s}  {verdict}",
              flush=True)
    print("MuJoCo/s and analytic/s: evaluations per second in one batched call, same inputs; "
          "|MJ-exact|: largest landing (throws) or fingertip (arms) difference; step100/step20: one "
          "training step (reset + step) of 100/20 trials, and its cost per evaluation as a multiple "
          "of the large batch's; us/proj-step: MuJoCo's CPU per RK4 step a throw needs, in the large batch.")
    print(f"Throws: each flight in the fewest equal RK4 steps whose landing-error bound is within "
          f"{flight.DEFAULT_TOLERANCE:g}, all steps in one model by time scaling; {flight.THREADS} thread(s); "
          "a batch in one model, landed throws leaving it (the staircase).")
    if driven:
        from somarm.perf import driven as driven_rows

        driven_rows.print_rows(quick=args.quick, repeats=repeats)
    if args.json is not None:
        _write_json(args.json, {
            "threads": args.threads, "quick": args.quick, "repeats": repeats,
            "tasks": {name: {"mujoco_per_s": f["mujoco"], "analytic_per_s": f["analytic"],
                             "difference": f["difference"], "dm_env_us": f["dm_env_us"],
                             "step100_ms": f["step100_ms"], "step100_x_batch": f["step100_x"],
                             "step20_ms": f["step20_ms"], "step20_x_batch": f["step20_x"],
                             **({"mujoco_us_per_projectile_step": f["projectile_step_us"],
                                 "projectile_steps_per_throw": f["projectile_steps"]}
                                if "projectile_step_us" in f else {})}
                      for name, f in results.items()},
        })
        print(f"figures written to {args.json}")
    return 0


def _write_json(path: Path, figures: dict) -> None:
    try:
        atomic_write_json(path, figures)
    except OSError as exc:
        raise ValueError(f"cannot write --json {path}: {exc.strerror or exc}") from None
