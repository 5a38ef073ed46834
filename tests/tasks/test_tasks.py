"""Invariants over every registered task (as dm_control's suite test), and the two interfaces agreeing."""

from __future__ import annotations

import numpy as np
import pytest

from somarm import tasks
from somarm.protocols import BatchedTask

#: The one-step tasks (the paper's); reach2_obstacle's whole episodes are tested in test_obstacle.py.
NAMES = [name for name in tasks.names() if name != "reach2_obstacle"]


def _actions(task, rng, n):
    return rng.uniform(task.action_low, task.action_high, (n, task.action_low.size))


def test_registry_lists_the_tasks_of_the_paper():
    assert tasks.names() == [*NAMES, "reach2_obstacle"]
    assert NAMES == ["reach2", "reach20", "four_goals", "throw", "throw_distance", "throw_wind",
                     "throw_friction", "throw_mass"]
    for name in tasks.names():
        line = tasks.record(name).summary
        assert line and "\n" not in line


@pytest.mark.parametrize("name", NAMES)
def test_batched_task_invariants(name):
    task = tasks.make(name, n_trials=7, seed=3)
    assert isinstance(task, BatchedTask)
    assert task.name == name and task.n_trials == 7
    assert (task.observation_low < task.observation_high).all()
    assert (task.action_low < task.action_high).all()
    rng = np.random.default_rng(0)
    for _ in range(3):
        observations = task.reset()
        assert observations.shape == (7, task.observation_low.size)
        assert np.isfinite(observations).all()
        assert ((observations >= task.observation_low) & (observations <= task.observation_high)).all()
        rewards = task.step(_actions(task, rng, 7))
        assert rewards.shape == (7,) and np.isfinite(rewards).all() and (rewards <= 0).all()
    assert task.t == 3
    fresh = task.sample_observations(np.random.default_rng(1), 500)
    assert fresh.shape == (500, task.observation_low.size)
    assert ((fresh >= task.observation_low) & (fresh <= task.observation_high)).all()


@pytest.mark.parametrize("name", tasks.names())
def test_periodic_action_dimensions_are_the_joint_angles_over_one_turn(name):
    task = tasks.make(name, n_trials=1)
    periodic = task.action_periodic
    assert periodic.dtype == np.bool_ and periodic.shape == task.action_low.shape
    assert periodic.all() == (name in ("reach2", "reach20", "four_goals")) and (periodic.all() or not periodic.any())
    span = task.action_high - task.action_low
    np.testing.assert_allclose(span[periodic], 2 * np.pi)  # a periodic dimension is one whole turn


@pytest.mark.parametrize("name", NAMES)
def test_same_seed_same_observations_different_seed_different(name):
    def first_three(seed, **kw):
        task = tasks.make(name, n_trials=4, seed=seed, **kw)
        return np.stack([task.reset() for _ in range(3)])

    a, b, c = first_three(5), first_three(5), first_three(6)
    np.testing.assert_array_equal(a, b)
    if name != "throw":  # a single state: every seed observes X = 4
        assert not np.array_equal(a, c)
    alone = first_three(5, trial_ids=[2, 3, 0, 1])
    np.testing.assert_array_equal(alone, a[:, [2, 3, 0, 1]])


@pytest.mark.parametrize("name", NAMES)
def test_evaluate_is_pure_and_matches_step(name):
    task = tasks.make(name, n_trials=3, seed=2)
    twin = tasks.make(name, n_trials=3, seed=2)
    rng = np.random.default_rng(4)
    actions = _actions(task, rng, 3)
    observations = task.reset()
    evaluated = task.evaluate(observations, actions)
    assert task.t == 0
    np.testing.assert_array_equal(twin.reset(), observations)
    np.testing.assert_array_equal(task.step(actions), evaluated)
    # Broadcasting: (n_trials, n_obs, obs_dim) with (n_trials, n_obs, action_dim).
    many = task.sample_observations(np.random.default_rng(5), 4)
    grid = np.broadcast_to(many, (3, 4, many.shape[1]))
    acts = _actions(task, rng, 12).reshape(3, 4, -1)
    assert task.evaluate(grid, acts).shape == (3, 4)


@pytest.mark.parametrize("name", NAMES)
def test_mujoco_and_analytic_backends_agree(name):
    rng = np.random.default_rng(6)
    mj = tasks.make(name, n_trials=1, seed=0)
    an = tasks.make(name, n_trials=1, seed=0, backend="analytic")
    observations = mj.sample_observations(rng, 400)
    actions = _actions(mj, rng, 400)
    tolerance = 1e-9 if name in ("reach2", "reach20", "four_goals") else 1e-6
    np.testing.assert_allclose(mj.evaluate(observations, actions), an.evaluate(observations, actions),
                               rtol=0, atol=tolerance)


