import json

import numpy as np
import pytest

from somarm.learners.schedules import (
    Constant,
    ExponentialDecay,
    InverseDecay,
    Schedule,
    parse_decay,
    parse_shape,
)


def test_inverse_decay_formula():
    f = InverseDecay(1000)
    assert f(0) == 1.0 and f(1000) == 0.5 and f(3000) == 0.25
    np.testing.assert_allclose(f(np.arange(0, 5000, 7)), 1.0 / (np.arange(0, 5000, 7) / 1000 + 1))
    assert Schedule(20, f).value(1000) == 10.0


def test_exponential_decay_formula():
    f = ExponentialDecay(0.9985)
    t = np.arange(0, 4000, 13)
    np.testing.assert_allclose(f(t), 0.9985**t, rtol=1e-13)
    assert Schedule(15, f).value(0) == 15.0
    np.testing.assert_allclose(Schedule(15, f).value(1000), 15 * 0.9985**1000, rtol=1e-13)


def test_floor_is_never_undercut_and_binds_late():
    s = Schedule(0.1, ExponentialDecay(0.999), floor=0.05)
    t = np.arange(0, 20000, 3)
    values = s(t)
    assert values.min() == 0.05 and values[0] == 0.1
    expected = np.maximum(0.05, 0.1 * 0.999**t)
    np.testing.assert_allclose(values, expected, rtol=1e-12)
    assert s.value(692) > 0.05 and s.value(694) == 0.05  # 0.999^693 = 0.4999...


def test_scalar_and_array_paths_agree():
    for s in (Schedule(20, InverseDecay(1000)), Schedule(1, ExponentialDecay(0.9997), 0.01), Schedule(3)):
        t = np.array([0, 1, 17, 999, 12345])
        np.testing.assert_allclose([s.value(int(k)) for k in t], s(t), rtol=1e-14)


def test_readable_repr():
    assert repr(Schedule(20, InverseDecay(1000))) == "Schedule(20 x 1/(t/1000+1))"
    assert repr(Schedule(0.1, ExponentialDecay(0.999), floor=0.05)) == "Schedule(0.1 x 0.999^t, floor 0.05)"
    assert repr(Schedule(3)) == "Schedule(3)"
    assert str(Constant()) == "1"


def test_dict_round_trip_is_exact():
    for s in (Schedule(0.1, InverseDecay(1 / 3)), Schedule(2 / 3, ExponentialDecay(0.9985), floor=0.1 / 3)):
        assert Schedule.from_dict(json.loads(json.dumps(s.to_dict()))) == s


def test_parse_decay_forms():
    assert parse_decay("inv:500") == InverseDecay(500)
    assert parse_decay("exp:0.9985") == ExponentialDecay(0.9985)
    assert parse_decay("const") == Constant()
    with pytest.raises(ValueError, match="allowed: inv:TAU"):
        parse_decay("linear:3")
    assert parse_shape("x", "10x10") == (10, 10) and parse_shape("x", "30") == (30,)
    with pytest.raises(ValueError, match="input_shape"):
        parse_shape("input_shape", "0x3")


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Schedule(-1.0), "scale must be >= 0"),
        (lambda: Schedule(1.0, floor=-0.1), "floor must be >= 0"),
        (lambda: Schedule(float("nan")), "scale must be finite"),
        (lambda: InverseDecay(0), "tau must be > 0"),
        (lambda: ExponentialDecay(1.5), "c must be <= 1"),
        (lambda: Schedule(1.0)(-3), "whole number >= 0"),
        (lambda: Schedule(1.0, decay=0.5), "decay must be"),
    ],
)
def test_bad_schedules(make, match):
    with pytest.raises(ValueError, match=match):
        make()
