"""The Gymnasium environments and the SB3 VecEnv: checks, the float32 boundary, reward parity, seeding."""

import warnings

import numpy as np
import pytest

from somarm import tasks
from somarm.peers.compare import peers_missing

if peers_missing():  # the peers extra (with CI=true, conftest turns this skip into a failure)
    pytest.skip(peers_missing(), allow_module_level=True)

import gymnasium  # noqa: E402
from gymnasium.utils.env_checker import check_env as gymnasium_check_env  # noqa: E402
from stable_baselines3.common.env_checker import check_env as sb3_check_env  # noqa: E402

from somarm.peers.gym import OneStepEnv, env_id, to_task_actions  # noqa: E402
from somarm.peers.vec_env import BatchedVecEnv  # noqa: E402

IDS = {"reach2": "somarm/Reach2-v0", "reach20": "somarm/Reach20-v0", "four_goals": "somarm/FourGoals-v0",
       "throw": "somarm/Throw-v0", "throw_distance": "somarm/ThrowDistance-v0",
       "throw_wind": "somarm/ThrowWind-v0", "throw_friction": "somarm/ThrowFriction-v0",
       "throw_mass": "somarm/ThrowMass-v0"}


def test_every_one_step_task_is_registered_under_its_id():
    from somarm.peers.gym import one_step_tasks

    assert set(IDS) == set(one_step_tasks()) == {n for n in tasks.names() if not tasks.record(n).episodic}
    assert "somarm/Reach2Obstacle-v0" not in gymnasium.registry
    for name, gym_id in IDS.items():
        assert env_id(name) == gym_id
        env = gymnasium.make(gym_id)
        assert env.unwrapped.task_name == name
        assert env.observation_space.dtype == np.float32 and env.action_space.dtype == np.float32
        assert (env.action_space.low == -1).all() and (env.action_space.high == 1).all()


@pytest.mark.parametrize("name", list(IDS))
def test_gymnasium_and_sb3_check_env_pass_without_warnings(name):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gymnasium_check_env(gymnasium.make(IDS[name]).unwrapped)
        sb3_check_env(OneStepEnv(name))


@pytest.mark.parametrize("name", list(IDS))
def test_rewards_equal_the_batched_tasks_for_the_same_observation_and_action(name):
    env = gymnasium.make(IDS[name])
    task = tasks.make(name, seed=7)
    rng = np.random.default_rng(0)
    for episode in range(5):
        observation, _ = env.reset(seed=7) if episode == 0 else env.reset()
        expected = task.reset()[0]
        assert np.array_equal(observation, expected.astype(np.float32))
        action = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        _, reward, terminated, truncated, _ = env.step(action)
        assert terminated and not truncated
        assert reward == task.step(to_task_actions(action[None], task.action_low, task.action_high))[0]


def test_reset_with_a_seed_is_deterministic_and_seeds_differ():
    env = gymnasium.make("somarm/ThrowWind-v0")
    first = [env.reset(seed=3)[0]] + [env.reset()[0] for _ in range(3)]
    again = [env.reset(seed=3)[0]] + [env.reset()[0] for _ in range(3)]
    other = env.reset(seed=4)[0]
    assert all(np.array_equal(a, b) for a, b in zip(first, again, strict=True))
    assert not np.array_equal(first[0], other)


@pytest.mark.parametrize("name", ["reach2", "reach20", "throw_mass"])
def test_the_float32_corners_of_the_action_space_map_inside_the_tasks_bounds(name):
    # float32(pi) is above float64 pi: a float32 box copied from the task's bounds would hand the
    # task values it rejects. The [-1, 1] space maps every float32 value inside the bounds.
    assert np.float64(np.float32(np.pi)) > np.pi
    env = gymnasium.make(IDS[name])
    dim = env.action_space.shape[0]
    low, high = env.unwrapped.task.action_low, env.unwrapped.task.action_high
    edges = np.array([-1.0, np.nextafter(np.float32(-1), np.float32(0)), np.nextafter(np.float32(1), np.float32(0)),
                      1.0], dtype=np.float32)
    for edge in edges:
        mapped = to_task_actions(np.full(dim, edge, dtype=np.float32), low, high)
        assert (mapped >= low).all() and (mapped <= high).all()
        env.reset(seed=0)
        assert np.isfinite(env.step(np.full(dim, edge, dtype=np.float32))[1])
    assert np.array_equal(to_task_actions(np.float32([-1.0] * dim), low, high), low)
    assert np.array_equal(to_task_actions(np.float32([1.0] * dim), low, high), high)
    observation, _ = env.reset(seed=1)
    assert env.observation_space.contains(observation)


def test_actions_outside_the_space_or_a_step_without_reset_are_clear_errors():
    env = OneStepEnv("reach2")
    with pytest.raises(ValueError, match="reset"):
        env.step(np.zeros(2, np.float32))
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"\[-1, 1\]"):
        env.step(np.array([1.5, 0.0], np.float32))
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0.0], np.float32))
    with pytest.raises(ValueError, match="unknown task"):
        OneStepEnv("reach3")
    with pytest.raises(ValueError, match="reach2_obstacle has multi-step episodes"):
        OneStepEnv("reach2_obstacle")


def test_the_vec_env_steps_all_trials_in_one_batch_with_the_tasks_rewards():
    venv = BatchedVecEnv("throw_distance", 4, seed=2)
    task = tasks.make("throw_distance", n_trials=4, seed=2)
    observations = venv.reset()
    assert observations.shape == (4, 1) and observations.dtype == np.float32
    expected = task.reset()
    actions = np.random.default_rng(1).uniform(-1, 1, (4, 2)).astype(np.float32)
    next_observations, rewards, dones, infos = venv.step(actions)
    assert dones.all() and rewards.dtype == np.float32
    assert np.array_equal(rewards, task.step(to_task_actions(actions, task.action_low, task.action_high))
                          .astype(np.float32))
    assert np.array_equal(np.stack([i["terminal_observation"] for i in infos]), expected.astype(np.float32))
    assert np.array_equal(next_observations, task.reset().astype(np.float32))
    venv.seed(5)
    assert np.array_equal(venv.reset(), tasks.make("throw_distance", n_trials=4, seed=5).reset().astype(np.float32))


def test_td3_learns_a_few_steps_through_the_vec_env():
    from stable_baselines3 import TD3

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = TD3("MlpPolicy", BatchedVecEnv("reach2", 8), seed=0, learning_starts=16, batch_size=16,
                    device="cpu")
        model.learn(64)
    assert model.num_timesteps == 64 and model.replay_buffer.size() == 8


def test_the_adapters_benchmark_prints_every_path(capsys):
    from somarm.cli import main

    assert main(["bench", "adapters", "--envs", "4", "--steps", "5", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    for label in ("task batched", "BatchedVecEnv", "task single", "gymnasium env", "SyncVectorEnv", "overhead"):
        assert label in out
