import numpy as np
import pytest

from somarm import learners
from somarm.motoric import MotoricConfig, MotoricMap
from somarm.somq import SOMQ, SOMQConfig

BOX = dict(observation_low=[0.0, 0.0], observation_high=[1.0, 1.0], action_low=[0.0], action_high=[2.0])


def test_registry():
    assert learners.LEARNERS == {"somq": (SOMQConfig, SOMQ), "motoric": (MotoricConfig, MotoricMap)}


@pytest.mark.parametrize("kind", ["somq", "motoric"])
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
    assert len(rows) == 8 and all(float(row[-1].rstrip("x")) > 0 for row in rows)


@pytest.mark.parametrize("kind", learners.KINDS)
def test_every_kind_is_layered_and_has_presets(kind):
    from somarm import presets
    from somarm.learner_base import ConfigBase, LearnerBase

    config_class, learner_class = learners.LEARNERS[kind]
    assert issubclass(config_class, ConfigBase) and issubclass(learner_class, LearnerBase)
    assert learner_class.kind == kind and learner_class.config_class is config_class
    assert isinstance(presets.config_for(kind, "table2"), config_class)
