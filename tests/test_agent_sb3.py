"""``SOMQ`` under Stable-Baselines3's contracts: evaluate_policy, callbacks, get_env/set_env, load(env),
and environments wrapped after ``gymnasium.make`` trained in as given."""

import gymnasium
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
from stable_baselines3 import SAC  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback, EvalCallback  # noqa: E402
from stable_baselines3.common.evaluation import evaluate_policy  # noqa: E402
from stable_baselines3.common.monitor import Monitor  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv  # noqa: E402

from somarm import SOMQ  # noqa: E402


class Recorder(BaseCallback):
    """Records every call SB3 makes on a callback, and stops when ``num_timesteps`` reaches ``stop_at``."""

    def __init__(self, stop_at=None):
        super().__init__()
        self.calls, self.steps, self.stop_at = [], [], stop_at

    def _on_training_start(self):
        self.calls.append("training_start")
        self.total = self.locals["total_timesteps"]

    def _on_rollout_start(self):
        self.calls.append("rollout_start")

    def _on_step(self):
        self.calls.append("step")
        self.steps.append(self.num_timesteps)
        assert {"new_obs", "rewards", "dones", "infos", "actions"} <= set(self.locals)
        assert self.training_env is self.model.get_env() and self.n_calls == len(self.steps)
        return self.stop_at is None or self.num_timesteps < self.stop_at

    def _on_rollout_end(self):
        self.calls.append("rollout_end")

    def _on_training_end(self):
        self.calls.append("training_end")


def test_callbacks_are_called_in_sb3s_order_with_its_counts():
    ours, theirs = Recorder(), Recorder()
    SOMQ("Pendulum-v1", seed=0).learn(20, callback=ours)
    SAC("MlpPolicy", "Pendulum-v1", learning_starts=1000, seed=0).learn(20, callback=theirs)  # no gradient step
    assert ours.calls == theirs.calls and ours.steps == theirs.steps == list(range(1, 21))
    assert ours.total == theirs.total == 20


def test_on_step_returning_false_ends_learn_after_that_step_and_the_model_learns_on(tmp_path):
    model = SOMQ("Pendulum-v1", seed=0)
    stop = Recorder(stop_at=730)
    model.learn(2000, callback=[stop])  # a list is a CallbackList
    assert model.num_timesteps == 730 and stop.calls[-1] == "training_end" and not model.interrupted
    model.save(tmp_path / "m")
    again = SOMQ.load(tmp_path / "m")
    again.learn(270, reset_num_timesteps=False)  # the curves cover every step taken, mid-block included
    assert again.num_timesteps == 1000
    again.learn(100)
    assert again.num_timesteps == 100 and again.learner.t == 1100  # counted anew; the schedules go on


def test_eval_and_checkpoint_callbacks_evaluate_and_save_loadable_models(tmp_path):
    model = SOMQ(Monitor(gymnasium.make("Pendulum-v1")), seed=0)
    evaluation = EvalCallback(Monitor(gymnasium.make("Pendulum-v1")), eval_freq=400, n_eval_episodes=2,
                              log_path=str(tmp_path / "eval"), best_model_save_path=str(tmp_path / "best"))
    checkpoint = CheckpointCallback(save_freq=500, save_path=str(tmp_path / "ck"))
    model.learn(1000, callback=CallbackList([evaluation, checkpoint]))
    assert evaluation.evaluations_timesteps == [400, 800] and np.isfinite(evaluation.best_mean_reward)
    saved = SOMQ.load(tmp_path / "ck" / "rl_model_1000_steps.zip")
    observation = np.array([0.3, -0.9, 1.5])
    assert saved.num_timesteps == 1000 and saved.predict(observation)[0] == model.predict(observation)[0]
    SOMQ.load(tmp_path / "best" / "best_model.zip").predict(observation)  # SB3's name for the folder
    halfway = SOMQ.load(tmp_path / "ck" / "rl_model_500_steps.zip")  # saved in the middle of learn
    assert halfway.num_timesteps == 500
    halfway.learn(500, reset_num_timesteps=False)  # its curves cover every step: it learns on
    assert halfway.num_timesteps == 1000
    halfway.save(tmp_path / "on")
    with np.load(tmp_path / "on" / "curves.npz") as curves:
        assert len(curves["block_means"]) * int(curves["block"]) == 1000
        # Pendulum's 200-step episodes: two before the checkpoint, two from new starts after the load
        assert curves["episode_ends"].tolist() == [200, 400, 700, 900]


