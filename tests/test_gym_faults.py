"""Faults on the Gymnasium surface, on real processes: a greedy evaluation stopped by a signal, keyword
values and ids checked before a run starts, ``SOMQ``'s size refusal and interrupted ``learn``, a
missing extra."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from processes import checkout_env, one_error_line, somarm_command, train_into_an_endless_evaluation

from somarm import run

ENV = checkout_env()


def somarm(*argv: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(somarm_command(*argv), capture_output=True, text=True, env=ENV, timeout=timeout)


def python(code: str, *, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=ENV, timeout=timeout)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_during_the_greedy_evaluation_cuts_it_and_writes_the_trained_run(tmp_path, sig):
    out = tmp_path / "run"
    proc = train_into_an_endless_evaluation(out, ENV)
    try:
        time.sleep(1.0)  # in the greedy evaluation now
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and f"stopped by {sig.name}" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["greedy_cut"] is True and summary["interrupted"] is True and summary["steps"] == 300
    assert "greedy_mean_return" not in summary
    config, learner = run.load(out)
    assert learner.t == 300 and config.task_params["evaluation_steps"] == 100_000_000
    assert not [p for p in out.iterdir() if p.name.startswith(".somarm-new")]


@pytest.mark.parametrize(("task_set", "needles"), [
    ("g=abc", ("with keyword g='abc' fails at its first step (TypeError: ",)),
    ("g=nan", ("with keyword g=nan fails", "is not finite")),
    ("render_mode=human", ("render_mode='human' is not taken by gym:Pendulum-v1",)),
    ("max_episode_steps=-1", ("max_episode_steps of gym:Pendulum-v1 takes a whole number of steps >= 1, got -1",)),
])
def test_a_keyword_value_gymnasium_cannot_take_is_one_line_before_anything_is_written(tmp_path, task_set, needles):
    out = tmp_path / "run"
    one_error_line(somarm("train", "gym:Pendulum-v1", "--steps", "100", "--task-set", task_set, "--out", str(out)),
                   *needles)
    assert not out.exists()


@pytest.fixture(scope="module")
def pendulum_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("gym") / "pendulum"
    result = run.train(run.RunConfig(task="gym:Pendulum-v1", n_steps=100, seed=1), progress=False)
    run.write(result, out, figures=False)
    return out


def test_evaluate_with_a_keyword_value_gymnasium_cannot_take_is_one_line(pendulum_run):
    one_error_line(somarm("evaluate", str(pendulum_run), "--task-set", "g=abc"), "with keyword g='abc' fails")


def test_a_malformed_id_on_the_command_line_or_in_config_json_is_one_line(pendulum_run, tmp_path):
    one_error_line(somarm("train", "gym:../../etc/passwd", "--out", str(tmp_path / "a")),
                   "gym:../../etc/passwd is not an environment Gymnasium can make")
    assert not (tmp_path / "a").exists()
    bad = tmp_path / "bad"
    bad.mkdir()
    for name in ("learner.npz", "config.json"):
        (bad / name).write_bytes((pendulum_run / name).read_bytes())
    config = json.loads((bad / "config.json").read_text())
    (bad / "config.json").write_text(json.dumps({**config, "task": "gym:../../etc/passwd"}))
    one_error_line(somarm("evaluate", str(bad)), str(bad / "config.json"), "is not an environment Gymnasium can make")
    from somarm import SOMQ

    with pytest.raises(ValueError, match="is not an environment Gymnasium can make"):
        SOMQ.load(bad)


def test_the_apis_size_refusal_is_the_command_lines():
    from somarm import SOMQ

    with pytest.raises(ValueError) as refused:
        SOMQ("reach2").learn(10**15)
    line = one_error_line(somarm("train", "reach2", "--steps", str(10**15), "--block", "1000"))
    size = line.removeprefix("somarm: error: ").split(", more than")[0]  # the memory free is measured apart
    assert str(refused.value).split(", more than")[0] == size and "needs about" in size


def test_learn_stopped_by_ctrl_c_says_so():
    proc = subprocess.Popen([sys.executable, "-c", (
        "import sys\nfrom somarm import SOMQ\nmodel = SOMQ('reach2')\nprint('ready', flush=True)\n"
        "model.learn(10**9)\nprint('returned', model.num_timesteps, model.interrupted, flush=True)\n")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    try:
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(2.0)  # learning now
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    word, steps, interrupted = out.split()
    assert word == "returned" and 0 < int(steps) < 10**9 and interrupted == "True"
    assert f"LearningInterrupted: SOMQ.learn was stopped by a signal after {steps} of 1000000000 steps" in err


BLOCKED = "import sys\nsys.modules['gymnasium'] = None\n"


def test_a_missing_extra_is_an_import_error_from_python_and_one_line_from_the_command_line(tmp_path):
    from somarm.extras import install_command

    done = python(BLOCKED + "from somarm import SOMQ\ntry:\n    SOMQ('Pendulum-v1')\nexcept ImportError as exc:\n"
                            "    print(type(exc).__name__, exc)\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"MissingExtra gym: tasks need gymnasium: {install_command('gym')}"
    done = python(BLOCKED + f"from somarm.cli import main\nsys.exit(main(['train', 'gym:Pendulum-v1', '--out', "
                            f"{str(tmp_path / 'run')!r}]))\n")
    one_error_line(done, f"gym: tasks need gymnasium: {install_command('gym')}")