@pytest.mark.parametrize("name", NAMES)
def test_dm_env_and_batched_interfaces_give_the_same_rewards(name):
    env = tasks.load(name, seed=11)
    batched = tasks.make(name, n_trials=2, seed=11)
    rng = np.random.default_rng(7)
    spec = env.action_spec()
    np.testing.assert_array_equal(spec.minimum, batched.action_low)
    np.testing.assert_array_equal(spec.maximum, batched.action_high)
    obs_spec = next(iter(env.observation_spec().values()))
    for _ in range(4):
        first = env.reset()
        assert first.first()
        observation = next(iter(first.observation.values()))
        obs_spec.validate(observation)  # finite and inside the stated bounds
        expected = batched.reset()[0]
        np.testing.assert_array_equal(observation, expected)
        action = _actions(batched, rng, 1)[0]
        last = env.step(action)
        assert last.last() and last.discount == 0.0
        assert last.reward == pytest.approx(float(batched.evaluate(expected, action)), abs=1e-12)
        batched.step(np.stack([action, action]))


@pytest.mark.parametrize("name, kind, part", [
    ("reach2", "site_xpos", "fingertip"), ("reach20", "site_xpos", "fingertip"),
    ("four_goals", "mocap_pos", "goal"), ("throw", "xpos", "projectile"), ("throw_mass", "mocap_pos", "target"),
])
def test_dm_env_physics_has_the_named_parts(name, kind, part):
    env = tasks.load(name)  # keep the environment alive while its physics is indexed
    assert getattr(env.physics.named.data, kind)[part].shape == (3,)


def _ik2(points):
    """Elbow-down inverse kinematics of the 0.4 + 0.4 arm (a known optimum)."""
    d = points - np.array([0.5, 0.0])
    cos2 = (np.sum(d * d, axis=-1) - 0.32) / 0.32
    theta2 = np.arccos(np.clip(cos2, -1, 1))
    theta1 = np.arctan2(d[..., 1], d[..., 0]) - np.arctan2(0.4 * np.sin(theta2), 0.4 + 0.4 * np.cos(theta2))
    return np.stack([theta1, theta2], axis=-1)


def test_reach2_optimum_earns_zero_and_the_goals_lie_on_the_circle():
    task = tasks.make("reach2", n_trials=200, seed=1)
    goals = task.reset()
    np.testing.assert_allclose(np.hypot(goals[:, 0] - 0.5, goals[:, 1] - 0.5), 0.25, atol=1e-15)
    np.testing.assert_allclose(task.step(_ik2(goals)), 0.0, atol=1e-12)


def test_four_goals_switch_at_the_configured_step():
    from somarm.tasks.four_goals import GOALS_AFTER, GOALS_BEFORE, quadrants

    task = tasks.make("four_goals", n_trials=50, seed=0, switch_step=2)
    for t in range(4):
        observations = task.reset()
        goals = np.asarray(GOALS_BEFORE)[quadrants(observations)]
        moved = np.asarray(GOALS_AFTER)[quadrants(observations)]
        rewards = task.step(_ik2(goals))  # reach the first goals exactly
        if t < 2:
            np.testing.assert_allclose(rewards, 0.0, atol=1e-12)
        else:
            np.testing.assert_allclose(rewards, -np.linalg.norm(goals - moved, axis=-1), atol=1e-12)
    assert task.t == 4
    task.set_step(0)
    obs = np.array([[0.1, 0.9], [0.9, 0.9], [0.1, 0.1], [0.9, 0.1]])
    np.testing.assert_array_equal(task.goals_for(obs), np.asarray(GOALS_BEFORE))


# -- bad input: one clear error each -----------------------------------------------------------
def test_unknown_task_lists_the_names():
    with pytest.raises(ValueError, match="reach2, reach20, four_goals, throw"):
        tasks.make("reach3")
    with pytest.raises(ValueError, match="tasks: reach2"):
        tasks.load("nope")
    with pytest.raises(ValueError, match="tasks: reach2"):
        tasks.record("nope")


@pytest.mark.parametrize("name, params, match", [
    ("reach2", {"speed": 1}, "its parameters: centre_x, centre_y, radius"),
    ("throw_wind", {"W": -1.0}, "its parameters: M, G, Fr, punish_low, tolerance"),
    ("reach2", {"radius": 0.6}, "inside the unit square"),
    ("reach2", {"centre_y": 0.75, "radius": 0.25}, "within the arm's reach"),
    ("four_goals", {"switch_step": -1}, "switch_step must be a whole number >= 0"),
    ("four_goals", {"goals_after": [[0.1, 0.1]]}, "four finite"),
    ("four_goals", {"goals_before": [[0.0, 1.0]] * 4}, "within the arm's reach"),
    ("throw", {"Fr": -0.1}, "Fr must be >= 0"),
    ("throw", {"M": 0}, "M must be > 0"),
    ("throw", {"X": 20.0}, "out of reach"),
    ("throw_mass", {"punish_low": "yes"}, "punish_low must be true or false"),
    ("throw", {"G": float("nan")}, "G must be a finite number"),
])
def test_bad_parameters_are_rejected(name, params, match):
    with pytest.raises(ValueError, match=match):
        tasks.make(name, **params)


def test_unknown_backend_is_rejected():
    with pytest.raises(ValueError, match="backends: mujoco, analytic"):
        tasks.make("reach2", backend="numpy")


