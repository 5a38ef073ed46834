"""reach2_obstacle: real contacts, goals behind the wall, whole episodes through both interfaces, and a trap
for distance-greed."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from somarm import run as runs
from somarm import tasks
from somarm.protocols import BatchedTask, EpisodicTask
from somarm.tasks import assets, obstacle, obstacle_search


def _link_points(angles: np.ndarray) -> np.ndarray:
    """Points along both links' centre lines, ``(40, 2)``, for joint angles ``(2,)``."""
    elbow = np.array([0.5, 0.0]) + 0.4 * np.array([np.cos(angles[0]), np.sin(angles[0])])
    tip = elbow + 0.4 * np.array([np.cos(angles.sum()), np.sin(angles.sum())])
    share = np.linspace(0.0, 1.0, 20)[:, None]
    return np.vstack([np.array([0.5, 0.0]) + share * (elbow - [0.5, 0.0]), elbow + share * (tip - elbow)])


def _random_actions(task, rng):
    return rng.uniform(task.action_low, task.action_high, (task.n_trials, 2))


def test_the_batched_task_conforms_and_its_episodes_end_at_different_steps():
    task = tasks.make("reach2_obstacle", n_trials=6, seed=3, step_limit=5)
    assert isinstance(task, BatchedTask) and isinstance(task, EpisodicTask) and task.episodic and task.actuated
    rng = np.random.default_rng(0)
    lengths, steps = [], np.zeros(6, dtype=int)
    for _ in range(12):
        observations = task.reset()
        assert observations.shape == (6, 4) and np.isfinite(observations).all()
        rewards = task.step(_random_actions(task, rng))
        assert rewards.shape == (6,) and (rewards <= -1.0).all()
        steps += 1
        over = task.terminal | task.truncated
        assert not (task.terminal & task.truncated).any()
        lengths += steps[over].tolist()
        steps[over] = 0
    assert max(lengths) == 5  # truncated at the step limit
    assert len(lengths) >= 12  # every trial restarted at least twice


def test_a_finished_trial_restarts_alone_and_trial_i_is_the_same_alone_or_batched():
    batch = tasks.make("reach2_obstacle", n_trials=4, seed=7, step_limit=3)
    alone = tasks.make("reach2_obstacle", n_trials=1, seed=7, trial_ids=[2], step_limit=3)
    rng = np.random.default_rng(1)
    restarts = 0
    for _ in range(8):
        over = batch.terminal | batch.truncated
        observations = batch.reset()
        if batch.t:  # running episodes continue where they were; finished ones start afresh
            np.testing.assert_array_equal(observations[~over], batch.next_observations[~over])
            assert not np.isclose(observations[over], batch.next_observations[over]).all(axis=1).any()
            restarts += int(over.sum())
        np.testing.assert_array_equal(alone.reset()[0], observations[2])
        actions = _random_actions(batch, rng)
        rewards = batch.step(actions)
        assert alone.step(actions[2:3])[0] == rewards[2]
        np.testing.assert_array_equal(alone.next_observations[0], batch.next_observations[2])
        assert alone.truncated[0] == batch.truncated[2] and alone.terminal[0] == batch.terminal[2]
    assert restarts >= 8


def test_the_links_never_pass_through_the_wall_in_random_episodes():
    task = tasks.make("reach2_obstacle", step_limit=25)
    rng = np.random.default_rng(2)
    # Random episodes biased towards the wall (theta1 turning towards it from either side), so that the
    # links push into it.
    starts = task.sample_observations(rng, 24)
    episodes = task.run_episodes(lambda o: np.column_stack([np.where(o[:, 0] < np.pi / 2, 0.4, -0.4),
                                                            rng.uniform(-0.4, 0.4, len(o))]),
                                 starts, paths=True)
    model = mujoco.MjModel.from_xml_path(str(assets.model_path("arm2_obstacle")))
    data = mujoco.MjData(model)
    wall = model.geom("wall").id
    deepest, touching = 0.0, 0
    for angles in episodes["path"].reshape(-1, 2)[::3]:
        data.qpos[:] = angles
        mujoco.mj_forward(model, data)
        for k in range(data.ncon):
            assert wall in (data.contact[k].geom1, data.contact[k].geom2)
            touching += 1
            deepest = max(deepest, -data.contact[k].dist)
        # No point of a link's centre line is ever inside the wall's middle (a link passing through
        # would cross it): the wall is x in [0.48, 0.52], y in [0.52, 0.80]; its middle 10 mm here.
        points = _link_points(angles)
        inside = (np.abs(points[:, 0] - 0.5) < 0.005) & (points[:, 1] > 0.53) & (points[:, 1] < 0.79)
        assert not inside.any(), angles
    assert touching > 50  # the links did press against the wall ...
    # ... and sank at most 25 mm of overlap (link radius 12 mm + wall half-width 20 mm = 32 mm to the middle).
    assert deepest < 0.025


