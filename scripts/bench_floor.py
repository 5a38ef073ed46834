"""Where the time goes, and the floor MuJoCo and the learners' kernels set under the time of an experiment.

Three measurements, each in one run on this machine:

1. ``dm_env``: a throw episode of ``tasks.load`` against its MuJoCo part alone (the throw's own RK4
   steps in one native ``mj_step`` call on the launcher model, no Python per step). If the MuJoCo
   part alone is above the 100 us target, no glue can meet it.
2. ``steps``: MuJoCo's CPU per projectile-step (the thread CPU of the native rollouts over the RK4
   steps the throws need) in a training step of 20 and of 100 trials and in a large batch, for the
   tasks' design (a batch in one model, landed throws leaving: the staircase;
   ``somarm.perf.rollouts`` clocks it), and each step's cost per throw (the flights alone,
   planned beforehand) as a multiple of the large batch's (the target: 1.5x at 100).
3. ``paper``: the paper's experiments one after another (lanes as usual, no worker processes), with
   the CPU seconds of every thread spent in MuJoCo's native calls and in the learners' compiled
   kernels. Their sum over the machine's 2 cores is a floor that no scheduling or glue can beat.

Usage:
  python scripts/bench_floor.py                   # all three (the paper part takes a few minutes)
  python scripts/bench_floor.py --skip-paper      # the first two only (about a minute)
  python scripts/bench_floor.py --quick           # reduced sizes and the --quick experiments
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
import threading
import time
import types
from collections import defaultdict
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "disable")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from somarm import tasks  # noqa: E402
from somarm.learners import somq  # noqa: E402
from somarm.perf import best_seconds  # noqa: E402
from somarm.perf.rollouts import RolloutClock  # noqa: E402
from somarm.reproduce import common, runner  # noqa: E402
from somarm.tasks import arms, flight  # noqa: E402
from somarm.tasks.assets import model_path  # noqa: E402
from somarm.validation import OneLineParser  # noqa: E402

THROWS = ("throw", "throw_distance", "throw_wind", "throw_friction", "throw_mass")
#: The paper's experiments (what the 120 s target covers), in the paper's order.
PAPER = ("reach2", "reach20", "four_goals", "throw", "throw_maps", "neighbourhood_q", "more_inputs")


def _throws(name: str, n: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """``n`` throws of a task: its observations' conditions and uniform launch velocities."""
    task = tasks.make(name)
    c = task.conditions(task.sample_observations(rng, n))
    out = {k: np.broadcast_to(np.asarray(c[k], dtype=np.float64), (n,)).copy() for k in ("Fr", "W", "M")}
    out["ux"], out["uy"] = rng.uniform(0.0, 1.0, (2, n))
    return out


def _plan(t: dict[str, np.ndarray], part: slice = slice(None)):
    """The tasks' own plan of these throws in one thread (steps, sorting, groups; ``flight._plan``)."""
    return flight._plan(*(t[key][part] for key in ("ux", "uy", "Fr", "W", "M")), G=0.05,
                        tolerance=flight.DEFAULT_TOLERANCE, workers=1)


def dm_env_floor(episodes: int, repeats: int) -> None:
    """Part 1: a dm_env throw episode against its RK4 steps in one native call."""
    print("dm_env throw episode: whole episode vs its MuJoCo steps alone (target <= 100 us)")
    model = mujoco.MjModel.from_xml_path(str(model_path("launcher")))
    model.opt.timestep = flight.SCALED_STEP
    data = mujoco.MjData(model)
    bare = flight.ProjectileBatch(1, G=0.05)  # the leanest model a throw can fly in: one body, two joints
    for name in THROWS:
        t = _throws(name, episodes, np.random.default_rng(0))
        steps = flight._model_steps(_plan(t).lengths).astype(int)  # the steps each flight takes
        env = tasks.load(name)
        actions = np.stack([t["ux"], t["uy"]], axis=-1)

        def whole(env=env, actions=actions):
            for action in actions:
                env.reset()
                env.step(action)

        def physics_only(model=model, data=data, steps=steps):
            for n in steps:
                mujoco.mj_step(model, data, nstep=int(n))

        whole_us = best_seconds(whole, repeats) / episodes * 1e6
        floor_us = best_seconds(physics_only, repeats) / episodes * 1e6
        bare_us = best_seconds(lambda: physics_only(bare.model, bare.data), repeats) / episodes * 1e6
        print(f"  {name:15s} RK4 steps a throw {steps.mean():5.1f}   episode {whole_us:5.0f} us   its MuJoCo "
              f"steps alone {floor_us:4.0f} us, in the leanest model {bare_us:4.0f} us   "
              f"{'below' if min(floor_us, bare_us) <= 100 else 'ABOVE'} the target")


