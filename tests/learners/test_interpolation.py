"""The interpolated response: exact fixtures, the reference, batching, save/load and bad settings."""

import dataclasses

import numpy as np
import pytest
from somq_cases import BOUNDS, small_config
from somq_cases import arc as _arc

from somarm.learners import interpolation
from somarm.learners.reference import ReferenceSOMQ, interpolated_response
from somarm.learners.somq import SOMQConfig, SOMQLearner

BOX1 = dict(observation_low=[0.0], observation_high=[3.0], action_low=[-1.0, -1.0], action_high=[1.0, 1.0])


def _planted(**changes):
    """Four input units at 0, 1, 2, 3 whose greedy action units are 0, 1, 2 and 4 (a jump at the end)."""
    settings = dict(input_shape=(4,), action_shape=(5,), alpha=0.5, lambda_s=0.0, lambda_a=0.5, n_s=0.0,
                    n_a=1.0, p=0.0, epsilon=0.0, response="interpolated")
    config = SOMQConfig(**{**settings, **changes})
    learner = SOMQLearner(config, **BOX1)
    learner.input_weights[0] = [[0.0], [1.0], [2.0], [3.0]]
    learner.action_weights[0] = [[-1.0, 0.0], [-0.5, 0.25], [0.0, 0.5], [0.5, 0.5], [1.0, -1.0]]
    learner.q[0] = -1.0
    for unit, best in enumerate([0, 1, 2, 4]):
        learner.q[0, unit, best] = 0.0
    return learner


def test_response_blends_the_two_nearest_units_with_tapered_inverse_distances():
    learner = _planted()
    # x = 1.25: nearest 1 (d 0.25), 2 (d 0.75), then 0 (d 1.25): v = 4 - 0.8, 4/3 - 0.8.
    v1, v2 = 1 / 0.25 - 1 / 1.25, 1 / 0.75 - 1 / 1.25
    b1, b2 = v1 / (v1 + v2), v2 / (v1 + v2)
    expected = b1 * np.array([-0.5, 0.25]) + b2 * np.array([0.0, 0.5])
    np.testing.assert_allclose(learner.predict([[1.25]]), [expected], rtol=0, atol=1e-15)
    # On a unit: that unit's greedy action alone; midway between two units far from the rest: the mean.
    np.testing.assert_array_equal(learner.predict([[[1.0], [2.0]]]), [[[-0.5, 0.25], [0.0, 0.5]]])


def test_units_whose_greedy_actions_are_far_apart_on_the_action_map_are_not_blended():
    learner = _planted()
    # x = 2.4: nearest 2 (greedy unit 2), then 3 (greedy unit 4, two grid steps away > MAX_JUMP).
    assert interpolation.MAX_JUMP < 2
    np.testing.assert_array_equal(learner.predict([[2.4]]), [[[0.0, 0.5]][0]])
    np.testing.assert_array_equal(learner.predict([[2.6]]), [[1.0, -1.0]])


def test_response_is_continuous_where_the_mapping_is():
    learner = _planted()
    x = np.linspace(0.0, 2.0, 2001)[None, :, None]
    response = learner.predict(x)[0]
    assert np.abs(np.diff(response, axis=0)).max() < 0.01  # steps of 0.001 in x, slopes below 10
    winner = dataclasses.replace(learner.config, response="winner")
    jumps = SOMQLearner(winner, **BOX1)
    for name in ("input_weights", "action_weights", "q"):
        getattr(jumps, name)[...] = getattr(learner, name)
    assert np.abs(np.diff(jumps.predict(x)[0], axis=0)).max() >= 0.5  # the paper's response jumps


def test_one_greedy_step_exact_arrays():
    learner = _planted()
    action = learner.act([[1.0]])  # on unit 1: response = u_1, epsilon 0
    np.testing.assert_array_equal(action, [[-0.5, 0.25]])
    assert learner._shifted[0] and learner._units[0] == 1
    before = learner.action_weights[0].copy()
    learner.learn([0.5])  # 0.5 > Q(s_1, a_1) = 0: step 7 shifts units 0..2 by 0.5 * psi * (a' - u_1) = 0
    np.testing.assert_array_equal(learner.action_weights[0], before)
    # Now a perturbed action away from the unit: epsilon 0.4, noise row fixed below.
    learner = _planted(epsilon=0.5)
    learner._streams.next = lambda: np.array([[0.9, 0.0, 0.0, 1.0, 0.5]])  # greedy; noise +1, 0
    action = learner.act([[1.0]])
    np.testing.assert_array_equal(action, [[0.0, 0.25]])
    learner.learn([0.5])
    # Units within N_A = 1 of unit 1 move by lambda_A * psi * (0.5, 0) with psi = 0.5, 1, 0.5: a shift,
    # where the paper's rule would also pull units 0 and 2 towards (0, 0.25).
    expected = np.array([[-0.875, 0.0], [0.0, 0.25], [0.125, 0.5], [0.5, 0.5], [1.0, -1.0]])
    expected[1, 0] = -0.25
    np.testing.assert_array_equal(learner.action_weights[0], expected)


