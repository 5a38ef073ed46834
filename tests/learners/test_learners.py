import numpy as np
import pytest

from somarm import learners
from somarm.learners.motoric import MotoricConfig, MotoricMap
from somarm.learners.somq import SOMQ, SOMQConfig

BOX = dict(observation_low=[0.0, 0.0], observation_high=[1.0, 1.0], action_low=[0.0], action_high=[2.0])


def test_registry():
    from somarm.learners.tabular import TabularConfig, TabularQ

    assert learners.LEARNERS == {"somq": (SOMQConfig, SOMQ), "motoric": (MotoricConfig, MotoricMap),
                                 "tabular": (TabularConfig, TabularQ)}


@pytest.mark.parametrize("kind", ["somq", "motoric", "tabular"])
def test_make_and_load_any_kind(tmp_path, kind):
    learner = learners.make_learner(kind, None, n_trials=2, seed=3, **BOX)
    assert learner.kind == kind
    for _ in range(5):
        learner.learn(-learner.act(np.full((2, 2), 0.3))[:, 0])
    learner.save(tmp_path / "learner.npz")
    loaded = learners.load_learner(tmp_path / "learner.npz")
    assert type(loaded) is type(learner) and loaded.t == 5
    x = np.random.default_rng(0).random((2, 4, 2))
    np.testing.assert_array_equal(loaded.predict(x), learner.predict(x))


def test_errors():
    with pytest.raises(ValueError, match="unknown learner kind 'ddpg'; allowed: somq, motoric"):
        learners.make_learner("ddpg", None, **BOX)
    with pytest.raises(ValueError, match="needs a MotoricConfig"):
        learners.make_learner("motoric", SOMQConfig(), **BOX)
    with pytest.raises(ValueError, match="cannot read a learner"):
        learners.load_learner("/nonexistent/learner.npz")


def test_wrong_kind_and_atomic_overwrite(tmp_path):
    path = tmp_path / "l.npz"
    somq = learners.make_learner("somq", None, **BOX)
    somq.save(path)
    with pytest.raises(ValueError, match="holds a somq learner, not motoric"):
        MotoricMap.load(path)
    motoric = learners.make_learner("motoric", None, **BOX)
    motoric.save(path)  # replaces the file whole
    assert isinstance(learners.load_learner(path), MotoricMap)
    assert [p.name for p in tmp_path.iterdir()] == ["l.npz"]  # no temporary left behind


def test_bench_learner_smoke(capsys):
    from somarm.benchmarks.learner import main

    assert main(["--steps", "20", "--repeats", "1", "--trials", "1,3"]) == 0
    out = capsys.readouterr().out
    assert "50x1 in, 50x1 act, 20-D" in out and "10x10 in, 8x1 act" in out and "30x1 in, 30x1 act" in out
    rows = [line.split() for line in out.splitlines() if line.startswith(("50x1", "10x10", "30x1"))]
    # 4 maps x 2 trial counts, then the interpolated response's rows: 4 maps x (t0 = 0, 50,000).
    assert len(rows) == 16 and all(float(row[-1].rstrip("x")) > 0 for row in rows)
    assert "interpolated within 2x of the winner response" in out


@pytest.mark.parametrize("kind", ["somq", "motoric"])
def test_act_twice_without_learn_is_refused(kind):
    learner = learners.make_learner(kind, None, n_trials=2, **BOX)
    learner.act(np.full((2, 2), 0.3))
    with pytest.raises(ValueError, match=r"act\(\) was called again before learn\(\)"):
        learner.act(np.full((2, 2), 0.3))
    learner.learn(np.zeros(2))
    learner.act(np.full((2, 2), 0.3))  # after learn, act again is fine


@pytest.mark.parametrize("kind", ["somq", "motoric"])
def test_complex_numbers_are_refused_not_truncated(kind):
    learner = learners.make_learner(kind, None, n_trials=1, **BOX)
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
    config = SOMQConfig(input_shape=(100, 100), action_shape=(10,))
    with pytest.raises(ValueError, match=r"input_shape=100x100, action_shape=10 and 1 trial\(s\) needs about "
                                         r"2\.2 GiB of memory, more than the 1\.0 GiB available"):
        learners.make_learner("somq", config, **BOX)
    learners.make_learner("somq", SOMQConfig(input_shape=(30, 30), action_shape=(10,)), **BOX)  # 19 MiB


@pytest.mark.parametrize("relative", [False, True])
def test_an_epsilon_that_overflows_is_refused(relative):
    config = SOMQConfig(epsilon=1e308, epsilon_relative=relative)
    with pytest.raises(ValueError, match="epsilon=1e\\+308 is too large"):
        learners.make_learner("somq", config, **BOX)
    learners.make_learner("somq", SOMQConfig(epsilon=1e6, epsilon_relative=relative), **BOX)  # large but finite


@pytest.mark.parametrize("kind", learners.KINDS)
def test_every_kind_is_layered_and_has_presets(kind):
    from somarm.learners import presets
    from somarm.learners.base import ConfigBase, LearnerBase
    from somarm.protocols import Learner

    config_class, learner_class = learners.LEARNERS[kind]
    assert issubclass(config_class, ConfigBase)
    # The map learners share LearnerBase (the input map); the tabular learner has fixed grids instead.
    assert issubclass(learner_class, LearnerBase) or kind == "tabular"
    assert isinstance(learners.make(kind, None, **BOX), Learner)
    assert learner_class.kind == kind and learner_class.config_class is config_class
    assert isinstance(presets.config_for(kind, "table2"), config_class)
