import json

import numpy as np
import pytest

from somarm import learners, run
from somarm.run import RunConfig


def _tiny(**kwargs):
    base = dict(task="reach2", n_trials=2, n_steps=400, seed=3, block=100)
    return RunConfig(**{**base, **kwargs})


def test_same_seed_same_numbers_different_seed_differs():
    a = run.train(_tiny(), progress=False)
    b = run.train(_tiny(), progress=False)
    c = run.train(_tiny(seed=4), progress=False)
    np.testing.assert_array_equal(a.block_means, b.block_means)
    np.testing.assert_array_equal(a.learner.q, b.learner.q)
    assert not np.array_equal(a.block_means, c.block_means)
    assert a.block_means.shape == (4, 2) and a.steps.tolist() == [100, 200, 300, 400]


def test_trial_alone_equals_trial_in_batch():
    batch = run.train(_tiny(n_trials=3), progress=False)
    # Trial 0 alone has trial index 0: the first column of the batch.
    alone = run.train(_tiny(n_trials=1), progress=False)
    np.testing.assert_array_equal(batch.block_means[:, 0], alone.block_means[:, 0])


def test_replay_one_trial_of_a_batch_alone():
    batch = run.train(_tiny(n_trials=3), progress=False)
    alone = run.train(_tiny(n_trials=1, trial_ids=[2]), progress=False)
    np.testing.assert_array_equal(batch.block_means[:, 2], alone.block_means[:, 0])
    np.testing.assert_array_equal(batch.learner.q[2], alone.learner.q[0])


def test_group_in_lockstep_equals_separate_runs():
    configs = [
        _tiny(task="throw", n_steps=300),
        _tiny(task="throw", n_steps=300, n_trials=1, overrides={"neighbourhood_q": False}),
    ]
    group = run.train_group(configs, progress=False)
    for config, result in zip(configs, group, strict=True):
        alone = run.train(config, progress=False)
        np.testing.assert_array_equal(result.block_means, alone.block_means)
        np.testing.assert_array_equal(result.learner.action_weights, alone.learner.action_weights)
    with pytest.raises(ValueError, match="shares backend, steps and block"):
        run.train_group([_tiny(), _tiny(n_steps=500)], progress=False)


def test_group_of_different_throw_tasks_equals_separate_runs():
    # Fig. 25's lockstep: several throw tasks share one batch of flights per step (and a task twice).
    configs = [
        _tiny(task="throw_distance", preset="table7a", n_steps=300, task_params={"punish_low": True}),
        _tiny(task="throw_mass", n_steps=300, n_trials=3, task_params={"punish_low": True}),
        _tiny(task="throw_distance", preset="table7a", n_steps=300, task_params={"punish_low": True},
              overrides={"neighbourhood_q": False}),
        _tiny(task="throw_wind", n_steps=300),
        _tiny(task="throw_wind", n_steps=300, seed=8),  # another seed: independent trials, same step
    ]
    alone = [run.train(config, progress=False) for config in configs]
    group = run.RunGroup(configs)
    assert len(group.tasks) == 4  # throw_distance (one task for both of its configs), throw_mass, throw_wind twice
    for config, result, single in zip(configs, group.train(progress=False), alone, strict=True):
        np.testing.assert_array_equal(result.block_means, single.block_means)
        np.testing.assert_array_equal(result.block_sq_means, single.block_sq_means)
        np.testing.assert_array_equal(result.learner.q, single.learner.q)
        assert result.task.name == config.task
    with pytest.raises(ValueError, match="on_step needs a group on one task and seed"):
        run.train_group(configs, progress=False, on_step=lambda *args: None)


