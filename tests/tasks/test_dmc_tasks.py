"""``dmc:DOMAIN-TASK`` wherever a task name is taken: the batched task, SOMQ, the CLI and the viewer."""

import json
import subprocess

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from processes import checkout_env, one_error_line, somarm_command  # noqa: E402

from somarm import run, tasks  # noqa: E402
from somarm.tasks import dmc, gym_envs  # noqa: E402

# A short time limit keeps every episode here to 20 steps (cartpole's control step is 0.01 s).
SHORT = {"time_limit": 0.2}


def somarm(*argv, timeout=300):
    return subprocess.run(somarm_command(*argv), capture_output=True, text=True, env=checkout_env(), timeout=timeout)


def _task(name="dmc:cartpole-balance", **kwargs):
    params = tasks.record(name).complete(dict(SHORT), seed=0)
    return tasks.make(name, **params, **kwargs)


def test_a_dmc_task_is_a_gym_task_over_the_suite_keeping_its_name():
    task = _task(n_trials=2)
    assert isinstance(task, gym_envs.GymTask) and task.name == "dmc:cartpole-balance"
    assert task.params.env_id == dmc.gym_id("dmc:cartpole-balance")
    assert task.max_episode_steps == 20  # read from the suite's own time limit: no TimeLimit wrapper
    record = tasks.record("dmc:cartpole-balance")
    assert record.episodic and record.name == "dmc:cartpole-balance"
    assert gym_envs.name_of(gym_envs.env_id_of("dmc:point_mass-easy")) == "dmc:point_mass-easy"
    assert gym_envs.name_of(gym_envs.env_id_of("gym:Pendulum-v1")) == "gym:Pendulum-v1"


def test_the_time_limit_ends_an_episode_as_a_truncation_in_every_trial():
    task = _task(n_trials=2)
    task.reset()
    ends = []
    for _ in range(20):
        task.step(np.zeros((2, 1)))
        ends.append((task.terminal.copy(), task.truncated.copy()))
        task.reset()
    assert all(not t.any() and not c.any() for t, c in ends[:-1])
    assert not ends[-1][0].any() and ends[-1][1].all()


def _trajectory(task, trial_id, steps=50):
    """Trial ``trial_id``'s scaled observations under actions that depend on the step and the trial id alone,
    over ``steps`` steps (two and a half episodes of 20 steps)."""
    where = task.trial_ids.tolist().index(trial_id)
    seen = [task.reset()[where].copy()]
    for t in range(steps):
        task.step(np.sin(0.3 * t * (task.trial_ids[:, None] + 1.0)))
        seen.append(task.next_observations[where].copy())
        task.reset()
    return np.array(seen)


def test_a_trial_alone_equals_it_in_a_batch():
    batched = _trajectory(_task(n_trials=3, seed=4), 2)
    alone = _trajectory(_task(trial_ids=[2], seed=4), 2)
    np.testing.assert_array_equal(batched, alone)
    assert not np.array_equal(_trajectory(_task(n_trials=3, seed=4), 1), batched)


def test_trials_are_seeded_copies():
    task = _task(n_trials=2, seed=1)
    first = task.reset()
    assert not np.array_equal(first[0], first[1])
    again = _task(n_trials=2, seed=1).reset()
    np.testing.assert_array_equal(first, again)


def test_greedy_episodes_are_capped_by_evaluation_steps_and_counted():
    params = tasks.record("dmc:cartpole-balance").complete({"evaluation_steps": 7}, seed=0)
    task = tasks.make("dmc:cartpole-balance", **params)
    out = task.run_episodes(lambda x: np.zeros((len(x), 1)), np.array([1, 2]))
    assert out["length"].tolist() == [7, 7] and out["cut"].all()
    whole = _task().run_episodes(lambda x: np.zeros((len(x), 1)), np.array([1]))
    assert whole["length"].tolist() == [20] and not whole["cut"].any()


@pytest.mark.parametrize("given, words", [
    ({"time_limit": -1}, ["dmc:cartpole-balance with keyword time_limit=-1", "time_limit takes"]),
    ({"random": "x"}, ["keyword random='x'", "random takes"]),
    ({"colour": 1}, ["dmc:cartpole-balance does not take these parameters"]),
])
def test_a_keyword_the_suite_task_cannot_take_is_refused_at_set_up_in_one_line(given, words):
    with pytest.raises(ValueError) as caught:
        tasks.record("dmc:cartpole-balance").params_from(given)
    message = str(caught.value)
    assert "\n" not in message and all(w in message for w in words), message