def test_evaluate_policy_takes_the_model_on_a_vec_env_and_on_a_monitor_env_and_agrees_with_evaluate():
    model = SOMQ("Pendulum-v1", seed=0).learn(3000)
    vec = DummyVecEnv([lambda: Monitor(gymnasium.make("Pendulum-v1"))])
    vec.seed(11)
    returns, _ = evaluate_policy(model, vec, n_eval_episodes=30, return_episode_rewards=True)
    plain = Monitor(gymnasium.make("Pendulum-v1"))
    plain.reset(seed=12)
    mean, _ = evaluate_policy(model, plain, n_eval_episodes=5)
    ours = model.evaluate()["greedy_mean_return"]  # somarm evaluate's number: 100 episodes
    assert abs(np.mean(returns) - ours) < 4 * np.std(returns) / np.sqrt(len(returns)) + 1.0
    assert np.isfinite(mean)
    action, state = model.predict(np.zeros((3, 3), np.float32), state=None, episode_start=np.ones(3, bool))
    assert action.shape == (3, 1) and state is None


def test_a_wrapped_environment_is_trained_in_as_given():
    from gymnasium.wrappers import NormalizeObservation, RecordEpisodeStatistics, TimeLimit

    statistics = RecordEpisodeStatistics(TimeLimit(gymnasium.make("Pendulum-v1"), 50))
    monitor = Monitor(statistics)  # outermost: both write info["episode"], which only Monitor allows
    model = SOMQ(monitor, seed=0).learn(500)
    assert len(statistics.return_queue) == 10
    assert monitor.get_episode_lengths() == [50] * 10  # its own time limit, seen by its own Monitor
    ends = np.diff(np.concatenate([[0], model._episodes[0].ends]))
    np.testing.assert_allclose(monitor.get_episode_rewards(), model._episodes[0].returns, rtol=1e-5)
    assert ends.tolist() == [50] * 10
    assert isinstance(model.get_env(), VecEnv) and model.env.envs[0] is model.given_env is monitor
    normalized = SOMQ(NormalizeObservation(gymnasium.make("Pendulum-v1")), seed=0)  # an infinite Box
    low, high = normalized.config.task_params["observation_low"], normalized.config.task_params["observation_high"]
    assert all(-10 < lo < hi < 10 for lo, hi in zip(low, high, strict=True))  # estimated on a copy of it


def test_an_environment_made_without_the_view_its_preset_asks_for_is_refused_in_one_line_and_with_it_is_trained_in():
    import somarm.tasks.dmc  # noqa: F401  (registers the suite's ids)

    raw = gymnasium.make("somarm-dmc/pendulum-swingup-v0")
    with pytest.raises(ValueError, match=r"preset dmc_pendulum sees dmc:pendulum-swingup made with angles=\[\[0, 1\]\], "
                                         r"action_repeat=5; the environment given was made without angles, "
                                         r"action_repeat: make it with them") as caught:
        SOMQ(raw, seed=0)
    assert "\n" not in str(caught.value)
    seen = Monitor(gymnasium.make("somarm-dmc/pendulum-swingup-v0", angles=[[0, 1]], action_repeat=5))
    model = SOMQ(seen, seed=0).learn(400)  # two episodes of 200 decisions
    assert seen.get_episode_lengths() == [200, 200] and model.learner.input_weights.shape[-1] == 2
    with pytest.raises(ValueError, match="the environment given was made without angles, action_repeat"):
        model.set_env(raw)
    assert SOMQ(raw, seed=0, preset="dmc").task.scale_low.size == 3  # a preset that asks nothing takes it as it is


def test_load_and_set_env_take_an_environment_of_the_same_id(tmp_path):
    SOMQ("Pendulum-v1", seed=0).learn(100).save(tmp_path / "m")
    model = SOMQ.load(tmp_path / "m", env=gymnasium.make("Pendulum-v1", max_episode_steps=30))
    assert model.task.max_episode_steps == 30 and model.num_timesteps == 100
    with pytest.raises(ValueError, match="set_env takes an environment of the model's task gym:Pendulum-v1, got "
                                         "gym:MountainCarContinuous-v0"):
        model.set_env(gymnasium.make("MountainCarContinuous-v0"))
