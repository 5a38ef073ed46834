"""A lockstep group shared out between processes (``somarm.run.split``): equal results, clean stops."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
from processes import still_running, survivors_of_a_killed_parent

from somarm import run
from somarm.run import RunConfig
from somarm.run.split import train_split

_ENV = {**os.environ, "MUJOCO_GL": "disable"}


def _configs(n_steps: int) -> list[RunConfig]:
    return [
        RunConfig(task="throw_distance", preset="table7a", n_trials=3, n_steps=n_steps, seed=2, block=50,
                  task_params={"punish_low": True}),
        RunConfig(task="throw_mass", preset="table7", n_trials=2, n_steps=n_steps, seed=2, block=50),
        RunConfig(task="reach2", n_trials=2, n_steps=n_steps, seed=5, block=50),
    ]


def test_a_group_in_two_processes_equals_the_group_in_one():
    configs = _configs(200)
    together = run.train_group(configs, progress=False)
    split = train_split(configs, processes=2, progress=False, snapshots_at=(100,))
    for a, b in zip(together, split, strict=True):
        assert a.config == b.config and not b.interrupted and b.steps_done == 200
        np.testing.assert_array_equal(a.block_means, b.block_means)
        np.testing.assert_array_equal(a.learner.q, b.learner.q)
        assert set(b.snapshots) == {100}


_SCRIPT = textwrap.dedent("""
    import os, sys
    from somarm.run import RunConfig
    from somarm.run.split import train_split
    configs = [RunConfig(task="throw_mass", preset="table7", n_trials=100, n_steps=10**6, seed=s) for s in (0, 1)]
    print("training", flush=True)
    results = train_split(configs, processes=2, progress=False)
    print("interrupted", all(r.interrupted for r in results), [r.steps_done > 0 for r in results], flush=True)
""")


def test_ctrl_c_stops_both_shares_and_leaves_no_worker(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", _SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=_ENV)
    try:
        assert proc.stdout.readline().strip() == "training"
        time.sleep(8)  # both shares under way (a worker starts in about 3 s)
        children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()
        assert children, "the second share runs in a worker process"
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert "interrupted True [True, True]" in out
    left = still_running(map(int, children), 10)  # multiprocessing's resource tracker may take a moment
    assert not left, f"worker(s) {left} still running"


def test_a_killed_parent_leaves_no_worker_training():
    # SIGKILL gives the parent no chance to stop its workers: each must notice by itself and end.
    proc = subprocess.Popen([sys.executable, "-c", _SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=_ENV)
    try:
        assert proc.stdout.readline().strip() == "training"
        time.sleep(8)  # the worker's share under way
        children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()
        workers = [pid for pid in map(int, children) if "somarm.run.split" in _command(pid) or "spawn_main" in _command(pid)]
        assert workers, "the second share runs in a worker process"
        left = survivors_of_a_killed_parent(proc, workers, 30)  # it stops between two steps
    finally:
        proc.kill()
    assert not left, f"worker(s) {left} still training after their parent died"


def _command(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as cmdline:
            return cmdline.read().replace(b"\0", b" ").decode()
    except OSError:
        return ""
