"""The training hook: show the greedy policy of the trial being trained on a fixed cycle of goals.

Every training step calls ``update``; it samples the shown trial's reward at most ``max_rate_hz``
times a second (throttled it only reads the clock, well under a microsecond) and once per
``hold_s`` it pushes the step and the running mean reward to the viewer's server without waiting
(``zmq.NOBLOCK``), with the policy's greedy answers to a fixed cycle of goals (one ``predict`` call
for the whole cycle; for a task of episodes, one greedy episode, and the next only once that one
has played; for a MuJoCo environment, one greedy rollout likewise). The server (``feed.py``) shows the goals one after
another, each held ``hold_s`` (a throw or an episode as long as it lasts), so a single reach can
be followed while the policy improves behind it; when training ends, ``finish`` sends the final
policy and the page says "training finished" and keeps showing it.

Nothing in the training process waits on the server or the browser, and no thread competes with
training for the GIL (a background thread cost 30% of training speed when we measured it). If the
server dies, ``update`` notices within a second, warns once, and from then on only reads the clock.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable

import numpy as np
import umsgpack

from somarm.run.progress import end_line
from somarm.validation import check_int, check_number
from somarm.viewer.client import ViewerUnavailableWarning

__all__ = ["LiveView", "greedy_policy", "pack_snapshot"]

_HEALTH_CHECK_S = 1.0
#: The warnings registry of ``LiveView``'s one-line warning (each said once per process, as ``warnings.warn``'s).
_WARNED: dict = {}
#: The running mean reward is over the last this many sampled steps of the shown trial.
_REWARD_WINDOW = 90
#: A path's frames play at 50 a second, every second 0.01 s timestep (motion.py).
_PATH_SECONDS_PER_TIMESTEP = 0.01


def greedy_policy(learner, trial: int = 0) -> Callable[[np.ndarray], np.ndarray]:
    """``policy(observations (n, obs_dim)) -> (n, action_dim)``: the greedy actions of one trial of ``learner``."""

    def policy(observations: np.ndarray) -> np.ndarray:
        observations = np.asarray(observations, dtype=np.float64)
        batch = np.broadcast_to(observations, (learner.n_trials, *observations.shape)).copy()
        return np.asarray(learner.predict(batch))[trial]

    return policy


def pack_snapshot(snapshot: dict) -> bytes:
    """The bytes ``feed.unpack_snapshot`` reads: msgpack of the dict, arrays as nested lists."""

    def plain(value):
        if isinstance(value, np.ndarray):
            return value.tolist()
        if isinstance(value, np.generic):
            return value.item()
        if isinstance(value, dict):
            return {k: plain(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [plain(v) for v in value]
        return value

    return umsgpack.packb(plain(snapshot))


class _Goals:
    """A one-step task: the greedy actions for a fixed cycle of observations (or the latest training row)."""

    kind = "goals"

    def __init__(self, task, policy, observations: np.ndarray) -> None:
        self.policy = policy
        self.observations = observations

    def items(self, row) -> tuple[dict, float]:
        if self.policy is None:  # no policy: the action being tried on the latest observation
            observation, action = row
            return {"observations": [observation], "actions": [action], "greedy": False}, 0.0
        return {"observations": self.observations, "actions": np.asarray(self.policy(self.observations)),
                "greedy": True}, 0.0

    def final(self) -> dict:
        return self.items(None)[0] if self.policy is not None else {}


class _Episodes:
    """A task of episodes: one greedy episode per snapshot, from each start of the cycle in turn."""

    kind = "paths"

    def __init__(self, task, policy, starts: np.ndarray) -> None:
        self.task = task
        self.policy = policy
        self.starts = starts
        self.k = 0

    def _episodes(self, indices: list[int]) -> dict:
        starts = self.starts[indices]
        episodes = self.task.run_episodes(self.policy, starts, paths=True)
        ends = 1 + episodes["length"] * self.task.control_steps
        paths = [episodes["path"][i, : ends[i]] for i in range(len(indices))]
        return {"observations": starts, "paths": paths, "indices": indices, "of": len(self.starts), "greedy": True}

    def items(self, row) -> tuple[dict, float]:
        if self.policy is None:
            return {}, 0.0
        snapshot = self._episodes([self.k % len(self.starts)])
        self.k += 1
        return snapshot, len(snapshot["paths"][0]) * _PATH_SECONDS_PER_TIMESTEP

    def final(self) -> dict:
        return self._episodes(list(range(len(self.starts)))) if self.policy is not None else {}


class _Rollouts:
    """Any MuJoCo environment (``.unwrapped.model`` / ``.data``): one greedy episode per snapshot."""

    kind = "states"

    def __init__(self, env, policy, max_steps: int, seed: int) -> None:
        self.env = env
        self.policy = policy
        self.max_steps = max_steps
        self.seed = seed
        self.k = 0

    def _episode(self) -> tuple[dict, float]:
        from somarm.viewer.model_view import rollout

        done = rollout(self.env, self.policy, n_steps=self.max_steps, seed=self.seed + self.k, until_done=True)
        self.k += 1
        return {"paths": [done.qpos], "rewards": [done.rewards], "timestep": done.timestep, "index": self.k,
                "greedy": self.policy is not None}, len(done.qpos) * done.timestep

    def items(self, row) -> tuple[dict, float]:
        return self._episode()

    def final(self) -> dict:
        return self._episode()[0]


class LiveView:
    """Live meshcat view of the greedy policy of one trial while it trains.

    Args:
      task_name: registered task (``reach2``, ``reach20``, ``four_goals``, ``throw``, ...), or None
        with ``env``.
      policy: ``policy(observations (n, obs_dim)) -> actions (n, action_dim)``, the greedy policy
        of the trial shown (``greedy_policy(learner, trial)``); None shows the action being tried on
        the latest training row instead (and a task of episodes shows nothing until ``finish``).
      env: instead of a task, a Gymnasium-style MuJoCo environment (its ``unwrapped`` has ``model``
        and ``data``); ``policy`` then maps one observation to one action. The viewer steps this
        environment itself (not the one being trained), one greedy episode per snapshot.
      host: address the page listens on (127.0.0.1: this machine only).
      port: web port; None picks a free one.
      hold_s: seconds each goal of the cycle is shown; the greedy answers are asked for at most once per hold.
      n_goals: goals (or episode starts) in the cycle, drawn once from the ``viewer`` stream of ``seed``.
      max_rate_hz: at most this many training steps a second are sampled for the running mean reward.
      trial: which trial of the batch is shown (its rewards are sampled; ``policy`` should be its).
      task_params: the run's task parameters, so goals and targets are drawn where training puts them.
      seed: the seed of the cycle's goals.
      n_steps: the run's length, for the text ("step 1,200 of 50,000").
      lines: lines about the run for the page (learner, trial, seed).
      max_episode_steps: with ``env``, the longest greedy episode shown.

    Attributes:
      url: the page to open.
      frames_sent: snapshots pushed to the server (it may still drop stale ones).
      alive: False once the server died (viewing is then off; training carries on).

    Example::

        group = RunGroup([config])
        with LiveView("reach2", policy=greedy_policy(group.learners[0])) as view:
            print("open", view.url)
            group.train(on_step=view.update)
            view.finish()

    Raises:
      ValueError: unknown task, bad rate, hold or trial; RuntimeError: the server did not start.
    """

    def __init__(
        self,
        task_name: str | None = None,
        *,
        policy: Callable[[np.ndarray], np.ndarray] | None = None,
        env=None,
        host: str = "127.0.0.1",
        port: int | None = None,
        hold_s: float = 0.75,
        n_goals: int = 8,
        max_rate_hz: float = 30.0,
        trial: int = 0,
        task_params: dict | None = None,
        seed: int = 0,
        n_steps: int | None = None,
        lines: list[str] | None = None,
        max_episode_steps: int = 1000,
    ) -> None:
        import zmq

        from somarm.viewer.server import MeshcatServer, stop_on_signals

        if (task_name is None) == (env is None):
            raise ValueError("LiveView takes a task name or an env (with .unwrapped.model/.data), one of them")
        rate = check_number("max_rate_hz", max_rate_hz, minimum=0.0, strict_minimum=True)
        self.hold_s = check_number("hold_s", hold_s, minimum=0.0, strict_minimum=True)
        self.trial = check_int("trial", trial, minimum=0)
        check_int("n_goals", n_goals, minimum=1)
        self.n_steps = n_steps
        self.lines = list(lines or [])
        self._period = 1.0 / rate
        if env is not None:
            self.name = str(getattr(getattr(env, "spec", None), "id", None) or "MuJoCo model")
            self._source = _Rollouts(env, policy, check_int("max_episode_steps", max_episode_steps, minimum=1), seed)
            server = MeshcatServer(host=host, port=port, title=self.name, live_model=env.unwrapped.model)
        else:
            self.name = task_name
            self._source = _task_source(task_name, policy, n_goals, seed, task_params)
            server = MeshcatServer(host=host, port=port, title=task_name, live_task=task_name,
                                   task_params=task_params)
        self._server = server.start()
        stop_on_signals(self._server)
        self.url: str = self._server.web_url
        self._zmq = zmq
        self._socket = zmq.Context.instance().socket(zmq.PUSH)
        self._socket.setsockopt(zmq.CONFLATE, 1)  # at most the newest snapshot waits in our queue
        self._socket.setsockopt(zmq.LINGER, 0)  # closing never waits for the server
        self._socket.connect(self._server.feed_url)
        self.frames_sent = 0
        self.alive = True
        self._next_time = 0.0
        self._next_send = 0.0
        self._next_items = 0.0
        self._next_check = time.perf_counter() + _HEALTH_CHECK_S
        self._rewards = np.full(_REWARD_WINDOW, np.nan)
        self._n_rewards = 0
        self._step = 0
        self._row = None

    def update(self, step: int, observations: np.ndarray, actions: np.ndarray, rewards: np.ndarray) -> None:
        """Offer the state after a training step; returns at once, whatever the server does.

        Args:
          step: steps done so far.
          observations: ``(n_trials, obs_dim)``.
          actions: ``(n_trials, action_dim)``.
          rewards: ``(n_trials,)``.

        Raises:
          ValueError: the batch has no trial ``trial`` (checked on the first sample).
        """
        now = time.perf_counter()
        if now < self._next_time:
            return
        self._next_time = now + self._period
        if not self.alive:
            return
        if now >= self._next_check:
            self._next_check = now + _HEALTH_CHECK_S
            if not self._server.alive():
                self._switch_off("stopped")
                return
        k = self.trial
        if k >= len(rewards):
            raise ValueError(f"LiveView trial={k} is not in this batch of {len(rewards)} trial(s)")
        self._rewards[self._n_rewards % _REWARD_WINDOW] = rewards[k]
        self._n_rewards += 1
        self._step = step
        self._row = (np.array(observations[k], dtype=np.float64), np.array(actions[k], dtype=np.float64))
        if now >= self._next_send:  # the step and the reward once per hold; new answers once the last have played
            self._next_send = now + self.hold_s
            items = {}
            if now >= self._next_items:
                items, duration = self._source.items(self._row)
                self._next_items = time.perf_counter() + max(self.hold_s, duration)
            self._push(items, finished=False)

    def _push(self, items: dict, *, finished: bool) -> None:
        window = min(self._n_rewards, _REWARD_WINDOW)
        snapshot = {"kind": self._source.kind, "name": self.name, "step": self._step, "n_steps": self.n_steps,
                    "finished": finished, "trial": self.trial, "lines": self.lines, "hold_s": self.hold_s,
                    "mean_reward": float(np.nanmean(self._rewards)) if window else None, "window": window,
                    "items": items}
        try:
            self._socket.send(pack_snapshot(snapshot), self._zmq.NOBLOCK)
            self.frames_sent += 1
        except self._zmq.Again:  # the server is not taking snapshots right now: drop this one
            pass

    def finish(self, step: int | None = None) -> None:
        """Training is over: send the final policy's answers for the whole cycle; the page says so and keeps them."""
        if not self.alive or self._socket.closed:
            return
        if step is not None:
            self._step = step
        self._push(self._source.final(), finished=True)

    def set_policy(self, policy: Callable[[np.ndarray], np.ndarray] | None) -> None:
        """Show another policy's greedy answers from now on (a new learner trained on the same task)."""
        self._source.policy = policy
        self._next_items = 0.0

    def serving(self) -> bool:
        """True while the viewer's server runs (and viewing has not been switched off)."""
        return self.alive and self._server.alive()

    def _switch_off(self, reason: str) -> None:
        self.alive = False
        end_line()  # the warning gets a line of its own, not the end of the progress bar's
        # One line: given as from "somarm", the warning shows no line of source code beneath it.
        warnings.warn_explicit(f"the meshcat viewer's server {reason}; viewing is off, training carries on",
                               ViewerUnavailableWarning, filename="somarm", lineno=0, module=__name__,
                               registry=_WARNED)

    def close(self) -> None:
        """Stop the server and close the socket. Idempotent."""
        if not self._socket.closed:
            self._socket.close(linger=0)
        self._server.stop()
        self.alive = False

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _task_source(task_name: str, policy, n_goals: int, seed: int, task_params: dict | None):
    """The cycle of a registered task: its goals (or episode starts), drawn as ``somarm view`` draws them."""
    from somarm.streams import trial_generators
    from somarm.viewer.feed import own_task
    from somarm.viewer.sessions import sweep_order

    task = own_task(task_name, task_params)  # an unknown task fails here, before a server starts
    rng = trial_generators(seed, np.array([0]), "viewer")[0]
    observations = np.asarray(task.sample_observations(rng, n_goals), dtype=np.float64)
    if task.episodic:
        return _Episodes(task, policy, observations)
    return _Goals(task, policy, observations[sweep_order(observations)])
