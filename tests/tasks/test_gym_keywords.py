"""A Gymnasium task's keywords and id, checked on one copy of the environment before a run starts."""

import math
import re

import gymnasium
import numpy as np
import pytest
from gymnasium import spaces

from somarm import run, tasks
from somarm.run import RunConfig
from somarm.tasks import gym_envs


class _Keeps(gymnasium.Env):
    """Keeps its keyword ``x`` whatever it is, and never looks at it: any value is taken."""

    observation_space = spaces.Box(0.0, 1.0, (1,), np.float64)
    action_space = spaces.Box(-1.0, 1.0, (1,), np.float64)

    def __init__(self, x=0.0, y=0.0):
        self.x, self.y = x, y

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.array([0.5]), {}

    def step(self, action):
        return np.array([0.5]), 0.0, False, False, {}


class _Refuses(_Keeps):
    """Refuses a negative ``size`` when made, as an environment's own check of a value would."""

    def __init__(self, size=1.0):
        if size < 0:
            raise AssertionError(f"size must be >= 0, got {size}")


class _Unbounded(_Keeps):
    """An infinite observation Box and NaN observations."""

    observation_space = spaces.Box(-np.inf, np.inf, (2,), np.float64)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return np.zeros(2), {}

    def step(self, action):
        self.t += 1
        return np.full(2, np.nan if self.t > 3 else 0.0), 0.0, False, False, {}


gymnasium.register("somarmtest/Keeps-v0", entry_point=_Keeps, max_episode_steps=5)
gymnasium.register("somarmtest/Refuses-v0", entry_point=_Refuses, max_episode_steps=5)
gymnasium.register("somarmtest/Unbounded-v0", entry_point=_Unbounded, max_episode_steps=50)


def _resolved(task, **params):
    return RunConfig(task=task, n_steps=10, block=10, task_params=params).resolved()


@pytest.mark.parametrize(("value", "said"), [("abc", "TypeError"), (float("nan"), "not finite")])
def test_a_keyword_value_the_environment_cannot_step_with_is_one_line_naming_key_value_and_why(value, said):
    with pytest.raises(ValueError) as refused:
        _resolved("gym:Pendulum-v1", g=value)
    message = str(refused.value)
    assert len(message.splitlines()) == 1
    assert message.startswith("gym:Pendulum-v1 with keyword g=") and repr(value) in message and said in message


def test_of_several_keywords_the_one_that_fails_is_named():
    with pytest.raises(ValueError, match=r"with keyword g='abc' fails") as refused:
        _resolved("gym:Pendulum-v1", g="abc", max_episode_steps=50)
    assert "max_episode_steps" not in str(refused.value)


def test_a_value_the_environment_refuses_when_made_is_one_line():
    with pytest.raises(ValueError, match=r"^gym:somarmtest/Refuses-v0 with keyword size=-2 fails when made "
                                         r"\(AssertionError: size must be >= 0, got -2\)"):
        _resolved("gym:somarmtest/Refuses-v0", size=-2)


@pytest.mark.parametrize("text", ["nan", "NaN", "inf", "-inf", "Infinity"])
def test_nan_and_inf_written_as_text_read_as_numbers_as_json_numbers_do(text):
    params = tasks.make("gym:somarmtest/Keeps-v0", x=tasks.parse_params("gym:somarmtest/Keeps-v0", {"x": text})["x"],
                        y=tasks.parse_params("gym:somarmtest/Keeps-v0", {"y": "1e308"})["y"]).params
    x, y = dict(params.kwargs)["x"], dict(params.kwargs)["y"]
    assert isinstance(x, float) and isinstance(y, float)
    assert math.isnan(x) if "n" == text.lower()[0] else x == float(text)


@pytest.mark.parametrize("value", [-1, 0, 2.5, 1e22, True, "ten"])
def test_a_time_limit_or_evaluation_cap_that_is_not_a_whole_number_of_steps_is_refused(value):
    for key in ("max_episode_steps", "evaluation_steps"):
        expected = f"{key} of gym:Pendulum-v1 takes a whole number of steps >= 1, got {value!r}"
        with pytest.raises(ValueError, match="^" + re.escape(expected) + "$"):
            _resolved("gym:Pendulum-v1", **{key: value})


def test_render_mode_is_refused_in_one_line():
    with pytest.raises(ValueError, match=r"^render_mode='human' is not taken by gym:Pendulum-v1: .*; leave it out$"):
        _resolved("gym:Pendulum-v1", render_mode="human")


@pytest.mark.parametrize("name", ["gym:../../etc/passwd", "gym:Pendulum-v1/../x", "gym:a b"])
def test_a_malformed_id_is_one_line_value_error(name):
    with pytest.raises(ValueError, match=r"^gym:.* is not an environment Gymnasium can make \(Error: Malformed "
                                         r"environment ID: .*\); give a registered id, such as gym:Pendulum-v1$"):
        tasks.record(name)


def test_infinite_bounds_with_non_finite_observations_are_said_to_be_so():
    with pytest.raises(ValueError) as refused:
        _resolved("gym:somarmtest/Unbounded-v0")
    message = str(refused.value)
    assert "observation Box is infinite in dimension(s) [0, 1]" in message and "non-finite observations" in message
    assert "takes a JSON list" not in message  # not a key the user never gave


def test_greedy_episodes_are_cut_at_the_evaluation_cap_below_a_long_time_limit(monkeypatch):
    config = _resolved("gym:somarmtest/Keeps-v0", max_episode_steps=100_000, evaluation_steps=7)
    result = run.train(config, progress=False)
    greedy = run.greedy_summary(result)
    assert greedy["greedy_mean_episode_length"] == 7
    assert greedy["greedy_episodes_cut"] == 100 and greedy["greedy_episode_cap"] == 7
    monkeypatch.setattr(gym_envs, "EVALUATION_STEPS", 9)  # the default cap
    task = tasks.make("gym:somarmtest/Keeps-v0", max_episode_steps=100_000)
    episodes = task.run_episodes(lambda x: np.zeros((len(x), 1)), np.arange(3))
    assert episodes["length"].tolist() == [9, 9, 9] and episodes["cut"].all()
    within = tasks.make("gym:somarmtest/Keeps-v0").run_episodes(lambda x: np.zeros((len(x), 1)), np.arange(2))
    assert within["length"].tolist() == [5, 5] and not within["cut"].any()  # its own limit ends them