@pytest.mark.parametrize("name", ["reach2", "throw"])
@pytest.mark.parametrize("bad, match", [
    (np.zeros((3, 3)), r"shape \(\.\.\., 2\)"),
    (np.zeros((2, 2)), r"shape \(3, 2\)"),
    (np.full((3, 2), np.nan), "finite"),
    (np.full((3, 2), np.inf), "finite"),
    (np.full((3, 2), 4.0), "inside"),
])
def test_bad_actions_are_rejected_with_one_line(name, bad, match):
    task = tasks.make(name, n_trials=3)
    task.reset()
    with pytest.raises(ValueError, match=match) as error:
        task.step(bad)
    assert "\n" not in str(error.value)


def test_step_before_reset_and_bad_env_action():
    task = tasks.make("reach20")
    with pytest.raises(ValueError, match="reset"):
        task.step(np.zeros((1, 20)))
    env = tasks.load("throw")
    env.reset()
    with pytest.raises(ValueError, match=r"inside \[\(0, 0\), \(1, 1\)\]"):
        env.step(np.array([0.5, 1.5]))
    env.reset()
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        env.step(np.zeros((1, 2)))


def test_set_threads_rejects_zero_and_keeps_results():
    from somarm.tasks import flight

    with pytest.raises(ValueError, match="n must be a whole number >= 1"):
        tasks.set_threads(0)
    task = tasks.make("throw")
    rng = np.random.default_rng(9)
    actions = rng.random((3000, 2))
    two = task.evaluate(np.array([4.0]), actions)
    try:
        tasks.set_threads(1)
        assert flight.THREADS == 1
        np.testing.assert_array_equal(task.evaluate(np.array([4.0]), actions), two)
    finally:
        tasks.set_threads(2)


@pytest.mark.parametrize("name", tasks.names())
def test_every_task_record_agrees_with_its_task(name):
    from somarm.learners import presets
    from somarm.tasks import assets

    record = tasks.record(name)
    task = tasks.make(name)
    assert record.name == name == task.name
    assert record.model in assets.MODEL_NAMES and record.preset in presets.PRESETS and record.n_steps > 0
    assert len(record.observation_labels) == task.observation_dim
    assert len(record.action_labels) == 2 and record.view in ("goals", "sweep", "fan")
    assert set(record.settable) <= set(record.fields())
    # The task declares what the record says, and every member of its protocol.
    from somarm.protocols import BatchedTask, EpisodicTask

    assert task.episodic == record.episodic and isinstance(task, BatchedTask)
    assert isinstance(task, EpisodicTask) == task.episodic


@pytest.mark.parametrize("name", tasks.names())
def test_every_task_record_names_the_backends_its_task_takes(name):
    backends = tasks.record(name).backends
    assert backends and set(backends) <= set(tasks.BACKENDS)
    for backend in tasks.BACKENDS:
        if backend in backends:
            assert tasks.make(name, backend=backend).backend == backend
            assert tasks.check_backend(name, backend) == backend
        else:
            wanted = " or ".join(backends)
            with pytest.raises(ValueError, match=f"needs the {wanted} backend"):
                tasks.make(name, backend=backend)
            with pytest.raises(ValueError, match=f"^{name} needs the {wanted} backend, got backend '{backend}'$"):
                tasks.check_backend(name, backend)


def test_task_parameter_text_is_read_once_into_values():
    params = tasks.parse_params("four_goals", {"switch_step": "500", "goals_before": "[[0.3, 0.7]]"})
    assert params == {"switch_step": 500, "goals_before": [[0.3, 0.7]]}
    assert tasks.parse_params("reach2", {"dynamics": "actuated", "radius": "0.2"}) == {
        "dynamics": "actuated", "radius": 0.2}
    assert tasks.parse_params("throw", {"punish_low": "true"}) == {"punish_low": True}
    for value in (0.2, True, 500, "actuated", [[0.3, 0.7]]):
        assert tasks.parse_params("reach2", {"radius": tasks.format_param(value)})["radius"] == value


@pytest.mark.parametrize("name, params, match", [
    ("reach2", {"radius": "0.2"}, r"^task parameter radius of reach2 takes a number written with the digits 0-9, "
                                  r"got the text '0.2'$"),
    ("reach2", {"nope": 1.0}, "^unknown parameter\\(s\\) nope for task reach2; its parameters: centre_x"),
    ("reach2", {"radius": 0.9}, "must lie inside the unit square"),
    ("throw", {"punish_low": "yes"}, "punish_low"),
])
def test_typed_task_parameters_are_checked_in_one_line(name, params, match):
    with pytest.raises(ValueError, match=match) as info:
        tasks.check_params(name, params)
    assert "\n" not in str(info.value)


def test_unknown_task_parameter_text_is_refused_before_it_is_read():
    with pytest.raises(ValueError, match="unknown parameter\\(s\\) nope for task throw"):
        tasks.parse_params("throw", {"nope": "1"})
    assert tasks.check_params("reach2", {"dynamics": "actuated", "radius": 0.2}) == {
        "dynamics": "actuated", "radius": 0.2}