def test_exploring_tries_a_neighbour_of_the_greedy_unit_or_a_random_unit():
    learner = _planted(p=1.0)
    for u, unit in ((0.0, 0), (0.24, 0), (0.26, 2), (0.5, 0), (0.75, 2), (0.99, 4)):
        learner._streams.next = lambda u=u: np.array([[0.0, u, 0.0, 0.5, 0.5]])  # explore; x on unit 1
        learner.act([[1.0]])
        assert learner._units[0] == unit and not learner._shifted[0], u
        learner._pending = False


def test_an_exploring_step_is_the_papers_step():
    learner = _planted(epsilon=0.4, p=1.0)
    learner._streams.next = lambda: np.array([[0.0, 0.55, 0.0, 1.0, 0.5]])  # explore; random unit 0; noise +1, 0
    action = learner.act([[1.0]])
    np.testing.assert_array_equal(action, [[-0.6, 0.0]])
    assert not learner._shifted[0]
    learner.learn([0.5])  # the paper's pull of units 0 and 1 towards (-0.6, 0)
    np.testing.assert_allclose(learner.action_weights[0, :2], [[-0.8, 0.0], [-0.5 + 0.25 * -0.1, 0.25 - 0.25 * 0.25]],
                               rtol=0, atol=1e-15)


def _config(input_shape, neighbourhood_q, gamma, noise="uniform"):
    return small_config(input_shape, neighbourhood_q, gamma, noise, response="interpolated")


@pytest.mark.parametrize("input_shape", [(6,), (3, 4), (1,)], ids=["1d", "2d", "one-unit"])
@pytest.mark.parametrize("neighbourhood_q,gamma,noise", [(True, 0.0, "uniform"), (False, 0.9, "gaussian")],
                         ids=["NL", "noNL-delayed-gaussian"])
@pytest.mark.parametrize("periodic", [False, True], ids=["box", "circles"])
def test_batched_equals_reference_exactly(input_shape, neighbourhood_q, gamma, noise, periodic):
    config = dataclasses.replace(_config(input_shape, neighbourhood_q, gamma, noise), periodic_actions=periodic)
    # With circles, action dimensions 0 and 2 wrap round (their low and high are one point).
    angles = [True, False, True] if periodic else None
    batched = SOMQLearner(config, n_trials=3, seed=5, action_periodic=angles, **BOUNDS)
    references = [ReferenceSOMQ(config, seed=5, trial_id=i, action_periodic=angles, **BOUNDS) for i in range(3)]
    rng = np.random.default_rng(7)
    observations = rng.uniform([0, -1], [1, 1], (3, 2))
    shifted = wrapped = 0
    for step in range(150):
        actions = batched.act(observations)
        shifted += int(batched._shifted.sum())
        expected = np.stack([ref.act(observations[i]) for i, ref in enumerate(references)])
        np.testing.assert_array_equal(actions, expected, err_msg=f"actions differ at step {step}")
        rewards = -np.abs(actions[:, 0] - observations[:, 0]) - np.abs(actions[:, 1] + observations[:, 1])
        if periodic:  # best near the edges of the circles, so that actions and units go round them
            rewards = (-np.abs(_arc(actions[:, 0] - 0.95, 2.0)) - np.abs(actions[:, 1] - observations[:, 0])
                       - np.abs(_arc(actions[:, 2] + 1.9, 4.0)))
            wrapped += int((actions[:, 0] < -0.5).sum() + (actions[:, 2] > 1.0).sum())
        next_observations = rng.uniform([0, -1], [1, 1], (3, 2))
        terminal = rng.random(3) < 0.3
        batched.learn(rewards, next_observations, terminal)
        for i, ref in enumerate(references):
            ref.learn(rewards[i], next_observations[i], bool(terminal[i]))
        observations = next_observations
    probes = rng.uniform([0, -1], [1, 1], (3, 20, 2))
    predicted = batched.predict(probes)
    for i, ref in enumerate(references):
        np.testing.assert_array_equal(batched.input_weights[i], ref.input_weights)
        np.testing.assert_array_equal(batched.action_weights[i], ref.action_weights)
        np.testing.assert_array_equal(batched.q[i], ref.q)
        for o in range(20):
            _, _, response = interpolated_response(probes[i, o], ref.input_weights, ref.action_weights, ref.q,
                                                   0.0, ref.distances_a, interpolation.n_basis_for(input_shape),
                                                   ref.action_low, ref.action_high, ref.wrap)
            np.testing.assert_array_equal(predicted[i, o], response)
    assert shifted > 100  # most steps were interpolated greedy steps
    assert wrapped > 20 or not periodic  # many actions came out across an edge


