"""The SB3-style ``SOMQ`` model: save and load through a claimed run folder."""

import subprocess
import sys

import numpy as np
import pytest

from somarm import SOMQ

pytest.importorskip("gymnasium")


def _model(steps: int = 200) -> SOMQ:
    model = SOMQ("Pendulum-v1", seed=3)
    model.learn(total_timesteps=steps)
    return model


def test_a_saved_model_loads_with_the_same_greedy_actions_and_replaces_an_earlier_save(tmp_path):
    folder = tmp_path / "model"
    _model(200).save(folder)
    (folder / "notes.txt").write_text("mine")  # a user's file in the folder stays
    model = _model(400)
    assert model.save(folder) == folder
    loaded = SOMQ.load(folder)
    observations = np.random.default_rng(0).uniform(-1.0, 1.0, (16, 3))
    for observation in observations:
        assert np.array_equal(loaded.predict(observation, deterministic=True)[0],
                              model.predict(observation, deterministic=True)[0])
    assert (folder / "notes.txt").read_text() == "mine"
    assert not list(folder.glob(".somarm-new*")) and not list(folder.glob(".somarm-old*"))


def test_saving_into_a_folder_another_process_writes_is_refused_in_one_line(tmp_path):
    folder = tmp_path / "model"
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from pathlib import Path; from somarm.run.claim import claim; "
         "held = claim(Path(sys.argv[1])); print('held', flush=True); time.sleep(60)", str(folder)],
        stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        model = _model(200)
        with pytest.raises(ValueError) as caught:
            model.save(folder)
        message = str(caught.value)
        assert "\n" not in message and "being written by another somarm process" in message
        assert f"pid {holder.pid}" in message
    finally:
        holder.kill()
        holder.wait()
    model.save(folder)  # the kernel freed the lock with the process
    assert (folder / "learner.npz").exists()


def _pendulum(**kwargs) -> SOMQ:
    return SOMQ("Pendulum-v1", seed=5, env_kwargs={"max_episode_steps": 3}, **kwargs)


def test_learning_in_parts_records_the_same_whole_episodes_as_learning_at_once():
    at_once, in_parts = _pendulum(), _pendulum()
    at_once.learn(9)
    for steps in (2, 2, 5):  # episodes of 3 steps span the parts
        in_parts.learn(steps)
    whole, parts = at_once._result().episodes, in_parts._result().episodes
    assert parts.lengths.tolist() == [3, 3, 3] and parts.ends.tolist() == [3, 6, 9]
    np.testing.assert_array_equal(parts.returns, whole.returns)


def test_a_loaded_model_learns_on_from_new_starts_and_saves_curves_over_every_step(tmp_path):
    first = _pendulum().task.reset()  # the run's first start
    model = _pendulum()
    model.learn(6)
    model.save(tmp_path / "a")
    loaded = SOMQ.load(tmp_path / "a")
    assert not np.array_equal(loaded.task.reset(), first)  # not the starts it began with
    loaded = SOMQ.load(tmp_path / "a")
    loaded.learn(3)
    loaded.save(tmp_path / "b")
    with np.load(tmp_path / "b" / "curves.npz") as data:
        assert data["block_means"].shape[0] * int(data["block"]) == 9
        assert data["episode_ends"].tolist() == [3, 6, 9]


def test_a_loaded_model_whose_curves_are_damaged_predicts_but_says_why_it_cannot_learn_on(tmp_path):
    model = _pendulum()
    model.learn(6)
    model.save(tmp_path / "a")
    whole = (tmp_path / "a" / "curves.npz").read_bytes()
    for damaged in (b"not a zip", whole[: len(whole) // 2]):  # garbage, and a file cut short
        (tmp_path / "a" / "curves.npz").write_bytes(damaged)
        loaded = SOMQ.load(tmp_path / "a")
        assert loaded.predict(np.zeros(3))[0].shape == (1,)
        with pytest.raises(ValueError, match="curves.npz") as error:
            loaded.learn(3)
        assert "\n" not in str(error.value)


def test_an_environment_object_from_an_unregistered_spec_is_refused_in_one_line():
    import gymnasium
    from gymnasium.envs.classic_control import PendulumEnv

    env = gymnasium.make(gymnasium.envs.registration.EnvSpec("somarmtest/Unregistered-v0", entry_point=PendulumEnv))
    with pytest.raises(ValueError, match="not a registered Gymnasium environment") as error:
        SOMQ(env, seed=0)
    assert "\n" not in str(error.value)


def test_an_environment_object_keeps_its_time_limit_and_keywords_and_renders_nothing():
    import gymnasium

    env = gymnasium.make("Pendulum-v1", max_episode_steps=50, g=5.0, render_mode="rgb_array")
    model = SOMQ(env, seed=0)
    assert model.config.task_params == {"g": 5.0, "max_episode_steps": 50}
    assert model.task.max_episode_steps == 50


def test_wrappers_that_change_the_action_box_or_the_observation_shape_are_refused_in_one_line():
    import gymnasium
    from gymnasium.wrappers import ClipAction, FrameStackObservation

    with pytest.raises(ValueError, match=r"change its action Box from \[\[-2.0\], \[2.0\]\] to \[\[-inf\]") as error:
        SOMQ(ClipAction(gymnasium.make("Pendulum-v1")), seed=0)  # ClipAction's Box is unbounded
    assert "\n" not in str(error.value)
    with pytest.raises(ValueError, match=r"change its observation shape from \(3,\) to \(2, 3\)"):
        SOMQ(FrameStackObservation(gymnasium.make("Pendulum-v1"), 2), seed=0)


def test_predicted_actions_have_the_action_box_dtype_and_lie_inside_it():
    import gymnasium

    model = _pendulum()
    model.learn(3)
    space = gymnasium.make("Pendulum-v1").action_space
    action, _ = model.predict(np.array([1.0, 0.0, 0.0]))
    assert action.dtype == space.dtype and space.contains(action)
    batch, _ = model.predict(np.zeros((4, 3)))
    assert batch.dtype == space.dtype and batch.shape == (4, 1)
