"""Periodic action dimensions (``periodic_actions``): exact fixtures, defaults, batching, files and errors."""

import json

import numpy as np
import pytest

from somarm.learners import presets
from somarm.learners.somq import SOMQConfig, SOMQLearner
from somarm.run import RunConfig, make

PI = np.pi
#: One angle (a circle when periodic) and one plain dimension.
BOX = dict(observation_low=[0.0], observation_high=[3.0], action_low=[-PI, 0.0], action_high=[PI, 1.0])
ANGLE = [True, False]


def _one_unit(periodic_actions=True, **changes):
    """One input unit, two action units: unit 0 (greedy) at angle 3.0, near the box's +pi edge."""
    settings = dict(input_shape=(1,), action_shape=(2,), alpha=0.5, lambda_s=0.0, lambda_a=1.0, n_s=0.0,
                    n_a=0.0, p=0.0, epsilon=0.5, periodic_actions=periodic_actions)
    learner = SOMQLearner(SOMQConfig(**{**settings, **changes}), action_periodic=ANGLE, **BOX)
    learner.input_weights[0] = [[1.0]]
    learner.action_weights[0] = [[3.0, 0.9], [0.0, 0.1]]
    learner.q[0] = [[-0.5, -1.0]]
    learner._streams.next = lambda: np.array([[0.9, 0.0, 0.0, 1.0, 1.0]])  # greedy; noise +1, +1
    return learner


def test_a_perturbation_past_pi_wraps_round_and_the_unit_follows_it_across_the_edge():
    learner = _one_unit()
    action = learner.act([[1.0]])
    # 3.0 + 0.5 = 3.5 rad is the pose at 3.5 - 2 pi; the plain dimension is still clipped (0.9 + 0.5 -> 1).
    np.testing.assert_allclose(action, [[3.5 - 2 * PI, 1.0]], rtol=0, atol=1e-15)
    learner.learn([0.0])  # better than Q = -0.5: lambda_A = 1 moves unit 0 onto the action, across the edge
    np.testing.assert_allclose(learner.action_weights[0], [[3.5 - 2 * PI, 1.0], [0.0, 0.1]], rtol=0, atol=1e-12)
    box = _one_unit(periodic_actions=False)
    np.testing.assert_array_equal(box.act([[1.0]]), [[PI, 1.0]])  # the paper's box clips at pi
    box.learn([0.0])
    np.testing.assert_allclose(box.action_weights[0], [[PI, 1.0], [0.0, 0.1]], rtol=0, atol=1e-12)


def test_the_action_map_moves_along_the_shorter_arc():
    learner = _one_unit(lambda_a=0.5)
    learner.action_weights[0, 0, 0] = -3.0
    learner._streams.next = lambda: np.array([[0.9, 0.0, 0.0, 0.0, 1.0]])  # noise -1 on the angle
    action = learner.act([[1.0]])
    np.testing.assert_allclose(action[0, 0], -3.5 + 2 * PI, rtol=0, atol=1e-15)  # -3.5 rad wrapped to +2.78
    learner.learn([0.0])
    # Half of the short way (0.5 rad clockwise, past -pi), not half of the long way (5.78 rad anticlockwise).
    np.testing.assert_allclose(learner.action_weights[0, 0, 0], -3.25 + 2 * PI, rtol=0, atol=1e-12)


def _two_sides(periodic_actions=True, **changes):
    """Four input units at 0..3 whose greedy action units 0, 1, 2, 3 sit at 3.0, -3.0, -2.0, -1.0 rad."""
    settings = dict(input_shape=(4,), action_shape=(4,), alpha=0.5, lambda_s=0.0, lambda_a=0.5, n_s=0.0,
                    n_a=1.0, p=0.0, epsilon=0.0, response="interpolated", periodic_actions=periodic_actions)
    learner = SOMQLearner(SOMQConfig(**{**settings, **changes}), action_periodic=ANGLE, **BOX)
    learner.input_weights[0] = [[0.0], [1.0], [2.0], [3.0]]
    learner.action_weights[0] = [[3.0, 0.5], [-3.0, 0.5], [-2.0, 0.5], [-1.0, 0.5]]
    learner.q[0] = -1.0 + 1.0 * np.eye(4)
    return learner


