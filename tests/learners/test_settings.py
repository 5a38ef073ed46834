"""Learner settings by key: text read once into typed values, typed values applied and checked."""

from __future__ import annotations

import pytest

from somarm.learners import presets
from somarm.learners.motoric import MotoricConfig
from somarm.learners.schedules import Constant, ExponentialDecay, InverseDecay, Schedule
from somarm.learners.settings import (
    allowed_keys,
    apply_settings,
    format_setting,
    format_settings,
    parse_settings,
)
from somarm.learners.somq import SOMQConfig
from somarm.learners.tabular import TabularConfig

#: The same settings as ``--set`` text and as the typed values the Python API takes.
TEXT = {"decay": "exp:0.9985", "alpha": "0.5", "p.floor": "0.05", "epsilon.scale": "0.3", "n_a.decay": "inv:100",
        "neighbourhood_q": "false", "input_shape": "10x10", "action_shape": "30", "gamma": "0.9",
        "noise": "gaussian", "input_init": "0:1", "response": "interpolated", "periodic_actions": "true"}
TYPED = {"decay": ExponentialDecay(0.9985), "alpha": 0.5, "p.floor": 0.05, "epsilon.scale": 0.3,
         "n_a.decay": InverseDecay(100.0), "neighbourhood_q": False, "input_shape": (10, 10), "action_shape": (30,),
         "gamma": 0.9, "noise": "gaussian", "input_init": (0.0, 1.0), "response": "interpolated",
         "periodic_actions": True}


def test_text_is_read_into_exactly_the_typed_values():
    parsed = parse_settings(SOMQConfig, TEXT)
    assert parsed == TYPED
    assert all(type(parsed[key]) is type(value) for key, value in TYPED.items())


def test_typed_changes_equal_the_text_ones_field_for_field():
    base = presets.get("table1")
    changed = base.with_changes(TYPED)
    assert changed == base.with_overrides(TEXT) == apply_settings(base, parse_settings(SOMQConfig, TEXT))
    assert changed.alpha == Schedule(0.5, ExponentialDecay(0.9985))
    assert changed.n_a.decay == InverseDecay(100.0) and changed.lambda_s.decay == ExponentialDecay(0.9985)
    assert changed.p.floor == 0.05 and changed.epsilon.scale == 0.3 and changed.input_shape == (10, 10)


def test_whole_numbers_become_floats_where_a_number_is_wanted():
    changed = presets.get("table5").with_changes({"n_a": 25, "gamma": 0})
    assert changed.n_a.scale == 25.0 and type(changed.n_a.scale) is float and type(changed.gamma) is float


@pytest.mark.parametrize("value", [0.1, 2.0, 1e-7, 1e308, 0.99985, True, False, None, (10, 10), (30,),
                                   (0.0, 1.0), (-0.5, 2.5), "gaussian", InverseDecay(1000.0),
                                   ExponentialDecay(0.9997), Constant()])
def test_text_written_from_a_value_reads_back_to_the_same_value(value):
    keys = {float: "gamma", bool: "neighbourhood_q", str: "noise", InverseDecay: "decay",
            ExponentialDecay: "decay", Constant: "decay", type(None): "input_init"}
    key = keys.get(type(value)) or ("input_init" if isinstance(value[0], float) else "input_shape")
    if key == "gamma" and value > 1:
        key = "alpha.floor"
    text = format_setting(value)
    assert parse_settings(SOMQConfig, {key: text}) == {key: value}


def test_text_is_as_short_as_the_command_line_form():
    assert format_settings(TYPED) == {**TEXT, "input_init": "0:1", "decay": "exp:0.9985"}
    assert format_setting(InverseDecay(250.0)) == "inv:250" and format_setting(1.0) == "1"


@pytest.mark.parametrize("changes, match", [
    ({"epsilon": "0.2"}, r"^epsilon must be a number, got the text '0.2' \(parse text with parse_settings\)$"),
    ({"decay": "inv:1000"}, r"^decay must be a Decay \(InverseDecay, ExponentialDecay or Constant; "
                            r"schedules.parse_decay reads"),
    ({"neighbourhood_q": "false"}, "^neighbourhood_q must be True or False, got the text 'false'"),
    ({"neighbourhood_q": 0}, "^neighbourhood_q must be True or False, got 0$"),
    ({"input_shape": "10x10"}, "^input_shape must be a tuple of 1 or 2 whole numbers"),
    ({"gamma": True}, "^gamma must be a number, got True$"),
    ({"alpha": -1.0}, "^alpha must be >= 0"),
    ({"p": 1.5}, r"^p=1.5: p must be a probability in \[0, 1\]"),
    ({"gamma": 2}, "^gamma=2: gamma must be <= 1"),
    ({"noise": "pink"}, "^noise=pink: noise must be 'uniform' or 'gaussian'"),
    ({"beta": 1.0}, "^unknown key 'beta'; allowed keys: decay, alpha\\[.scale|.floor|.decay\\]"),
    ({"alpha.": 1.0}, "^unknown key 'alpha.'"),
])
def test_a_bad_typed_setting_is_one_line_naming_the_key(changes, match):
    with pytest.raises(ValueError, match=match) as info:
        SOMQConfig().with_changes(changes)
    assert "\n" not in str(info.value)


def test_each_config_takes_its_own_keys():
    assert "neighbourhood_values" in allowed_keys(MotoricConfig) and "p[" not in allowed_keys(MotoricConfig)
    with pytest.raises(ValueError, match="unknown key 'p'"):
        MotoricConfig().with_changes({"p": 0.5})
    assert allowed_keys(TabularConfig) == "decay, epsilon[.scale|.floor|.decay], observation_bins, action_bins, " \
                                          "alpha, gamma"


def test_tabular_settings_go_through_the_same_parser():
    parsed = parse_settings(TabularConfig, {"observation_bins": "8", "alpha": "none", "epsilon.floor": "0.1",
                                            "gamma": "0.5"})
    assert parsed == {"observation_bins": 8, "alpha": None, "epsilon.floor": 0.1, "gamma": 0.5}
    changed = TabularConfig().with_changes({**parsed, "alpha": 0.25})
    assert (changed.observation_bins, changed.alpha, changed.epsilon.floor, changed.gamma) == (8, 0.25, 0.1, 0.5)
    for texts, match in (({"observation_bins": "4.5"}, "^observation_bins=4.5: observation_bins must be a whole"),
                         ({"alpha": "fast"}, "^alpha=fast: alpha must be a number or none$"),
                         ({"action_bins": "0"}, "^action_bins=0: action_bins must be")):
        with pytest.raises(ValueError, match=match):
            TabularConfig().with_overrides(texts)
    with pytest.raises(ValueError, match="^observation_bins must be a whole number, got 4.5$"):
        TabularConfig().with_changes({"observation_bins": 4.5})


def test_a_change_a_later_one_makes_good_is_taken_in_either_order_and_one_never_made_good_is_named():
    linear = SOMQConfig().with_changes({"local_linear": True, "shared_slopes": True})
    for changes in ({"local_linear": False, "shared_slopes": False}, {"shared_slopes": False, "local_linear": False}):
        plain = linear.with_changes(changes)
        assert (plain.local_linear, plain.shared_slopes) == (False, False)
    with pytest.raises(ValueError, match="^local_linear=false: shared_slopes needs local_linear=true"):
        linear.with_changes({"local_linear": False, "gamma": 0.5})
    with pytest.raises(ValueError, match="^gamma=2: gamma must be <= 1"):
        linear.with_changes({"local_linear": False, "shared_slopes": False, "gamma": 2})