#: The tasks' design of a batch's flights, a function of their plan: landings in flight order.
DESIGNS = {"staircase": lambda plan: flight._fly(plan, 0.05)}


def _measure(plans, fly, repeats: int) -> tuple[float, float, float]:
    """Best of ``repeats``: CPU seconds of the flights (this thread's), MuJoCo's CPU per needed
    projectile-step in microseconds, and the body-steps MuJoCo took per needed projectile-step."""
    needed = sum(float(plan.flat[-1].sum()) for plan in plans)
    for plan in plans[:3]:  # this thread's models are built here, outside the timing
        fly(plan)
    best = (np.inf, np.inf, np.inf)
    for _ in range(repeats):
        with RolloutClock() as clock:
            start = time.thread_time()  # CPU, not wall: a busy machine's waits left out
            for plan in plans:
                fly(plan)
            seconds = time.thread_time() - start
        best = min(best, (seconds, clock.us_per_projectile_step(needed), clock.body_steps / needed))
    return best


def step_floor(large: int, steps: int, repeats: int) -> dict[str, dict]:
    """Part 2: MuJoCo's CPU per projectile-step, and steps as multiples of a large batch.

    Returns:
      Per task, per design and batch size (20, 100, ``large``): ``us_per_projectile_step``,
      ``body_steps_per_projectile_step`` and ``us_per_throw`` (the flights' CPU).
    """
    print("training steps and a large batch, one thread: MuJoCo's CPU per projectile-step (its native rollouts "
          "over the RK4 steps the throws need; in brackets the steps MuJoCo took per needed one), and the flights' "
          "CPU per throw as a multiple of the large batch's (target <= 1.5x at 100 trials)")
    print(f"  {'task':15s} {'throws':>6s}   {'staircase':>16s}   {'x large':>7s}")
    figures: dict[str, dict] = {}
    for name in THROWS:
        t = _throws(name, large, np.random.default_rng(1))
        figures[name] = {}
        for n, count in ((20, steps), (100, steps), (large, 1)):
            plans = [_plan(t, slice(j * n, (j + 1) * n)) for j in range(count)]
            row = {design: _measure(plans, fly, repeats) for design, fly in DESIGNS.items()}
            figures[name][n] = {design: {"us_per_projectile_step": us, "body_steps_per_projectile_step": ratio,
                                         "us_per_throw": seconds / (n * count) * 1e6}
                                for design, (seconds, us, ratio) in row.items()}
        big = figures[name][large]["staircase"]["us_per_throw"]
        for n in (20, 100, large):
            f = figures[name][n]
            cells = "   ".join(f"{f[d]['us_per_projectile_step']:6.3f} us ({f[d]['body_steps_per_projectile_step']:4.2f})"
                               for d in DESIGNS)
            print(f"  {name:15s} {n:6d}   {cells}   {f['staircase']['us_per_throw'] / big:6.2f}x", flush=True)
    return figures