def test_the_suites_keywords_reach_the_task():
    params = tasks.record("dmc:pendulum-swingup").complete({"time_limit": 0.5}, seed=0)
    task = tasks.make("dmc:pendulum-swingup", **params)
    assert task.max_episode_steps == 25  # pendulum's control step is 0.02 s


def test_somq_takes_a_dmc_name_and_a_suite_environment_and_keeps_the_name(tmp_path):
    import gymnasium

    from somarm import SOMQ

    model = SOMQ("dmc:point_mass-easy", seed=0, env_kwargs=SHORT, n_trials=1)
    model.learn(60)
    model.save(tmp_path / "m")
    config = json.loads((tmp_path / "m" / "config.json").read_text())
    assert config["task"] == "dmc:point_mass-easy" and config["task_params"]["time_limit"] == 0.2
    loaded = SOMQ.load(tmp_path / "m")
    assert loaded.config.task == "dmc:point_mass-easy"
    env = gymnasium.make(dmc.gym_id("dmc:point_mass-easy"), time_limit=0.2)
    given = SOMQ(env, seed=0, n_trials=1)
    assert given.config.task == "dmc:point_mass-easy" and given.config.task_params.get("time_limit") == 0.2
    assert "domain" not in given.config.task_params


def test_train_and_evaluate_a_dmc_task_from_the_cli(tmp_path):
    out = tmp_path / "run"
    done = somarm("train", "dmc:cartpole-balance", "--steps", "200", "--trials", "1", "--task-set", "time_limit=0.2", "--out", str(out),
                  "--no-figures", "--no-progress")
    assert done.returncode == 0, done.stderr
    config = json.loads((out / "config.json").read_text())
    summary = json.loads((out / "summary.json").read_text())
    assert config["task"] == "dmc:cartpole-balance" and config["task_params"]["time_limit"] == 0.2
    assert len(config["task_params"]["observation_low"]) == 5  # the scaling estimate is kept
    assert 0.0 <= summary["greedy_mean_return"] <= 20.0  # 20 steps of rewards in [0, 1]
    done = somarm("evaluate", str(out))
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("task, needles", [
    ("dmc:reachr-easy", ["unknown dm_control domain 'reachr'", "reacher"]),
    ("dmc:reacher-medium", ["unknown task 'medium' of dm_control's reacher", "easy, hard"]),
])
def test_an_unknown_domain_or_task_is_one_line_from_the_cli(tmp_path, task, needles):
    one_error_line(somarm("train", task, "--out", str(tmp_path / "a")), *needles)
    assert not (tmp_path / "a").exists()


def test_a_bad_task_set_is_one_line_with_nothing_written(tmp_path):
    one_error_line(somarm("train", "dmc:reacher-easy", "--task-set", "time_limit=-2", "--out", str(tmp_path / "a")),
                   "time_limit=-2", "time_limit takes")
    assert not (tmp_path / "a").exists()


def test_somarm_tasks_lists_the_suites_tasks():
    done = somarm("tasks")
    listed = {line.split()[0] for line in done.stdout.splitlines() if line.strip()}
    assert done.returncode == 0 and set(dmc.names()) <= listed


def test_the_viewer_draws_the_suites_model(tmp_path):
    from somarm.viewer import gym_view

    page = tmp_path / "view.html"
    gym_view.view("dmc:reacher-easy", episodes=1, task_set={"time_limit": 0.4}, html=page, log=lambda line: None)
    text = page.read_text()
    assert page.stat().st_size > 10_000 and "dmc:reacher-easy" in text


def test_the_viewer_follows_a_trained_run(tmp_path):
    from somarm.viewer import gym_view

    result = run.train(run.RunConfig(task="dmc:reacher-easy", n_steps=100, n_trials=1, seed=0, task_params=SHORT),
                       progress=False)
    run.write(result, tmp_path / "run", figures=False)
    page = tmp_path / "view.html"
    gym_view.view("dmc:reacher-easy", run=tmp_path / "run", episodes=1, html=page, log=lambda line: None)
    assert page.exists()


def test_the_report_tasks_train_with_their_own_presets_and_others_with_the_generic_one():
    from somarm.learners import presets

    for name, (preset, steps) in gym_envs.DMC_BENCHMARKS.items():
        record = tasks.record(name)
        assert (record.preset, record.n_steps) == (preset, steps) and preset in presets.PRESETS
        width = tasks.make(name, **record.complete(dict(SHORT), seed=0)).action_low.size
        assert presets.get(preset).action_shape == ((11,) if width == 1 else (3, 3))
    assert tasks.record("dmc:acrobot-swingup").preset == "gym"