def test_split_shares_the_trials_between_processes_evenly_most_first():
    assert run.share_lanes([100, 100, 100, 100], 2) == [0, 1, 0, 1]
    assert run.share_lanes([20, 20, 20], 2) == [0, 1, 0]
    assert run.share_lanes([1, 50, 30, 30], 2) == [0, 0, 1, 1]  # 50 + 1 | 30 + 30
    assert run.share_lanes([5, 5], 4) == [0, 1]  # no more lanes than configs
    assert run.share_lanes([5, 5, 5], 1) == [0, 0, 0]


def test_interrupt_leaves_valid_partial_run(tmp_path):
    def stop_at_250(step, observations, actions, rewards):
        if step == 250:
            raise KeyboardInterrupt

    result = run.train(_tiny(), progress=False, on_step=stop_at_250)
    assert result.interrupted and result.steps_done == 250
    assert result.block_means.shape == (2, 2)
    run.write(result, tmp_path, figures=False)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["steps"] == 250 and summary["seed"] == 3
    config, learner = run.load(tmp_path)
    assert config == result.config and learner.t == 250
    assert not list(tmp_path.glob("*.tmp"))


def test_run_folder_round_trip_and_figures(tmp_path):
    result = run.train(_tiny(), progress=False)
    run.write(result, tmp_path)
    names = {p.name for p in tmp_path.iterdir()}
    assert {
        "config.json",
        "curves.npz",
        "learner.npz",
        "summary.json",
        "learning_curve.png",
        "input_map.png",
        "action_map.png",
    } <= names
    curves = np.load(tmp_path / "curves.npz")
    np.testing.assert_array_equal(curves["block_means"], result.block_means)
    assert int(curves["seed"]) == 3
    config, learner = run.load(tmp_path)
    np.testing.assert_array_equal(learner.q, result.learner.q)


@pytest.mark.parametrize("kind", learners.LEARNERS)
def test_every_learner_kind_passes_the_memory_check_trains_and_reloads(tmp_path, kind):
    config = RunConfig(task="reach2", learner=kind, n_trials=2, n_steps=200, block=50, seed=1).resolved()
    run.check_memory_needs([config])  # each kind's own estimate, through the registry
    result = run.train(config, progress=False)
    run.write(result, tmp_path)
    _, learner = run.load(tmp_path)
    for name in learner.learned_arrays:
        np.testing.assert_array_equal(getattr(learner, name), getattr(result.learner, name))
    assert ((tmp_path / "input_map.png").exists()) == learner.has_maps


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"task": "nope"}, "unknown task"),
        ({"learner": "dqn"}, "unknown learner"),
        ({"n_trials": 0}, "trials"),
        ({"n_steps": 0}, "steps"),
        ({"seed": -1}, "seed"),
    ],
)
def test_bad_run_settings_are_one_clear_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        _tiny(**kwargs).resolved()


def test_parse_assignments():
    assert run.parse_assignments(["a=1", " b = x "], "--set") == {"a": "1", "b": "x"}
    with pytest.raises(ValueError, match="KEY=VALUE"):
        run.parse_assignments(["novalue"], "--set")


def test_load_run_names_missing_file(tmp_path):
    with pytest.raises(ValueError, match="config.json is missing"):
        run.load(tmp_path)


def test_every_run_setting_is_a_train_option():
    import argparse
    import dataclasses

    from somarm.run.config import add_options, from_options

    parser = argparse.ArgumentParser()
    add_options(parser)
    args = parser.parse_args(["reach2", "--steps", "300", "--trial-ids", "4", "7", "--set", "alpha=0.5"])
    config = from_options(args)
    options = {f.name for f in dataclasses.fields(RunConfig) if f.metadata["flag"]}
    assert options == {f.name for f in dataclasses.fields(RunConfig)} - {"learner_config"}
    assert options <= set(vars(args))
    assert (config.n_steps, config.n_trials, config.trial_ids, config.overrides) == (300, 2, [4, 7], {"alpha": 0.5})
    assert config.learner_config.alpha.scale == 0.5  # the typed learner config the run builds from
    assert config.preset == "table1" and config.block == 100  # the task's record and the field default
