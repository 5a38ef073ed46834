"""A run whose environment fails keeps what it learned, on real processes: an exception raised by the
environment at step 30, a NaN observation at step 30, and SIGHUP each leave a valid partial run (marked
failed, with the error's one line, where the environment failed) and one line on stderr, never a traceback."""

from __future__ import annotations

import json
import signal
import subprocess
from pathlib import Path

import numpy as np
import pytest
from processes import checkout_env, one_error_line, somarm_command

#: A Gymnasium environment that fails at its 30th step (after a reset, as every copy is stepped).
FAILING_ENV = '''
import gymnasium
import numpy as np


class Failing(gymnasium.Env):
    observation_space = gymnasium.spaces.Box(-1.0, 1.0, (2,), np.float64)
    action_space = gymnasium.spaces.Box(-1.0, 1.0, (1,), np.float64)

    def __init__(self, how="raise"):
        self.how, self.steps = how, 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(2), {}

    def step(self, action):
        self.steps += 1
        observation = np.full(2, 0.5)
        if self.steps == 30 and self.how == "raise":
            raise RuntimeError("the simulator lost its connection\\nsecond line")
        if self.steps >= 30 and self.how == "nans":
            observation[1] = np.nan
        return observation, -float(abs(action[0])), False, False, {}


gymnasium.register("Failing-v0", entry_point=Failing, max_episode_steps=5)
'''


def _train_failing(tmp_path: Path, how: str) -> tuple[subprocess.CompletedProcess, Path]:
    (tmp_path / "failing_env.py").write_text(FAILING_ENV)
    out = tmp_path / "run"
    done = subprocess.run(somarm_command("train", "gym:failing_env:Failing-v0", "--task-set", f"how={how}",
                                         "--steps", "100", "--block", "10", "--no-progress", "--no-figures",
                                         "--out", str(out)),
                          capture_output=True, text=True, cwd=tmp_path, env=checkout_env(), timeout=120)
    return done, out


@pytest.mark.parametrize("how, said", [("raise", "RuntimeError: the simulator lost its connection"),
                                       ("nans", "FloatingPointError: the task's next observation of trial 0 is not "
                                               "finite")])
def test_a_failing_environment_keeps_the_partial_run_marked_failed(tmp_path, how, said):
    done, out = _train_failing(tmp_path, how)
    line = one_error_line(done, "training failed at step 30", said, f"kept in {out}")
    assert "second line" not in line
    summary = json.loads((out / "summary.json").read_text(), parse_constant=pytest.fail)
    assert summary["failed"].startswith("training failed at step 30: ") and summary["interrupted"]
    assert summary["steps"] == 29
    with np.load(out / "curves.npz") as curves:
        assert curves["block_means"].shape == (2, 1) and np.isfinite(curves["block_means"]).all()
    assert (out / "learner.npz").stat().st_size > 0 and not (out / ".somarm-new").exists()


def test_sighup_keeps_a_valid_partial_run(tmp_path):
    out = tmp_path / "run"
    # As from a terminal: a suite started under nohup would hand the run SIGHUP ignored, which it keeps ignored.
    proc = subprocess.Popen(somarm_command("train", "reach2", "--steps", "50000000", "--no-figures", "--out", str(out)),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=checkout_env(),
                            preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_DFL))
    try:
        line = proc.stderr.readline()
        assert "mean reward" in line, line + proc.stderr.read()
        proc.send_signal(signal.SIGHUP)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130 and "Traceback" not in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] and 0 < summary["steps"] < 50_000_000
    assert (out / "learner.npz").is_file() and not (out / ".somarm-new").exists()
