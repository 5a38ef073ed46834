import numpy as np
import pytest
from somq_cases import held_bytes

from somarm import learners
from somarm.learners.motoric import MotoricConfig, MotoricMap
from somarm.learners.somq import SOMQConfig, SOMQLearner

BOX = dict(observation_low=[0.0, 0.0], observation_high=[1.0, 1.0], action_low=[0.0], action_high=[2.0])


def test_registry():
    from somarm.learners.tabular import TabularConfig, TabularQ

    assert learners.LEARNERS == {"somq": (SOMQConfig, SOMQLearner), "motoric": (MotoricConfig, MotoricMap),
                                 "tabular": (TabularConfig, TabularQ)}


@pytest.mark.parametrize("kind", learners.LEARNERS)
def test_make_and_load_any_kind(tmp_path, kind):
    learner = learners.make(kind, None, n_trials=2, seed=3, **BOX)
    assert learner.kind == kind
    for _ in range(5):
        learner.learn(-learner.act(np.full((2, 2), 0.3))[:, 0])
    learner.save(tmp_path / "learner.npz")
    loaded = learners.load(tmp_path / "learner.npz")
    assert type(loaded) is type(learner) and loaded.t == 5
    x = np.random.default_rng(0).random((2, 4, 2))
    np.testing.assert_array_equal(loaded.predict(x), learner.predict(x))


def test_errors():
    with pytest.raises(ValueError, match="unknown learner kind 'ddpg'; allowed: somq, motoric"):
        learners.make("ddpg", None, **BOX)
    with pytest.raises(ValueError, match="needs a MotoricConfig"):
        learners.make("motoric", SOMQConfig(), **BOX)
    with pytest.raises(ValueError, match="cannot read a learner"):
        learners.load("/nonexistent/learner.npz")


def test_wrong_kind_and_atomic_overwrite(tmp_path):
    path = tmp_path / "l.npz"
    somq = learners.make("somq", None, **BOX)
    somq.save(path)
    with pytest.raises(ValueError, match="holds a somq learner, not motoric"):
        MotoricMap.load(path)
    motoric = learners.make("motoric", None, **BOX)
    motoric.save(path)  # replaces the file whole
    assert isinstance(learners.load(path), MotoricMap)
    assert [p.name for p in tmp_path.iterdir()] == ["l.npz"]  # no temporary left behind


def test_bench_learner_smoke(capsys):
    from somarm.perf.learner import main

    assert main(["--steps", "20", "--repeats", "1", "--trials", "1,3"]) == 0
    out = capsys.readouterr().out
    assert "50x1 in, 50x1 act, 20-D" in out and "10x10 in, 8x1 act" in out and "30x1 in, 30x1 act" in out
    rows = [line.split() for line in out.splitlines() if line.startswith(("50x1", "10x10", "30x1"))]
    # 4 maps x 2 trial counts, then the interpolated response's rows: 4 maps x (t0 = 0, 50,000).
    # The ratios are printed as numbers (their size depends on the machine's load: not asserted on).
    assert len(rows) == 16 and all(float(row[-1].rstrip("x")) >= 0 for row in rows)
    assert "interpolated within 2x of the winner response" in out
    from somarm.perf.learner import REPRESENTATIONS

    for label, _ in REPRESENTATIONS:  # one row per representation and trial count, with its memory
        found = [line for line in out.splitlines() if line[:36].rstrip() == label]
        assert len(found) == 2 and float(found[0].split()[-1]) > 0


@pytest.mark.parametrize("kind", ["somq", "motoric"])
def test_act_twice_without_learn_is_refused(kind):
    learner = learners.make(kind, None, n_trials=2, **BOX)
    learner.act(np.full((2, 2), 0.3))
    with pytest.raises(ValueError, match=r"act\(\) was called again before learn\(\)"):
        learner.act(np.full((2, 2), 0.3))
    learner.learn(np.zeros(2))
    learner.act(np.full((2, 2), 0.3))  # after learn, act again is fine


@pytest.mark.parametrize("kind", ["somq", "motoric"])
def test_complex_numbers_are_refused_not_truncated(kind):
    learner = learners.make(kind, None, n_trials=1, **BOX)
    with pytest.raises(ValueError, match="observations must be real numbers, got complex"):
        learner.act(np.array([[0.3 + 1j, 0.3]]))
    learner.act(np.array([[0.3, 0.3]]))
    with pytest.raises(ValueError, match="rewards must be real numbers"):
        learner.learn(np.array([1j]))