def test_starts_lie_on_both_sides_clear_of_the_wall_and_every_goal_behind_it():
    task = tasks.make("reach2_obstacle")
    episodes = task.sample_observations(np.random.default_rng(4), 400)
    tips = obstacle.fingertips(episodes[:, :2])
    left = tips[:, 0] < obstacle.WALL_X
    assert 0.4 < left.mean() < 0.6  # both sides, even odds
    assert not obstacle.touches_wall(episodes[:, :2]).any()
    # The goal lies on the other side of the wall, inside the goal region (its mirror image on the left).
    assert ((episodes[:, 2] < obstacle.WALL_X) != left).all()
    right_goals = np.where(left[:, None], episodes[:, 2:], obstacle.mirror_point(episodes[:, 2:]))
    x0, x1, y0, y1 = obstacle.GOAL_REGION
    assert ((right_goals[:, 0] >= x0) & (right_goals[:, 0] <= x1)).all()
    assert ((right_goals[:, 1] >= y0) & (right_goals[:, 1] <= y1)).all()
    # Starts spread over the rest pose's neighbourhood (or its mirror image), not one pose.
    right_poses = np.where(left[:, None], obstacle.mirror_pose(episodes[:, :2]), episodes[:, :2])
    assert np.abs(right_poses - obstacle.REST_POSE).max() > 0.8 * task.params.start_spread


def test_the_task_is_mirror_symmetric_about_the_wall():
    task = tasks.make("reach2_obstacle")
    start = np.array([[0.7, 1.2, 0.3, 0.66]])
    mirrored = np.concatenate([obstacle.mirror_pose(start[:, :2]), obstacle.mirror_point(start[:, 2:])], axis=1)
    moves = iter([np.array([[0.4, 0.4]]), np.array([[0.3, -0.2]])] * 10)
    flipped = iter([np.array([[-0.4, -0.4]]), np.array([[-0.3, 0.2]])] * 10)
    one = task.run_episodes(lambda o: next(moves), start, paths=True)
    other = task.run_episodes(lambda o: next(flipped), mirrored, paths=True)
    np.testing.assert_allclose(obstacle.mirror_pose(one["path"][0]), other["path"][0], atol=1e-6)
    np.testing.assert_allclose(one["returns"], other["returns"], atol=1e-6)


def test_distance_greed_rarely_reaches_a_goal_that_the_search_reaches_in_a_few_steps():
    task = tasks.make("reach2_obstacle")
    starts = task.sample_observations(np.random.default_rng(0), 16)
    greedy = task.run_episodes(obstacle_search.distance_greedy_policy(task), starts)
    assert greedy["success"].mean() <= 2 / 16  # a straight move rarely gets there: the wall is in the way
    found = obstacle_search.shortest_paths(task, starts)
    assert found["found"].all() and (found["length"] <= 6).all()
    # The lengths are the replay's: every plan reaches its goal through run_episodes in that many steps.
    replay = obstacle_search.replay(task, starts, found["plans"])
    np.testing.assert_array_equal(replay["length"], found["length"])
    assert replay["success"].all()
    assert all(len(plan) == n for plan, n in zip(found["plans"], found["length"], strict=True))


def test_no_move_sequence_of_the_grid_is_shorter_than_the_search_where_it_finds_3_steps():
    # Exhaustive over two steps of the 7 x 7 grid (2,401 sequences, no state merged): none reaches the goal
    # from a start where the search's shortest path takes 3 steps.
    task = tasks.make("reach2_obstacle")
    starts = task.sample_observations(np.random.default_rng(1), 12)
    found = obstacle_search.shortest_paths(task, starts)
    three = starts[found["length"] == 3][:2]
    assert len(three) >= 1
    grid = obstacle_search.moves(task.params.max_step)
    for start in three:
        first, second = np.repeat(grid, len(grid), axis=0), np.tile(grid, (len(grid), 1))
        q, v = task.advance(np.repeat(start[None, :2], len(first), axis=0), np.zeros((len(first), 2)), first)
        d1 = task.distances(q, start[2:])
        q, _ = task.advance(q, v, second)
        d2 = task.distances(q, start[2:])
        assert min(d1.min(), d2.min()) >= task.params.tolerance


