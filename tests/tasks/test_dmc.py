"""The suite tasks behind Gymnasium's API: same physics as dm_env, episodes end as the suite says."""

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from dm_control import suite  # noqa: E402

from somarm.tasks import dmc  # noqa: E402


def _actions(rng, env, n):
    low, high = env.action_space.low, env.action_space.high
    return low + (high - low) * rng.random((n, low.size))


@pytest.mark.parametrize("domain, task", [("reacher", "easy"), ("cartpole", "swingup"), ("point_mass", "easy")])
def test_a_suite_env_steps_the_same_physics_as_the_dm_env_path(domain, task):
    env = dmc.SuiteEnv(domain, task)
    observation, _ = env.reset(seed=7)
    # The dm_env path: the same task, its random state seeded with the draw reset(seed=7) made.
    seed = int(np.random.Generator(np.random.PCG64(7)).integers(2**32))
    reference = suite.load(domain, task, task_kwargs={"random": seed})
    step = reference.reset()
    np.testing.assert_array_equal(observation, dmc.flatten(step.observation))
    for action in _actions(np.random.default_rng(0), env, 20):
        observation, reward, terminated, truncated, _ = env.step(action)
        step = reference.step(action)
        np.testing.assert_array_equal(observation, dmc.flatten(step.observation))
        assert reward == step.reward
        assert not (terminated or truncated)


def test_the_observation_is_flattened_in_the_suites_key_order():
    env = dmc.SuiteEnv("reacher", "easy")
    observation, _ = env.reset(seed=0)
    assert [key for key, _ in env.keys] == list(env.environment.observation_spec())
    parts = env.environment._task.get_observation(env.physics)
    np.testing.assert_array_equal(observation, np.concatenate([np.ravel(v) for v in parts.values()]))
    assert env.observation_space.shape == (sum(n for _, n in env.keys),)


def test_the_time_limit_is_a_truncation_not_a_termination():
    env = dmc.SuiteEnv("pendulum", "swingup", time_limit=0.2)
    env.reset(seed=1)
    ends = [env.step(env.action_space.sample())[2:4] for _ in range(env.episode_steps)]
    assert env.episode_steps == round(0.2 / env.environment.control_timestep())
    assert ends[-1] == (False, True)
    assert all(end == (False, False) for end in ends[:-1])