def test_trial_alone_equals_trial_in_batch_and_resume_equals_uninterrupted(tmp_path):
    config = _config((6,), True, 0.0)
    batch = SOMQLearner(config, n_trials=4, seed=3, **BOUNDS)
    alone = SOMQLearner(config, n_trials=1, seed=3, trial_ids=[2], **BOUNDS)
    rng = np.random.default_rng(0)
    for step in range(60):
        x = rng.uniform([0, -1], [1, 1], (4, 2))
        a = batch.act(x)
        np.testing.assert_array_equal(alone.act(x[2:3]), a[2:3])
        if step == 30:  # save and reload between act and learn
            alone.save(tmp_path / "alone.npz")
            alone = SOMQLearner.load(tmp_path / "alone.npz")
            assert alone.config.response == "interpolated"
        r = -np.abs(a).sum(axis=1)
        batch.learn(r)
        alone.learn(r[2:3])
    np.testing.assert_array_equal(alone.action_weights[0], batch.action_weights[2])
    np.testing.assert_array_equal(alone.q[0], batch.q[2])


def test_response_is_a_setting_like_any_other():
    config = SOMQConfig().with_overrides({"response": "interpolated"})
    assert config.response == "interpolated"
    assert SOMQConfig.from_dict(config.to_dict()) == config
    assert SOMQConfig().response == "winner"
    with pytest.raises(ValueError, match=r"^response=nearest: response must be one of winner, interpolated"):
        SOMQConfig().with_overrides({"response": "nearest"})
    with pytest.raises(ValueError, match="response must be one of winner, interpolated, got 3"):
        SOMQConfig(response=3)


def test_cli_trains_views_and_rejects_an_unknown_response(tmp_path, capsys):
    from somarm.cli import main
    from somarm.run import load as load_run

    run = tmp_path / "run"
    args = ["train", "reach2", "--set", "response=interpolated", "--preset", "table1+", "--trials", "2",
            "--steps", "300", "--no-progress", "--no-figures", "--out", str(run)]
    assert main(args) == 0
    config, learner = load_run(run)
    assert config.overrides["response"] == "interpolated" and learner.config.response == "interpolated"
    assert learner.config.lambda_a.floor == 0.1  # table1+
    page = tmp_path / "view.html"
    assert main(["view", "reach2", "--run", str(run), "--html", str(page), "--goals", "3"]) == 0
    assert page.stat().st_size > 1000
    capsys.readouterr()
    assert main(["train", "reach2", "--set", "response=nearest", "--steps", "10", "--block", "10",
                 "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("somarm: error:") and "response must be one of winner, interpolated" in err
    assert len(err.splitlines()) == 1


def _without(path, name, out):
    """Copy the learner file ``path`` to ``out`` without its array ``name`` (an older or damaged file)."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {key: data[key] for key in data.files if key != name}
    np.savez(out, **arrays)
    return out


def test_a_file_saved_before_shifted_existed_still_loads_and_resumes(tmp_path):
    config = _config((6,), True, 0.0)
    config = dataclasses.replace(config, response="winner")
    whole = SOMQLearner(config, n_trials=2, seed=5, **BOUNDS)
    rng = np.random.default_rng(1)
    observations = rng.uniform([0, -1], [1, 1], (40, 2, 2))
    for x in observations[:20]:
        whole.learn(-np.abs(whole.act(x)).sum(axis=1))
    whole.act(observations[20])  # saved between act and learn
    whole.save(tmp_path / "new.npz")
    old = SOMQLearner.load(_without(tmp_path / "new.npz", "_shifted", tmp_path / "old.npz"))
    assert not old._shifted.any()
    for learner in (whole, old):
        learner.learn(-np.abs(learner._actions).sum(axis=1))
        for x in observations[21:]:
            learner.learn(-np.abs(learner.act(x)).sum(axis=1))
    np.testing.assert_array_equal(old.action_weights, whole.action_weights)
    np.testing.assert_array_equal(old.q, whole.q)
    # A file that lacks an array every learner has is damaged: one line naming the file and the array.
    damaged = _without(tmp_path / "new.npz", "q", tmp_path / "damaged.npz")
    with pytest.raises(ValueError, match=r"damaged\.npz is a damaged learner file: array 'q' is missing$") as err:
        SOMQLearner.load(damaged)
    assert "\n" not in str(err.value)
