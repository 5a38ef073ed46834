"""``somarm train`` writes the trained run before its greedy evaluation, and says when the evaluation's cap
cut episodes: on real processes."""

from __future__ import annotations

import json
import signal
import subprocess
import time

import pytest
from processes import checkout_env, somarm_command, train_into_an_endless_evaluation

from somarm import run

pytest.importorskip("gymnasium")
ENV = checkout_env()


def test_a_sigkill_during_the_greedy_evaluation_keeps_the_trained_run(tmp_path):
    out = tmp_path / "run"
    proc = train_into_an_endless_evaluation(out, ENV)
    try:
        # The run is written before the evaluation starts: wait for its summary, then kill in the evaluation.
        deadline = time.monotonic() + 60
        while not (out / "summary.json").exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(0.5)  # in the evaluation now
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == -signal.SIGKILL
    config, learner = run.load(out)
    assert learner.t == 300 and config.task == "gym:Pendulum-v1"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 300 and "greedy_mean_return" not in summary
    assert (out / "curves.npz").exists()
    assert not [p for p in out.iterdir() if p.name.startswith(".somarm-new")]


def test_the_done_line_and_evaluate_say_how_many_greedy_episodes_the_cap_cut(tmp_path):
    out = tmp_path / "run"
    done = subprocess.run(somarm_command("train", "gym:Pendulum-v1", "--steps", "200", "--trials", "1", "--task-set",
                                         "evaluation_steps=5", "--no-figures", "--no-progress", "--out", str(out)),
                          capture_output=True, text=True, env=ENV, timeout=300)
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["greedy_episodes_cut"] == summary["greedy_episodes"]  # Pendulum's 200-step episodes, cut at 5
    note = f"({summary['greedy_episodes']} of {summary['greedy_episodes']} episodes cut at 5 steps"
    assert note in done.stdout, done.stdout
    evaluated = subprocess.run(somarm_command("evaluate", str(out)), capture_output=True, text=True, env=ENV,
                               timeout=300)
    assert evaluated.returncode == 0 and note in evaluated.stdout, evaluated.stdout + evaluated.stderr
