"""``SOMQ`` as an SB3 user writes it: a policy name before the environment, ``verbose``, ``save("x.zip")``."""

import zipfile

import numpy as np
import pytest

from somarm import SOMQ

pytest.importorskip("gymnasium")


def _same_actions(a: SOMQ, b: SOMQ) -> bool:
    observations = np.random.default_rng(0).uniform(-1.0, 1.0, (8, 3))
    return all(np.array_equal(a.predict(x)[0], b.predict(x)[0]) for x in observations)


def test_a_policy_name_before_the_environment_is_taken_as_sb3_takes_it():
    import gymnasium as gym

    plain = SOMQ("Pendulum-v1", seed=2).learn(100)
    assert _same_actions(SOMQ("MlpPolicy", "Pendulum-v1", seed=2).learn(100), plain)
    assert _same_actions(SOMQ(policy="MlpPolicy", env=gym.make("Pendulum-v1"), seed=2).learn(100), plain)
    assert _same_actions(SOMQ(env="Pendulum-v1", seed=2).learn(100), plain)


@pytest.mark.parametrize(("args", "kwargs", "expected"), [
    (("CnnPolicy", "Pendulum-v1"), {}, "policy 'CnnPolicy'"),
    (("MlpPolicy",), {}, "give the environment too"),
    ((), {}, "give an environment"),
    (("Pendulum-v1",), {"verbose": 3}, "verbose must be 0, 1 or 2"),
])
def test_a_policy_or_verbose_somq_cannot_honour_is_refused_in_one_line(args, kwargs, expected):
    with pytest.raises(ValueError) as caught:
        SOMQ(*args, **kwargs)
    assert expected in str(caught.value) and "\n" not in str(caught.value), caught.value


def test_verbose_says_what_learn_did_and_quiet_says_nothing(capsys):
    SOMQ("Pendulum-v1", seed=1).learn(400)
    assert capsys.readouterr() == ("", "")
    SOMQ("Pendulum-v1", seed=1, verbose=1).learn(400)
    shown = capsys.readouterr()
    assert "400/400" in shown.err and "mean return" in shown.err, shown  # the progress line, as lines in a log
    from somarm import tasks

    default = tasks.record("gym:Pendulum-v1").n_steps  # the preset's run length, which 400 steps fall short of
    assert "400 steps" in shown.out and f"scored after {default:,}" in shown.out, shown.out


def test_save_to_a_zip_writes_one_file_that_load_reads_back(tmp_path):
    model = SOMQ("Pendulum-v1", seed=4).learn(300)
    path = model.save(tmp_path / "sub" / "pendulum.zip")
    assert path == tmp_path / "sub" / "pendulum.zip" and path.is_file()
    assert list((tmp_path / "sub").iterdir()) == [path]  # one file, no folder beside it
    assert {"config.json", "learner.npz"} <= set(zipfile.ZipFile(path).namelist())
    loaded = SOMQ.load(path)
    assert _same_actions(loaded, model)
    loaded.learn(100)  # its curves came back too: it learns on
    assert loaded.learner.t == 400


def test_somarm_evaluate_reads_a_saved_zip(tmp_path, capsys):
    from somarm.cli import main

    path = SOMQ("Pendulum-v1", seed=4).learn(200).save(tmp_path / "pendulum.zip")
    capsys.readouterr()
    assert main(["evaluate", str(path), "--task-set", "evaluation_steps=5"]) == 0
    assert "greedy mean return" in capsys.readouterr().out


def test_save_refuses_an_empty_path_in_one_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    model = SOMQ("Pendulum-v1", seed=4)
    for path in ("", "  "):
        with pytest.raises(ValueError) as caught:
            model.save(path)
        assert "save needs a path" in str(caught.value) and "\n" not in str(caught.value)
    assert list(tmp_path.iterdir()) == []


def test_a_damaged_zip_is_refused_in_one_line_naming_it(tmp_path):
    path = tmp_path / "broken.zip"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("config.json", "{not json")
    with pytest.raises(ValueError) as caught:
        SOMQ.load(path)
    message = str(caught.value)
    assert str(path) in message and "somarm-zip" not in message and "\n" not in message, message