def test_the_interpolated_response_blends_angles_across_the_edge_the_short_way():
    # x = 0.25: units 0 (d 0.25) and 1 (d 0.75), cut at unit 2 (d 1.75); 3.0 and -3.0 rad are 0.283 rad apart.
    v0, v1 = 1 / 0.25 - 1 / 1.75, 1 / 0.75 - 1 / 1.75
    b1 = v1 / (v0 + v1)
    response = _two_sides().predict([[0.25]])[0, 0]
    np.testing.assert_allclose(response, 3.0 + b1 * (2 * PI - 6.0), rtol=0, atol=1e-12)
    # In the box the same blend goes the long way, through 0 (a pose 3 rad away from both).
    np.testing.assert_allclose(_two_sides(False).predict([[0.25]])[0, 0], (1 - b1) * 3.0 - b1 * 3.0, atol=1e-12)


def test_a_blended_step_shifts_the_neighbourhood_the_short_way_and_wraps_it():
    learner = _two_sides(epsilon=0.4)
    learner._streams.next = lambda: np.array([[0.9, 0.0, 0.0, 1.0, 0.5]])  # greedy; noise +1 on the angle
    action = learner.act([[0.0]])  # on unit 0: the response is u_0 = 3.0, perturbed by +0.4 -> wraps
    np.testing.assert_allclose(action, [[3.4 - 2 * PI, 0.5]], rtol=0, atol=1e-15)
    learner.learn([0.5])
    # Units 0 and 1 (psi 1 and 0.5 at N_A = 1) shift by lambda_A psi x 0.4 rad: unit 0 past pi, wrapped.
    np.testing.assert_allclose(learner.action_weights[0, :, 0], [3.2 - 2 * PI, -2.9, -2.0, -1.0], rtol=0,
                               atol=1e-12)


def test_the_setting_is_off_by_default_and_a_declaration_alone_changes_nothing():
    assert SOMQConfig().periodic_actions is False
    for name in ("table1", "table2", "table5", "table5+", "obstacle"):
        assert presets.get(name).periodic_actions is False
    assert presets.get("table1+").periodic_actions is True and presets.get("table2+").periodic_actions is True
    config = SOMQConfig(input_shape=(3,), action_shape=(5,), epsilon=0.8)
    declared = SOMQLearner(config, n_trials=2, seed=4, action_periodic=ANGLE, **BOX)
    plain = SOMQLearner(config, n_trials=2, seed=4, **BOX)
    rng = np.random.default_rng(0)
    clipped = 0
    for _ in range(200):
        x = rng.uniform(0, 3, (2, 1))
        actions = declared.act(x)
        np.testing.assert_array_equal(actions, plain.act(x))
        clipped += int((np.abs(actions[:, 0]) == PI).sum())
        rewards = -np.abs(actions[:, 0] - x[:, 0])
        declared.learn(rewards)
        plain.learn(rewards)
    np.testing.assert_array_equal(declared.action_weights, plain.action_weights)
    np.testing.assert_array_equal(declared.q, plain.q)
    assert clipped > 0  # some actions met the box's edge: clipped, not wrapped


def test_a_run_passes_the_tasks_periodic_angles_to_the_learner():
    _, learner = make(RunConfig(task="reach2", preset="table1+", n_trials=1, n_steps=100).resolved())
    assert learner.action_periodic.tolist() == [True, True] and learner._wrap.all()
    _, learner = make(RunConfig(task="reach2", preset="table1", n_trials=1, n_steps=100).resolved())
    assert learner.action_periodic.all() and not learner._wrap.any()  # the paper's box
    _, learner = make(RunConfig(task="throw_distance", preset="table1+", n_trials=1, n_steps=100).resolved())
    assert not learner._wrap.any()  # throws have no angle that wraps


def _config(response):
    return SOMQConfig(input_shape=(4,), action_shape=(6,), epsilon=1.5, periodic_actions=True, response=response)