class _Clock:
    """CPU seconds of every thread inside wrapped functions, by kind (a call may count for several)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.seconds: dict[str, float] = defaultdict(float)

    def wrap(self, kinds: tuple[str, ...], fn):
        def timed(*args, **kwargs):
            start = time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                spent = time.thread_time() - start
                with self.lock:
                    for kind in kinds:
                        self.seconds[kind] += spent
        return timed

    def count(self, fly):
        """``flight._fly`` that also adds the RK4 steps its throws need to ``seconds["projectile_steps"]``."""
        def counted(plan, G):
            with self.lock:
                self.seconds["projectile_steps"] += float(plan.flat[-1].sum())
            return fly(plan, G)
        return counted


def _proxy(module, **wrapped) -> types.SimpleNamespace:
    """A stand-in for ``module`` whose named functions are replaced."""
    names = {n: getattr(module, n) for n in dir(module) if not n.startswith("__")}
    return types.SimpleNamespace(**{**names, **wrapped})


@contextlib.contextmanager
def _clocked():
    """A ``_Clock`` on MuJoCo's native calls and the learners' kernels, every group in this process."""
    clock = _Clock()
    saved = (flight.mj_rollout, flight._fly, arms.mujoco, somq._kernels, common.SPLIT_TRIAL_STEPS)
    flight.mj_rollout = _proxy(flight.mj_rollout,
                               rollout=clock.wrap(("mujoco", "flights"), flight.mj_rollout.rollout))
    flight._fly = clock.count(flight._fly)
    arms.mujoco = _proxy(mujoco, mj_kinematics=clock.wrap(("mujoco",), mujoco.mj_kinematics))
    somq._kernels = _proxy(somq._kernels, act_kernel=clock.wrap(("kernels",), somq._kernels.act_kernel),
                           learn_kernel=clock.wrap(("kernels",), somq._kernels.learn_kernel))
    common.SPLIT_TRIAL_STEPS = float("inf")  # no worker processes: the clock sees every group
    try:
        yield clock
    finally:
        flight.mj_rollout, flight._fly, arms.mujoco, somq._kernels, common.SPLIT_TRIAL_STEPS = saved


def paper_floor(quick: bool, cores: int, names: tuple[str, ...] = PAPER, label: str = "") -> dict[str, float]:
    """Part 3: the experiments with the CPU seconds of MuJoCo and of the learners' kernels.

    Returns:
      The totals: ``wall``, ``mujoco`` and ``kernels`` seconds, and the ``floor`` on ``cores``.
    """
    print(f"the paper's experiments{' (--quick)' if quick else ''}{label}, one after another: wall time and the "
          "CPU seconds of all threads in MuJoCo's native calls and in the learners' kernels")
    totals = defaultdict(float)
    with _clocked() as clock, tempfile.TemporaryDirectory() as folder:
        for name in names:
            before = dict(clock.seconds)
            start = time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):  # the runner's own lines
                runner.reproduce(Path(folder) / name, quick=quick, only=[name], progress=False)
            wall = time.perf_counter() - start
            spent = {k: clock.seconds[k] - before.get(k, 0.0)
                     for k in ("mujoco", "kernels", "flights", "projectile_steps")}
            for key, value in (("wall", wall), *spent.items()):
                totals[key] += value
            totals[f"mujoco:{name}"] = spent["mujoco"]
            print(f"  {name:16s} wall {wall:7.1f} s   MuJoCo {spent['mujoco']:7.1f} s   kernels "
                  f"{spent['kernels']:6.1f} s{_flights_line(spent)}", flush=True)
    totals["floor"] = (totals["mujoco"] + totals["kernels"]) / cores
    print(f"  {'all':16s} wall {totals['wall']:7.1f} s   MuJoCo {totals['mujoco']:7.1f} s   kernels "
          f"{totals['kernels']:6.1f} s{_flights_line(totals)}")
    print(f"  floor on {cores} cores, MuJoCo and kernels perfectly shared, nothing else: {totals['floor']:.1f} s")
    return dict(totals)


def _flights_line(spent: dict[str, float]) -> str:
    """What the throws' flights took of MuJoCo's time: its seconds, the RK4 steps the throws needed
    and the microseconds per step ("" without throws)."""
    if not spent["projectile_steps"]:
        return ""
    return (f"   (flights {spent['flights']:.1f} s for {spent['projectile_steps'] / 1e6:.1f}M projectile-steps, "
            f"{spent['flights'] / spent['projectile_steps'] * 1e6:.3f} us each)")


def main(argv: list[str] | None = None) -> int:
    """Print the three parts; 0, or 2 after one line naming a bad option."""
    parser = OneLineParser(prog="bench_floor.py", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes and the --quick experiments")
    parser.add_argument("--skip-paper", action="store_true", help="only the dm_env and training-step parts")
    try:
        args = parser.parse_args(argv)
    except ValueError as exc:
        print(f"bench_floor.py: error: {exc} (allowed: --quick, --skip-paper)", file=sys.stderr)
        return 2
    repeats = 1 if args.quick else 4
    dm_env_floor(episodes=50 if args.quick else 400, repeats=repeats)
    step_floor(large=6000 if args.quick else 60_000, steps=5 if args.quick else 60, repeats=repeats)
    if not args.skip_paper:
        paper_floor(args.quick, os.cpu_count() or 2)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