def test_a_repeated_action_is_held_for_k_suite_steps_its_rewards_summed_within_the_suites_limit():
    k = 3
    held, plain = dmc.SuiteEnv("cartpole", "balance", action_repeat=k), dmc.SuiteEnv("cartpole", "balance")
    assert held.episode_steps == -(-plain.episode_steps // k)  # 1,000 suite steps: 334 decisions
    assert held.dt == k * plain.dt
    first, _ = held.reset(seed=5)
    np.testing.assert_array_equal(first, plain.reset(seed=5)[0])
    ends, rewards, rng = [], [], np.random.default_rng(1)
    for _ in range(held.episode_steps):
        action = _actions(rng, held, 1)[0]
        observation, reward, terminated, truncated, _ = held.step(action)
        steps = [plain.step(action) for _ in range(k) if not plain.environment._reset_next_step]
        np.testing.assert_array_equal(observation, steps[-1][0])
        assert reward == sum(step[1] for step in steps)
        ends.append((terminated, truncated))
        rewards.append(reward)
    # the suite's own limit ends the episode on its last, shorter hold (1,000 = 333 x 3 + 1)
    assert ends[-1] == (False, True) and all(end == (False, False) for end in ends[:-1])
    assert 0.0 < sum(rewards) <= plain.episode_steps


def test_angles_see_each_cosine_and_sine_pair_as_its_angle_of_the_same_physics():
    seen, plain = dmc.SuiteEnv("cartpole", "swingup", angles=[[1, 2]]), dmc.SuiteEnv("cartpole", "swingup")
    assert seen.observation_space.shape == (4,) and plain.observation_space.shape == (5,)
    np.testing.assert_array_equal(seen.observation_space.low, [-np.inf, -np.pi, -np.inf, -np.inf])
    np.testing.assert_array_equal(seen.observation_space.high, [np.inf, np.pi, np.inf, np.inf])
    pairs = [(seen.reset(seed=3)[0], plain.reset(seed=3)[0])]
    rng = np.random.default_rng(2)
    for _ in range(50):
        action = _actions(rng, plain, 1)[0]
        pairs.append((seen.step(action)[0], plain.step(action)[0]))
    for angle, flat in pairs:  # the cart's position, then the pole's angle, then the velocities
        np.testing.assert_array_equal(angle[[0, 2, 3]], flat[[0, 3, 4]])
        np.testing.assert_allclose([np.cos(angle[1]), np.sin(angle[1])], flat[1:3], atol=1e-12)
    upright = dmc.SuiteEnv("pendulum", "swingup", angles=[[0, 1]])
    upright.physics.named.data.qpos["hinge"] = 0.3
    upright.physics.forward()
    assert upright.observation_of(upright.environment.task.get_observation(upright.physics))[0] == pytest.approx(0.3)


def test_the_same_seed_gives_the_same_episode_and_another_seed_another():
    def episode(seed):
        env = dmc.SuiteEnv("point_mass", "easy")
        first, _ = env.reset(seed=seed)
        rest = [env.step(a)[0] for a in _actions(np.random.default_rng(3), env, 10)]
        return np.stack([first, *rest])

    np.testing.assert_array_equal(episode(4), episode(4))
    assert not np.array_equal(episode(4), episode(5))


def test_every_listed_task_opens_with_a_bounded_action_box():
    from somarm.tasks import gym_envs

    listed = dmc.names()
    assert len(listed) == len(suite.ALL_TASKS) and listed == gym_envs.suite_names()
    for name in listed:
        env = dmc.SuiteEnv(*dmc.split_name(name))
        assert np.isfinite(env.action_space.low).all() and np.isfinite(env.action_space.high).all()
    assert "dmc:point_mass-easy" in listed and "dmc:cartpole-swingup_sparse" in listed
    assert dmc.split_name("dmc:cartpole-swingup_sparse") == ("cartpole", "swingup_sparse")


@pytest.mark.parametrize("name, words", [
    ("dmc:reachr-easy", ["unknown dm_control domain 'reachr'", "reacher"]),
    ("dmc:reacher-medium", ["unknown task 'medium'", "easy, hard"]),
    ("dmc:reacher", ["unknown task ''", "easy, hard"]),
])
def test_an_unknown_domain_or_task_is_refused_in_one_line_naming_what_there_is(name, words):
    with pytest.raises(ValueError) as caught:
        dmc.split_name(name)
    assert "\n" not in str(caught.value)
    assert all(word in str(caught.value) for word in words)


@pytest.mark.parametrize("kwargs, key", [({"time_limit": 0}, "time_limit"), ({"time_limit": "long"}, "time_limit"),
                                         ({"time_limit": float("nan")}, "time_limit"), ({"random": -1}, "random"),
                                         ({"random": 1.5}, "random"), ({"action_repeat": 0}, "action_repeat"),
                                         ({"action_repeat": 2.5}, "action_repeat"),
                                         ({"action_repeat": True}, "action_repeat"), ({"angles": [[0, 0]]}, "angles"),
                                         ({"angles": [[0, 9]]}, "angles"), ({"angles": [0, 1]}, "angles"),
                                         ({"angles": [[0, 1], [1, 2]]}, "angles"), ({"angles": "0,1"}, "angles")])
def test_bad_keywords_are_refused_naming_the_key(kwargs, key):
    with pytest.raises(ValueError, match=f"^{key} takes"):
        dmc.SuiteEnv("reacher", "easy", **kwargs)


def test_an_unbounded_action_spec_is_refused(monkeypatch):
    from dm_env import specs

    real = dmc._load

    def unbounded(domain, task, kwargs):
        environment = real(domain, task, kwargs)
        environment.action_spec = lambda: specs.BoundedArray((1,), np.float64, -np.inf, np.inf)
        return environment

    monkeypatch.setattr(dmc, "_load", unbounded)
    with pytest.raises(ValueError, match="unbounded action spec"):
        dmc.SuiteEnv("pendulum", "swingup")


def test_the_suite_is_registered_with_gymnasium_under_its_own_namespace():
    import gymnasium

    env = gymnasium.make(dmc.gym_id("dmc:cartpole-balance"), time_limit=1.0)
    assert env.spec.max_episode_steps is None and env.unwrapped.episode_steps == 100
    observation, _ = env.reset(seed=2)
    direct = dmc.SuiteEnv("cartpole", "balance", time_limit=1.0)
    np.testing.assert_array_equal(observation, direct.reset(seed=2)[0])
    assert env.unwrapped.model.nq == direct.physics.model.nq and env.unwrapped.data.qpos.shape == (direct.physics.model.nq,)
