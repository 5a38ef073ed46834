import numpy as np
import pytest

from somarm.streams import UniformStreams, trial_generators, trial_ids_for


def test_trial_alone_equals_trial_in_batch():
    batch = UniformStreams(3, trial_ids_for(5), "learner", 4, block=7)
    alone = UniformStreams(3, trial_ids_for(1, [3]), "learner", 4, block=3)
    rows_batch = np.stack([batch.next().copy() for _ in range(20)])
    rows_alone = np.stack([alone.next().copy() for _ in range(20)])
    np.testing.assert_array_equal(rows_batch[:, 3], rows_alone[:, 0])


def test_purposes_and_seeds_differ():
    ids = trial_ids_for(2)
    a = UniformStreams(0, ids, "learner", 3).next().copy()
    b = UniformStreams(0, ids, "task", 3).next().copy()
    c = UniformStreams(1, ids, "learner", 3).next().copy()
    assert not np.array_equal(a, b) and not np.array_equal(a, c)
    assert not np.array_equal(a[0], a[1])


def test_state_round_trip_continues_exactly():
    s = UniformStreams(9, trial_ids_for(3), "task", 2, block=4)
    for _ in range(6):
        s.next()
    state = s.get_state()
    expected = np.stack([s.next().copy() for _ in range(10)])
    t = UniformStreams(9, trial_ids_for(3), "task", 2, block=4)
    t.set_state(state)
    got = np.stack([t.next().copy() for _ in range(10)])
    np.testing.assert_array_equal(expected, got)


@pytest.mark.parametrize(
    "n_trials, ids, match",
    [(0, None, "n_trials"), (2, [1], "trial_ids"), (2, [-1, 0], "trial_ids")],
)
def test_bad_trial_ids(n_trials, ids, match):
    with pytest.raises(ValueError, match=match):
        trial_ids_for(n_trials, ids)


def test_streams_that_go_on_from_a_step_are_their_own_and_step_0_is_the_start():
    ids = np.arange(3)
    start = [g.random(4) for g in trial_generators(7, ids, "task")]
    again = [g.random(4) for g in trial_generators(7, ids, "task", start=0)]
    later = [g.random(4) for g in trial_generators(7, ids, "task", start=500)]
    np.testing.assert_array_equal(start, again)
    assert not np.isclose(np.array(start), np.array(later)).any()


@pytest.mark.parametrize("name", ["reach2", "reach2_obstacle"])
def test_a_task_continued_at_a_step_meets_new_starts_and_at_step_0_the_same(name):
    from somarm import tasks

    fresh = tasks.make(name, n_trials=2, seed=3).reset()
    same, later = tasks.make(name, n_trials=2, seed=3), tasks.make(name, n_trials=2, seed=3)
    same.continue_at(0)
    later.continue_at(1000)
    np.testing.assert_array_equal(same.reset(), fresh)
    assert later.t == 1000 and not np.isclose(later.reset(), fresh).all(axis=1).any()