@pytest.mark.parametrize("response", ["winner", "interpolated"])
def test_trial_alone_equals_trial_in_batch_and_a_saved_learner_keeps_its_circles(tmp_path, response):
    batch = SOMQLearner(_config(response), n_trials=3, seed=2, action_periodic=ANGLE, **BOX)
    alone = SOMQLearner(_config(response), n_trials=1, seed=2, trial_ids=[1], action_periodic=ANGLE, **BOX)
    rng = np.random.default_rng(3)
    crossed = 0
    for step in range(80):
        x = rng.uniform(0, 3, (3, 1))
        a = batch.act(x)
        np.testing.assert_array_equal(alone.act(x[1:2]), a[1:2])
        if step == 40:  # save and reload between act and learn
            alone.save(tmp_path / "alone.npz")
            alone = SOMQLearner.load(tmp_path / "alone.npz")
            assert alone.config.periodic_actions and alone.action_periodic.tolist() == ANGLE
        before = batch.action_weights[..., 0].copy()
        r = -np.abs(np.sin(a[:, 0] - x[:, 0]))
        batch.learn(r)
        alone.learn(r[1:2])
        crossed += int((np.abs(batch.action_weights[..., 0] - before) > PI).sum())
    np.testing.assert_array_equal(alone.action_weights[0], batch.action_weights[1])
    np.testing.assert_array_equal(alone.q[0], batch.q[1])
    assert crossed > 0  # some unit went round the edge of the box


def _rewrite_meta(path, out, change):
    with np.load(path, allow_pickle=False) as data:
        arrays = {key: data[key] for key in data.files}
    meta = json.loads(str(arrays["meta"]))
    change(meta)
    arrays["meta"] = np.array(json.dumps(meta))
    np.savez(out, **arrays)
    return out


def test_a_file_saved_before_periodic_dimensions_loads_with_none_and_a_bad_one_is_named(tmp_path):
    learner = SOMQLearner(_config("winner"), action_periodic=ANGLE, **BOX)
    learner.save(tmp_path / "new.npz")
    old = SOMQLearner.load(_rewrite_meta(tmp_path / "new.npz", tmp_path / "old.npz", lambda m: m.pop("periodic")))
    assert old.action_periodic.tolist() == [False, False] and not old._wrap.any()
    bad = _rewrite_meta(tmp_path / "new.npz", tmp_path / "bad.npz", lambda m: m.update(periodic=[1, 0, 1]))
    with pytest.raises(ValueError, match=r"bad\.npz is a damaged learner file: action_periodic must be 2 "
                                         r"booleans") as err:
        SOMQLearner.load(bad)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("make_learner, match", [
    (lambda: SOMQLearner(SOMQConfig(), action_periodic=[True], **BOX),
     r"^action_periodic must be 2 booleans \(one per action dimension\), got \[True\]$"),
    (lambda: SOMQLearner(SOMQConfig(), action_periodic=[1, 0], **BOX), "^action_periodic must be 2 booleans"),
    (lambda: SOMQConfig(periodic_actions="yes"), "^periodic_actions must be True or False, got 'yes'$"),
    (lambda: SOMQConfig().with_overrides({"periodic_actions": "maybe"}),
     "^periodic_actions=maybe: periodic_actions must be true or false, got 'maybe'$"),
])
def test_bad_periodic_settings_give_one_line(make_learner, match):
    with pytest.raises(ValueError, match=match):
        make_learner()


def test_the_setting_is_set_like_any_other():
    config = SOMQConfig().with_overrides({"periodic_actions": "true"})
    assert config.periodic_actions is True
    assert SOMQConfig.from_dict(config.to_dict()) == config


def test_the_action_map_figure_does_not_draw_links_across_the_seam():
    from somarm import plots

    weights = np.array([[3.0, 0.0], [3.1, 0.1], [-3.1, 0.2], [-3.0, 0.3]])  # units 1-2 meet across +-pi
    low, high = np.full(2, -np.pi), np.full(2, np.pi)
    for periodic, gaps in ((np.array([True, False]), 1), (None, 0), (np.array([False, False]), 0)):
        fig, ax = plots.plt.subplots()
        plots.draw_action_map(ax, weights, low, high, periodic=periodic)
        x = ax.lines[0].get_xdata()
        assert np.isnan(x).sum() == gaps
        if gaps:
            assert np.isnan(x[2]) and len(x) == 5  # the break sits between units 1 and 2
        plots.plt.close(fig)
