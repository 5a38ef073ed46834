"""The fixed-action tabular learner: reference behaviour, batching, save/load, the size limit."""

import numpy as np
import pytest

from somarm import learners, tasks
from somarm.learners.tabular import TabularConfig, TabularQ

BOX = dict(observation_low=[0.0], observation_high=[1.0], action_low=[0.0], action_high=[1.0])


def _tiny(config=None, **kwargs):
    return learners.make("tabular", config or TabularConfig(observation_bins=4, action_bins=8), **BOX, **kwargs)


def test_cells_and_action_grid_are_the_stated_ones():
    learner = _tiny()
    assert np.allclose(learner.actions[:, 0], (np.arange(8) + 0.5) / 8)
    cells = learner.cells(np.array([[0.0], [0.2499], [0.25], [1.0]]).reshape(1, 4, 1))
    assert cells.tolist() == [[0, 0, 1, 3]]


def test_q_is_the_sample_mean_of_each_pair_as_a_plain_loop_computes_it():
    learner = _tiny(n_trials=3, seed=4)
    rng = np.random.default_rng(0)
    sums, counts = {}, {}
    for _ in range(300):
        x = rng.random((3, 1))
        a = learner.act(x)
        r = -np.abs(a[:, 0] - x[:, 0]) + rng.normal(0, 0.1, 3)
        learner.learn(r)
        for trial in range(3):
            key = (trial, int(min(3, x[trial, 0] * 4)), int(np.argmin(np.abs(learner.actions[:, 0] - a[trial, 0]))))
            sums[key] = sums.get(key, 0.0) + r[trial]
            counts[key] = counts.get(key, 0) + 1
    for (trial, cell, action), total in sums.items():
        assert learner.q[trial, cell, action] == pytest.approx(total / counts[(trial, cell, action)], abs=1e-12)
    assert learner.counts.sum() == 900


def test_on_a_task_with_a_known_optimum_the_greedy_action_is_the_best_grid_action():
    # Reward -|a - x| with x uniform in a cell: the best grid action is the centre nearest the
    # cell's middle, here (2k+1)/8 for cell k (two action centres per cell, both equally near:
    # their expected rewards differ by sampling noise only, so either is optimal).
    config = TabularConfig(observation_bins=4, action_bins=8, epsilon=1.0)
    learner = _tiny(config, seed=1)
    rng = np.random.default_rng(1)
    for _ in range(4000):  # about 125 rewards per pair: the means differ by >= 0.06, their SE ~0.006
        x = rng.random((1, 1))
        learner.learn(-np.abs(learner.act(x)[:, 0] - x[:, 0]))
    middles = np.array([[[0.125], [0.375], [0.625], [0.875]]])
    greedy = learner.predict(middles)[0, :, 0]
    best = {0: (1 / 16, 3 / 16), 1: (5 / 16, 7 / 16), 2: (9 / 16, 11 / 16), 3: (13 / 16, 15 / 16)}
    for cell, value in enumerate(greedy):
        assert min(abs(value - b) for b in best[cell]) < 1e-12
    expected_error = np.mean([abs(g - x) for g, x in zip(greedy, middles[0, :, 0], strict=True)])
    assert expected_error <= 1 / 16 + 1e-12


def test_untried_actions_are_never_greedy():
    learner = _tiny(TabularConfig(observation_bins=1, action_bins=4, epsilon=1.0))
    learner.act(np.array([[0.5]]))
    tried = learner._choices[0]
    learner.learn(np.array([-5.0]))  # a bad reward, but the only estimate there is
    assert learner.predict(np.array([[0.1]]))[0, 0] == learner.actions[tried, 0]


