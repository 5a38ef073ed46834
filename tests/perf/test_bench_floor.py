"""The floor benchmark's accounting (scripts/bench_floor.py): what it clocks, and that it cleans up."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np

from somarm import tasks
from somarm.learners import somq
from somarm.reproduce import common
from somarm.tasks import arms, flight

_SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "bench_floor.py"


def _load():
    spec = importlib.util.spec_from_file_location("bench_floor", _SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules["bench_floor"] = module
    spec.loader.exec_module(module)
    return module


def test_the_clock_counts_mujoco_and_kernels_and_puts_everything_back(capsys):
    bench = _load()
    saved = (flight.mj_rollout, flight._fly, arms.mujoco, somq._kernels, common.SPLIT_TRIAL_STEPS)
    with bench._clocked() as clock:
        assert common.SPLIT_TRIAL_STEPS == float("inf")
        task = tasks.make("throw_distance", n_trials=40)
        task.reset()
        task.step(np.full((40, 2), 0.6))
        arms.fingertips(np.zeros((10, 2)), 2)
    assert clock.seconds["mujoco"] > clock.seconds["flights"] > 0.0 and clock.seconds["kernels"] == 0.0
    assert clock.seconds["projectile_steps"] >= 40  # the 40 throws' RK4 steps, at least one each
    assert (flight.mj_rollout, flight._fly, arms.mujoco, somq._kernels, common.SPLIT_TRIAL_STEPS) == saved
    totals = bench.paper_floor(True, 2, names=("throw",))
    out = capsys.readouterr().out
    assert "throw " in out and "floor on 2 cores" in out
    # Thread CPU inside the wrapped calls: some of each, and no more than two cores' worth of the wall.
    assert 0.0 < totals["mujoco"] and 0.0 < totals["kernels"]
    assert totals["mujoco"] + totals["kernels"] <= 2 * totals["wall"]
    assert totals["floor"] == (totals["mujoco"] + totals["kernels"]) / 2
    assert 0.0 < totals["flights"] <= totals["mujoco"] and "projectile-steps" in out
    assert (flight.mj_rollout, flight._fly, arms.mujoco, somq._kernels, common.SPLIT_TRIAL_STEPS) == saved


def test_the_step_part_clocks_the_flights_of_every_batch_size(capsys):
    bench = _load()
    figures = bench.step_floor(large=300, steps=2, repeats=1)
    assert "staircase" in capsys.readouterr().out
    for name in bench.THROWS:
        for n in (20, 100, 300):
            f = figures[name][n]["staircase"]
            # MuJoCo steps at least the bodies the throws need, and takes some time for them
            assert f["us_per_projectile_step"] > 0 and f["body_steps_per_projectile_step"] >= 0.9


def test_a_bad_option_is_one_line(capsys):
    assert _load().main(["--fast"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--fast" in err and "--quick" in err and "--skip-paper" in err
