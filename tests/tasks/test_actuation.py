"""Actuated arms: the servos reach their targets, a short settle leaves them short, batches equal trials alone."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from somarm import tasks
from somarm.tasks import actuation, arms, assets, reach

# Targets spread over the whole joint box, including both limits' neighbourhoods.
_RNG = np.random.default_rng(11)


def _targets(n_links: int, n: int) -> np.ndarray:
    return _RNG.uniform(-np.pi, np.pi, (n, n_links))


@pytest.mark.parametrize("name, n_links", [("reach2", 2), ("reach20", 20)])
def test_actuated_reach_ends_within_1e_3_of_the_setpoint_after_a_second(name, n_links):
    targets = _targets(n_links, 64)
    actuated = tasks.make(name, n_trials=64, dynamics="actuated", settle_time=1.0)
    reached = actuated.reached_angles(targets)
    gap = np.linalg.norm(arms.fingertips(reached, n_links) - arms.fingertips(targets, n_links), axis=-1)
    assert gap.max() < 1e-3
    # The reward is read where the arm is: equal to the kinematic reward within the same gap.
    goals = tasks.make(name, n_trials=64).sample_observations(np.random.default_rng(0), 64)
    kinematic = tasks.make(name, n_trials=64).evaluate(goals, targets)
    np.testing.assert_allclose(actuated.evaluate(goals, targets), kinematic, atol=1e-3)


def test_at_the_default_settle_time_the_servos_have_not_arrived_yet_every_goal_is_reachable():
    task = tasks.make("reach2", n_trials=64, dynamics="actuated")
    assert task.params.settle_time == 0.2 and task.settle_steps == 20
    targets = _targets(2, 400)
    reached = task.reached_angles(targets)
    gap = np.linalg.norm(arms.fingertips(reached, 2) - arms.fingertips(targets, 2), axis=-1)
    assert gap.mean() > 0.06 and gap.max() > 0.12  # the physics' answer, not the target's
    # Each joint covers most of its way from the start pose (all zeros): the servos lag, they do not wander.
    share = reached / targets
    assert 0.85 < np.median(share) < 0.97 and (share > 0).all()
    # Every goal of the circle is still in reach with the elbow up (theta2 > 0), by targets 0.3 rad or more
    # inside the joint limits: some target puts the fingertip within 1 cm.
    grid = np.linspace(-np.pi + 0.3, np.pi - 0.3, 221)
    inside = np.stack(np.meshgrid(grid, grid, indexing="ij"), -1).reshape(-1, 2)
    inside = inside[inside[:, 1] > 0]
    tips = arms.fingertips(task.reached_angles(inside), 2)
    goals = reach.goal_circle_points(task.params, np.linspace(0, 2 * np.pi, 72, endpoint=False))
    assert np.sqrt(((goals[:, None] - tips[None]) ** 2).sum(-1)).min(axis=1).max() < 0.01


def test_actuated_joint_angles_are_not_periodic_the_kinematic_ones_are():
    # A servo target of -pi turns the joint the other way from one of pi: not one pose when driven.
    assert tasks.make("reach2").action_periodic.all()
    assert not tasks.make("reach2", dynamics="actuated").action_periodic.any()
    start = np.zeros((2, 2))
    edges = np.array([[np.pi, 0.0], [-np.pi, 0.0]])
    reached, _ = actuation.Servos("arm2").run(start, start, edges, 15)
    assert reached[0, 0] > 2.0 and reached[1, 0] < -2.0


def test_a_short_settle_time_visibly_leaves_the_arm_short():
    targets = _targets(2, 64)
    short = tasks.make("reach2", n_trials=64, dynamics="actuated", settle_time=0.25).reached_angles(targets)
    gap = np.linalg.norm(arms.fingertips(short, 2) - arms.fingertips(targets, 2), axis=-1)
    assert gap.max() > 0.02  # a fingertip more than 2 cm short of where the setpoint puts it
    # ... and the servo is still moving towards the target: more time, smaller gap.
    longer = tasks.make("reach2", n_trials=64, dynamics="actuated", settle_time=0.5).reached_angles(targets)
    assert np.abs(longer - targets).sum() < np.abs(short - targets).sum()


def test_the_path_starts_at_rest_and_ends_where_the_reward_is_read():
    task = tasks.make("reach2", dynamics="actuated", settle_time=0.3)
    targets = np.array([[1.0, -2.0], [-0.5, 0.7]])
    path = task.reached_angles(targets, path=True)
    assert path.shape == (2, 30, 2)
    np.testing.assert_array_equal(path[:, -1], task.reached_angles(targets))
    # One timestep after the start pose (all zeros) every joint has begun to turn towards its target.
    assert (np.sign(path[:, 0]) == np.sign(targets)).all()
    assert (np.abs(path[:, 0]) < 0.1 * np.abs(targets)).all()


def test_trial_i_alone_equals_trial_i_in_the_batch_on_any_thread_count():
    batch = tasks.make("reach2", n_trials=6, seed=4, dynamics="actuated")
    batch.reset()
    actions = _targets(2, 6)
    together = batch.step(actions)
    for i in (0, 5):
        alone = tasks.make("reach2", n_trials=1, seed=4, trial_ids=[i], dynamics="actuated")
        alone.reset()
        assert alone.step(actions[i:i + 1])[0] == together[i]
    start = np.zeros((600, 2))
    many = _targets(2, 600)
    one, _ = actuation.Servos("arm2", n_threads=1).run(start, start, many, 40)
    two, _ = actuation.Servos("arm2", n_threads=2).run(start, start, many, 40)
    np.testing.assert_array_equal(one, two)


def test_dm_env_actuated_reward_equals_the_batched_one():
    batched = tasks.make("reach2", seed=2, dynamics="actuated")
    env = tasks.load("reach2", seed=2, dynamics="actuated")
    rng = np.random.default_rng(5)
    for _ in range(3):
        goal = batched.reset()
        action = rng.uniform(-np.pi, np.pi, (1, 2))
        expected = batched.step(action)[0]
        env.reset()
        step = env.step(action[0])
        assert step.last() and step.reward == pytest.approx(expected, abs=1e-12)
        np.testing.assert_array_equal(env.physics.goal(), goal[0])


def test_kinematic_default_is_unchanged_by_the_actuators():
    # The models gained servos, but the kinematic tasks never integrate: the reward is the setpoint's.
    task = tasks.make("reach2", n_trials=5, seed=1)
    assert task.params.dynamics == "kinematic" and not task.actuated
    goals, targets = task.reset(), _targets(2, 5)
    expected = -np.linalg.norm(arms.fingertips(targets, 2) - goals, axis=-1)
    np.testing.assert_array_equal(task.step(targets), expected)


@pytest.mark.parametrize("name", ["arm2", "arm20"])
def test_both_arms_carry_the_documented_servos(name):
    model = mujoco.MjModel.from_xml_path(str(assets.model_path(name)))
    assert model.nu == model.njnt
    np.testing.assert_array_equal(model.actuator_gainprm[:, 0], assets.ACTUATION["kp"])
    np.testing.assert_array_equal(model.dof_damping, assets.ACTUATION["damping"])
    np.testing.assert_array_equal(model.dof_armature, assets.ACTUATION["armature"])
    assert model.opt.timestep == arms.TIMESTEP
    for i in range(model.nu):
        assert model.actuator(i).name == model.joint(int(model.actuator_trnid[i, 0])).name


@pytest.mark.parametrize("params, match", [
    ({"dynamics": "torque"}, "dynamics must be one of kinematic, actuated"),
    ({"dynamics": "actuated", "settle_time": 0}, r"settle_time must be in \[0.01, 100\]"),
    ({"settle_time": "long"}, "settle_time must be a finite number"),
])
def test_bad_dynamics_parameters_are_rejected_in_one_line(params, match):
    with pytest.raises(ValueError, match=match) as info:
        tasks.make("reach2", **params)
    assert "\n" not in str(info.value)


def test_actuated_needs_the_mujoco_backend():
    with pytest.raises(ValueError, match="needs the mujoco backend"):
        tasks.make("reach2", dynamics="actuated", backend="analytic")
    assert reach.DYNAMICS == ("kinematic", "actuated")


def test_target_scale_lets_a_servo_bring_its_joint_near_pi_in_the_settle_time():
    # In 0.2 s a servo covers about 0.92 of its way: a target of pi leaves the joint near 2.9; the wider box
    # takes a target beyond pi and brings the joint to pi, while the joints' own limits stay at +-pi.
    narrow = tasks.make("reach2", n_trials=1, dynamics="actuated")
    wide = tasks.make("reach2", n_trials=1, dynamics="actuated", target_scale=1.15)
    assert narrow.action_high[0] == pytest.approx(np.pi) and wide.action_high[0] == pytest.approx(1.15 * np.pi)
    beyond = np.array([[1.1 * np.pi, 0.0]])
    assert narrow.reached_angles(beyond)[0, 0] < 0.95 * np.pi  # clamped to a target of pi
    assert 0.99 * np.pi < wide.reached_angles(beyond)[0, 0] < 1.05 * np.pi
    inside = np.array([[1.0, -2.0]])
    np.testing.assert_allclose(wide.reached_angles(inside), narrow.reached_angles(inside))
    with pytest.raises(ValueError, match="target_scale"):
        tasks.make("reach2", target_scale=1.1)
    with pytest.raises(ValueError, match="target_scale"):
        tasks.make("reach2", dynamics="actuated", target_scale=2.5)