def test_trial_i_is_the_same_alone_or_in_a_batch():
    # MuJoCo, not the closed forms: numpy's vectorised sin/cos may round a batch differently.
    task = tasks.make("reach2", n_trials=3, seed=2)
    alone_task = tasks.make("reach2", seed=2, trial_ids=[2])
    kwargs = dict(observation_low=task.observation_low, observation_high=task.observation_high,
                  action_low=task.action_low, action_high=task.action_high, seed=2)
    batch = learners.make("tabular", n_trials=3, **kwargs)
    alone = learners.make("tabular", n_trials=1, trial_ids=[2], **kwargs)
    for _ in range(500):
        batch.learn(task.step(batch.act(task.reset())))
        alone.learn(alone_task.step(alone.act(alone_task.reset())))
    assert np.array_equal(batch.q[2], alone.q[0]) and np.array_equal(batch.counts[2], alone.counts[0])


def test_save_and_load_continue_exactly(tmp_path):
    learner = _tiny(TabularConfig(observation_bins=3, action_bins=5, alpha=0.3), n_trials=2, seed=5)
    rng = np.random.default_rng(3)
    for _ in range(50):
        learner.learn(-rng.random(2) - learner.act(rng.random((2, 1)))[:, 0])
    learner.act(np.array([[0.2], [0.9]]))  # saved between act and learn
    learner.save(tmp_path / "tab.npz")
    copy = learners.load(tmp_path / "tab.npz")
    assert isinstance(copy, TabularQ) and copy.config == learner.config
    for one in (learner, copy):
        one.learn(np.array([-0.5, -0.1]))
        for _ in range(20):
            one.learn(-one.act(np.array([[0.4], [0.6]]))[:, 0])
    assert np.array_equal(copy.q, learner.q) and copy.t == learner.t


def test_an_action_grid_too_large_is_a_clear_error():
    task = tasks.make("reach20", backend="analytic")
    with pytest.raises(ValueError, match=r"20 dimensions .* table entries; at most 1e\+07"):
        learners.make("tabular", observation_low=task.observation_low, observation_high=task.observation_high,
                     action_low=task.action_low, action_high=task.action_high)


@pytest.mark.parametrize("bad", [dict(observation_bins=0), dict(alpha=0.0), dict(alpha=1.5),
                                 dict(epsilon=2.0), dict(gamma=-0.1)])
def test_bad_settings_name_the_setting(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        TabularConfig(**bad)


def test_gamma_bootstraps_from_the_next_cell():
    learner = _tiny(TabularConfig(observation_bins=2, action_bins=2, epsilon=0.0, alpha=1.0, gamma=0.5))
    learner.act(np.array([[0.9]]))
    learner.learn(np.array([1.0]))  # cell 1, action 0: Q = 1
    learner.act(np.array([[0.1]]))
    learner.learn(np.array([0.0]), next_observations=np.array([[0.9]]), terminal=False)
    assert learner.q[0, 0, 0] == 0.5
    learner.act(np.array([[0.1]]))
    with pytest.raises(ValueError, match="next_observations"):
        learner.learn(np.array([0.0]), terminal=False)


def test_a_paper_table_gives_its_exploration_probability_and_discount():
    from somarm.learners import presets

    table = presets.get("table5")
    config = TabularConfig.from_table(table)
    assert config.epsilon == table.p and config.gamma == table.gamma
    assert TabularConfig.from_dict(config.to_dict()) == config


def test_a_damaged_file_is_one_line_naming_it(tmp_path):
    import json

    learner = TabularQ(TabularConfig(), observation_low=[0, 0], observation_high=[1, 1], action_low=[0, 0],
                       action_high=[1, 1], n_trials=2, seed=0)
    path = tmp_path / "learner.npz"
    learner.save(path)
    saved = dict(np.load(path))
    for name, change in (("meta-list", {"meta": np.array(json.dumps([1]))}), ("no-q", {"q": None})):
        damaged = {key: value for key, value in {**saved, **change}.items() if value is not None}
        np.savez(tmp_path / f"{name}.npz", **damaged)
        with pytest.raises(ValueError, match=rf"^{tmp_path / name}\.npz is a damaged learner file: ") as info:
            TabularQ.load(tmp_path / f"{name}.npz")
        assert "\n" not in str(info.value)
