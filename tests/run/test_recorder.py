"""``run.recorder.BlockRecorder``, ``run.snapshots`` and ``run.stepper``: the parts of the training loop."""

from types import SimpleNamespace

import numpy as np

from somarm import run
from somarm.run.recorder import BlockRecorder
from somarm.run.snapshots import Snapshots
from somarm.run.stepper import Stepper


def _one_step_tasks(*n_trials):
    return [SimpleNamespace(n_trials=n, episodic=False) for n in n_trials]


def test_each_block_is_the_mean_and_mean_square_of_its_steps_rewards():
    recorder = BlockRecorder(_one_step_tasks(2, 1), n_steps=7, block=3)
    rng = np.random.default_rng(0)
    rewards = rng.uniform(-1, 0, (7, 3))
    ends = [recorder.record(r) for r in rewards]
    assert ends == [False, False, True, False, False, True, False]
    means, squares, episodes = recorder.curves()
    np.testing.assert_allclose(means, rewards[:6].reshape(2, 3, 3).mean(axis=1))
    np.testing.assert_allclose(squares, (rewards[:6] ** 2).reshape(2, 3, 3).mean(axis=1))
    assert episodes is None and recorder.measures == means[-1].mean()


def test_snapshots_are_copies_taken_only_at_the_steps_asked_for():
    learner = SimpleNamespace(learned_arrays=("q",), q=np.zeros(2))
    snapshots = Snapshots([learner], at=(2,))
    for step in (1, 2, 3):
        learner.q += 1
        snapshots.after(step)
    assert list(snapshots.taken[0]) == [2]
    np.testing.assert_array_equal(snapshots.taken[0][2]["q"], [2, 2])  # a copy: later steps leave it


def test_the_stepper_gives_each_learner_its_own_trials_and_the_rewards_side_by_side():
    group = run.RunGroup([run.RunConfig(task="reach2", n_trials=2, n_steps=5, block=1, seed=1),
                          run.RunConfig(task="reach2", n_trials=3, n_steps=5, block=1, seed=2)])
    stepper = Stepper(group.tasks, group.learners, group.parts, group.owners)
    rewards = stepper.step()
    assert rewards.shape == (5,) and (rewards <= 0).all()
    for task, actions in zip(group.tasks, stepper.actions, strict=True):
        assert actions.shape == (task.n_trials, task.action_low.size)