def test_dm_env_episode_equals_trial_0_of_the_batch():
    env = tasks.load("reach2_obstacle", seed=5, step_limit=6)
    batch = tasks.make("reach2_obstacle", seed=5, step_limit=6)
    rng = np.random.default_rng(3)
    for _ in range(2):  # two episodes: the second start comes from the same stream
        first = env.reset()
        start = batch.reset()[0]
        np.testing.assert_array_equal(first.observation["angles"], start[:2])
        np.testing.assert_array_equal(first.observation["goal"], start[2:])
        np.testing.assert_array_equal(env.physics.goal(), start[2:])  # the marker moved to the goal
        while True:
            action = _random_actions(batch, rng)
            reward = batch.step(action)[0]
            step = env.step(action[0])
            assert step.reward == pytest.approx(reward, abs=1e-9)
            np.testing.assert_allclose(step.observation["angles"], batch.next_observations[0, :2], atol=1e-9)
            if step.last():
                assert step.discount == (0.0 if batch.terminal[0] else 1.0)
                assert batch.terminal[0] or batch.truncated[0]
                break
            assert not (batch.terminal[0] or batch.truncated[0])
            batch.reset()
        batch.reset()


def test_training_hands_the_learner_next_observations_and_terminal_flags():
    # A small input map, so that 60 steps visit a unit twice and a next state's value is not the initial 0.
    config = runs.RunConfig(task="reach2_obstacle", preset="obstacle", n_steps=60, n_trials=2, block=20,
                            task_params={"step_limit": 10}, overrides={"input_shape": (3, 3)})
    discounted = runs.train(config, progress=False)
    myopic = runs.train(dataclasses.replace(config, overrides={"input_shape": (3, 3), "gamma": 0.0}),
                        progress=False)
    # Same observations, actions and rewards up to the first learning step; with gamma > 0 the
    # Q-values also hold the next state's value, so they differ.
    assert discounted.learner.t == myopic.learner.t == 60
    assert not np.array_equal(discounted.learner.q, myopic.learner.q)
    assert discounted.block_means.shape == (3, 2) and (discounted.block_means <= -1).all()


@pytest.mark.parametrize("params, match", [
    ({"max_step": 0}, r"max_step must be in \[0.01, 1\]"),
    ({"start_spread": 0.5}, r"start_spread must be in \[0, 0.3\]"),
    ({"step_limit": 2.5}, r"step_limit must be a whole number in \[1, 1000\]"),
    ({"tolerance": "near"}, "tolerance must be a finite number"),
    ({"wall": 1}, "unknown parameter"),
])
def test_bad_obstacle_parameters_are_rejected_in_one_line(params, match):
    with pytest.raises(ValueError, match=match) as info:
        tasks.make("reach2_obstacle", **params)
    assert "\n" not in str(info.value)


def test_bad_backend_and_early_step_are_rejected():
    with pytest.raises(ValueError, match="needs the mujoco backend"):
        tasks.make("reach2_obstacle", backend="analytic")
    task = tasks.make("reach2_obstacle")
    with pytest.raises(ValueError, match="call reset"):
        task.step(np.zeros((1, 2)))
    task.reset()
    with pytest.raises(ValueError, match="must lie inside"):
        task.step(np.full((1, 2), 0.5))


def test_the_joint_field_is_zero_at_the_goal_and_walled_off_where_a_link_overlaps_the_wall():
    goal = np.array([0.32, 0.64])
    field = obstacle_search.joint_field(goal, 0.08)
    # A pose whose fingertip is at the goal (elbow out to the left: the mirror of one right of the wall).
    at_goal = obstacle.mirror_pose(np.array([0.6565, 1.2635]))
    assert np.linalg.norm(obstacle.fingertips(at_goal) - goal) < 0.04 and field.radians(at_goal) == 0.0
    inside = np.array([np.pi / 2, 0.0])  # the arm straight up, through the wall
    assert obstacle.touches_wall(inside) and np.isinf(field.radians(inside))
    # From the rest pose right of the wall the way round is longer than the straight line in joint space to
    # the nearest pose at the goal: that line passes through the wall.
    centres = np.linspace(-np.pi, np.pi, 160, endpoint=False) + np.pi / 160
    poses = np.stack(np.meshgrid(centres, centres, indexing="ij"), -1)
    at_the_goal = (np.linalg.norm(obstacle.fingertips(poses) - goal, axis=-1) < 0.08) & ~obstacle.touches_wall(poses)
    straight = np.abs(poses[at_the_goal] - obstacle.REST_POSE).max(axis=-1).min()
    assert 1.5 * straight < field.radians(obstacle.REST_POSE) < np.inf
