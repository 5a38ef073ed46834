"""RunConfig: typed settings, the learner config built once, text read only at the front ends."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from somarm import run, tasks
from somarm.learners import presets
from somarm.learners.motoric import MotoricConfig
from somarm.learners.schedules import InverseDecay
from somarm.learners.somq import SOMQConfig
from somarm.run import RunConfig
from somarm.run.config import add_options, from_options


def _options(*argv: str) -> RunConfig:
    parser = argparse.ArgumentParser()
    add_options(parser)
    return from_options(parser.parse_args(list(argv)))


def test_the_command_line_text_becomes_the_typed_config_the_python_api_gives():
    cli = _options("reach2", "--set", "decay=inv:250", "--set", "epsilon=0.2", "--set", "input_shape=10x10",
                   "--task-set", "radius=0.2", "--task-set", "dynamics=actuated")
    typed = RunConfig(task="reach2", overrides={"decay": InverseDecay(250.0), "epsilon": 0.2, "input_shape": (10, 10)},
                      task_params={"radius": 0.2, "dynamics": "actuated"}).resolved()
    assert cli == typed
    assert cli.overrides == {"decay": InverseDecay(250.0), "epsilon": 0.2, "input_shape": (10, 10)}
    assert cli.task_params == {"radius": 0.2, "dynamics": "actuated"}
    assert cli.learner_config == presets.get("table1").with_changes(cli.overrides)
    assert cli.learner_config.epsilon.scale == 0.2 and cli.learner_config.alpha.decay == InverseDecay(250.0)


def test_a_typed_run_equals_the_same_run_from_the_command_line():
    common = ("--trials", "2", "--steps", "300", "--seed", "3")
    cli = run.train(_options("reach2", *common, "--set", "alpha=0.5", "--set", "neighbourhood_q=false"),
                    progress=False)
    typed = run.train(RunConfig(task="reach2", n_trials=2, n_steps=300, seed=3,
                                overrides={"alpha": 0.5, "neighbourhood_q": False}), progress=False)
    np.testing.assert_array_equal(cli.block_means, typed.block_means)
    np.testing.assert_array_equal(cli.learner.q, typed.learner.q)


def test_a_whole_learner_config_is_used_as_given_and_overrides_change_it():
    own = SOMQConfig(input_shape=(5,), action_shape=(7,))
    config = RunConfig(task="reach2", learner_config=own, overrides={"gamma": 0.5}).resolved()
    assert config.learner_config == SOMQConfig(input_shape=(5,), action_shape=(7,), gamma=0.5)
    assert config.preset is None and config.resolved() == config  # resolving twice changes nothing
    task, learner = run.make(config)
    assert learner.config is config.learner_config  # built once: the learner holds the resolved config


@pytest.mark.parametrize("kwargs, match", [
    ({"overrides": {"epsilon": "0.2"}}, r"^epsilon must be a number, got the text '0.2' \(parse text with"),
    ({"overrides": {"decay": "inv:1000"}}, "^decay must be a Decay"),
    ({"overrides": {"bogus": 1.0}}, "^unknown key 'bogus'; allowed keys: decay, alpha"),
    ({"task_params": {"radius": "0.2"}}, "^task parameter radius of reach2 takes a number written with the digits 0-9, got the text '0.2'"),
    ({"task_params": {"nope": 1}}, r"^unknown parameter\(s\) nope for task reach2"),
    ({"learner_config": MotoricConfig()}, "^learner_config of a somq learner must be a SOMQConfig, got MotoricConfig$"),
    ({"learner": "bogus"}, "^unknown learner 'bogus'; allowed: somq, motoric, tabular$"),
    ({"preset": "table9", "learner_config": SOMQConfig()}, "^unknown preset 'table9'"),
    ({"backend": "bullet"}, "^unknown backend 'bullet'; backends: mujoco, analytic, gymnasium$"),
    ({"task": "reach2_obstacle", "backend": "analytic"}, "^reach2_obstacle needs the mujoco backend"),
])
def test_bad_typed_settings_fail_in_one_line_before_anything_is_built(kwargs, match, monkeypatch):
    def no_build(*args, **kw):
        raise AssertionError("a task was built to check a setting")

    monkeypatch.setattr(tasks, "make", no_build)
    with pytest.raises(ValueError, match=match) as info:
        RunConfig(**{"task": "reach2", **kwargs}).resolved()
    assert "\n" not in str(info.value)


def test_config_json_round_trip_keeps_the_text_form_and_the_values():
    config = RunConfig(task="four_goals", overrides={"decay": InverseDecay(250.0), "n_a.floor": 1.0},
                       task_params={"switch_step": 500}, trial_ids=[4, 7], n_trials=2).resolved()
    data = json.loads(json.dumps(config.to_dict()))
    assert data["overrides"] == {"decay": "inv:250", "n_a.floor": "1"}
    assert data["task_params"] == {"switch_step": 500} and "learner_config" not in data  # the keys as before
    assert RunConfig.from_dict(data).resolved() == config
    own = RunConfig(task="reach2", learner_config=SOMQConfig(input_shape=(5,))).resolved()
    assert own.to_dict()["learner_config"]["input_shape"] == [5]
    assert RunConfig.from_dict(json.loads(json.dumps(own.to_dict()))).resolved() == own


def test_a_config_json_written_before_typed_settings_still_loads():
    # The form every run folder had: overrides and task parameters as text, no learner_config.
    old = {"task": "reach2", "learner": "somq", "preset": "table1",
           "overrides": {"alpha": "0.5", "decay": "inv:250.0", "neighbourhood_q": "false"},
           "task_params": {"radius": "0.2", "dynamics": "kinematic"}, "n_trials": 2, "n_steps": 300,
           "seed": 3, "backend": "mujoco", "block": 100, "trial_ids": None}
    config = RunConfig.from_dict(old).resolved()
    assert config.overrides == {"alpha": 0.5, "decay": InverseDecay(250.0), "neighbourhood_q": False}
    assert config.task_params == {"radius": 0.2, "dynamics": "kinematic"}
    assert config == RunConfig(task="reach2", n_trials=2, n_steps=300, seed=3,
                               overrides={"alpha": 0.5, "decay": InverseDecay(250.0), "neighbourhood_q": False},
                               task_params={"radius": 0.2, "dynamics": "kinematic"}).resolved()
    with pytest.raises(ValueError, match="^alpha=fast: alpha must be a number written with the digits 0-9"):
        RunConfig.from_dict({**old, "overrides": {"alpha": "fast"}})


def test_a_hand_written_config_json_may_give_override_values_as_json():
    config = RunConfig.from_dict({"task": "reach2", "overrides": {"gamma": 0, "neighbourhood_q": False}})
    assert config.overrides == {"gamma": 0.0, "neighbourhood_q": False}


def test_a_run_folder_with_the_older_config_json_loads_and_evaluates(tmp_path):
    result = run.train(RunConfig(task="reach2", n_trials=2, n_steps=200, overrides={"input_shape": (10, 10)},
                                 task_params={"radius": 0.2}), progress=False)
    run.write(result, tmp_path, figures=False)
    data = json.loads((tmp_path / "config.json").read_text())
    assert data["overrides"] == {"input_shape": "10x10"} and data["task_params"] == {"radius": 0.2}
    data["task_params"] = {"radius": "0.2"}  # as folders written before typed settings hold it
    (tmp_path / "config.json").write_text(json.dumps(data))
    config, learner = run.load(tmp_path)
    assert config == result.config and config.task_params == {"radius": 0.2}
    assert run.task_for(config, learner).params.radius == 0.2