def test_complex_actions_are_refused_by_the_task():
    from somarm import tasks

    task = tasks.make("reach2", n_trials=1)
    task.reset()
    with pytest.raises(ValueError, match="must be real numbers, got complex"):
        task.step(np.array([[0.1 + 0.5j, 0.1]]))


def test_memory_is_estimated_before_allocating(monkeypatch):
    from somarm import validation

    monkeypatch.setattr(validation, "_available_memory", lambda: 2**30)
    config = SOMQConfig(input_shape=(1000, 1000), action_shape=(200,))  # Q alone: 2e8 floats
    with pytest.raises(ValueError, match=r"input_shape=1000x1000, action_shape=200 and 1 trial\(s\) needs about "
                                         r"1\.5 GiB of memory, more than the 1\.0 GiB available"):
        learners.make("somq", config, **BOX)
    learners.make("somq", SOMQConfig(input_shape=(100, 100), action_shape=(10,)), **BOX)  # 1.1 MiB


@pytest.mark.parametrize("relative", [False, True])
def test_an_epsilon_that_overflows_is_refused(relative):
    config = SOMQConfig(epsilon=1e308, epsilon_relative=relative)
    with pytest.raises(ValueError, match="epsilon=1e\\+308 is too large"):
        learners.make("somq", config, **BOX)
    learners.make("somq", SOMQConfig(epsilon=1e6, epsilon_relative=relative), **BOX)  # large but finite


@pytest.mark.parametrize("kind", learners.LEARNERS)
def test_every_kind_is_layered_and_has_presets(kind):
    from somarm.learners import presets
    from somarm.learners.base import ConfigBase, LearnerBase
    from somarm.protocols import Learner

    config_class, learner_class = learners.LEARNERS[kind]
    assert issubclass(config_class, ConfigBase)
    assert issubclass(learner_class, LearnerBase)
    assert isinstance(learners.make(kind, None, **BOX), Learner)
    assert learner_class.kind == kind and learner_class.config_class is config_class
    assert isinstance(presets.config_for(kind, "table2"), config_class)


@pytest.mark.parametrize("kind", learners.LEARNERS)
def test_every_kind_estimates_its_memory_in_one_place_the_registry_reaches(kind, monkeypatch):
    from somarm import validation

    config = learners.config_class(kind)()
    what, n_bytes = learners.memory_needed(kind, config, n_trials=3, obs_dim=2, action_dim=1)
    assert what.startswith(f"a {kind} learner with ") and what.endswith("and 3 trial(s)") and n_bytes > 0
    learner = learners.make(kind, config, n_trials=3, **BOX)
    # What it allocates is covered: the arrays the learner holds fit inside the estimate, but for
    # a few numbers per trial and dimension (bounds, winners, chosen cells) that no estimate counts.
    held = held_bytes(learner)
    assert held <= n_bytes + 64 * (3 + 2 + 1)
    monkeypatch.setattr(validation, "_available_memory", lambda: int(n_bytes) - 1)
    with pytest.raises(ValueError, match=rf"^a {kind} learner with .* needs about .* of memory, more than"):
        learners.make(kind, config, n_trials=3, **BOX)


@pytest.mark.parametrize("kind", ["somq", "motoric"])
def test_a_ten_thousand_unit_input_map_holds_no_grid_distance_matrix(kind):
    config = learners.config_class(kind)(input_shape=(100, 100))
    _, n_bytes = learners.memory_needed(kind, config, n_trials=1, obs_dim=4, action_dim=1)
    assert n_bytes < 10e6  # a (10,000 x 10,000) distance matrix alone would take 800 MB
    learner = learners.make(kind, config, n_trials=1, observation_low=np.zeros(4), observation_high=np.ones(4),
                            action_low=np.zeros(1), action_high=np.ones(1))
    assert held_bytes(learner) <= n_bytes + 64 * (1 + 4 + 1)


def test_an_unknown_kind_has_no_memory_estimate():
    with pytest.raises(ValueError, match="unknown learner kind 'dqn'; allowed: somq, motoric, tabular"):
        learners.memory_needed("dqn", None, n_trials=1, obs_dim=1, action_dim=1)


@pytest.mark.parametrize("kind", learners.LEARNERS)
def test_what_a_learner_says_it_has_is_what_it_has(kind):
    learner = learners.make(kind, None, n_trials=2, **BOX)
    assert learner.has_maps == hasattr(learner, "input_weights") == hasattr(learner, "action_weights")
    assert learner.has_action_map == (learner.has_maps and hasattr(learner, "q"))
    assert learner.learned_arrays and all(isinstance(getattr(learner, n), np.ndarray) for n in learner.learned_arrays)
    assert learner.periodic_dimensions.shape == (1,) and not learner.periodic_dimensions.any()
