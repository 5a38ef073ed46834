"""The smaller faults, on real processes: a name too long for the file system and a value nested
30,000 deep are one line each; every JSON file a run writes is strict JSON; ``SOMQ.save("")`` is refused."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest
from processes import checkout_env, one_error_line, somarm_command

from somarm import run

LONG = "x" * 300
DEEP = "[" * 30_000 + "]" * 30_000


def somarm(*argv: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(somarm_command(*argv), capture_output=True, text=True, env=checkout_env(), timeout=120,
                          cwd=cwd)


@pytest.mark.parametrize("argv", [
    ("train", "reach2", "--steps", "100"),
    ("sweep", "reach2", "--grid", "alpha=0.1,0.2", "--steps", "100"),
    ("compare", "reach2", "--learners", "tabular", "--samples", "200"),
])
def test_an_out_name_too_long_for_the_file_system_is_one_line(tmp_path, argv):
    one_error_line(somarm(*argv, "--out", str(tmp_path / LONG)), "File name too long", "give a shorter folder name")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv", [
    ("train", "reach2", "--steps", "100", "--task-set", f"radius={DEEP}"),
    ("sweep", "reach2", "--steps", "100", "--grid", f"task.radius=0.1,{DEEP}"),
    ("compare", "reach2", "--learners", "tabular", "--samples", "200", "--task-set", f"radius={DEEP}"),
])
def test_a_task_parameter_nested_30000_deep_is_one_line(tmp_path, argv):
    line = one_error_line(somarm(*argv, "--out", str(tmp_path / "out")), "nested too deeply")
    assert len(line) < 400
    assert not (tmp_path / "out").exists()


def test_every_json_file_of_a_run_is_strict_even_with_non_finite_values(tmp_path):
    result = run.train(run.RunConfig(task="reach2", n_steps=100), progress=False)
    run.write(result, tmp_path / "run", figures=False,
              extra_summary={"greedy_mean_reward": float("inf"), "spread": [1.0, float("nan")]})
    for path in (tmp_path / "run").glob("*.json"):
        data = json.loads(path.read_text(), parse_constant=pytest.fail)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["greedy_mean_reward"] is None and summary["non_finite"] == {
        "/greedy_mean_reward": "inf", "/spread/1": "nan"}
    assert data is not None


def test_save_to_an_empty_path_is_refused_and_writes_nothing(tmp_path):
    code = ("from somarm import SOMQ\nmodel = SOMQ('reach2')\nmodel.learn(100)\ntry:\n    model.save('')\n"
            "except ValueError as exc:\n    print(exc)\n")
    done = subprocess.run([__import__("sys").executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                          env=checkout_env(), timeout=120)
    assert done.returncode == 0 and len(done.stdout.strip().splitlines()) == 1, done.stdout + done.stderr
    assert "SOMQ.save needs a path" in done.stdout and list(tmp_path.iterdir()) == []


def test_an_observation_box_with_a_flat_dimension_is_named_as_such():
    from somarm.validation import check_observation_box

    with pytest.raises(ValueError, match=r"low == high in dimension\(s\) \[1\]"):
        check_observation_box("gym:Flat-v0", np.array([-1.0, 2.0]), np.array([1.0, 2.0]))
    check_observation_box("gym:Ok-v0", np.array([-1.0, -np.inf]), np.array([1.0, np.inf]))


FLAT_ENV = '''
import gymnasium
import numpy as np


class Flat(gymnasium.Env):
    observation_space = gymnasium.spaces.Box(np.array([-1.0, 2.0]), np.array([1.0, 2.0]), (2,), np.float64)
    action_space = gymnasium.spaces.Box(-1.0, 1.0, (1,), np.float64)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.array([0.0, 2.0]), {}

    def step(self, action):
        return np.array([0.5, 2.0]), 0.0, False, False, {}


gymnasium.register("Flat-v0", entry_point=Flat, max_episode_steps=5)
'''


def test_training_on_a_box_with_a_flat_dimension_is_one_line_naming_it(tmp_path):
    (tmp_path / "flat_env.py").write_text(FLAT_ENV)
    done = somarm("train", "gym:flat_env:Flat-v0", "--steps", "100", "--out", str(tmp_path / "out"), cwd=tmp_path)
    one_error_line(done, "low == high in dimension(s) [1]")
    assert not (tmp_path / "out").exists()
