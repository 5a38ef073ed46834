"""The training hook: stream the trial being trained to the browser, throttled, never blocking.

``update`` is called after every training step. When throttled it only reads the clock
(about 0.2 microseconds). Otherwise it packs one trial's numbers (a few hundred bytes) and
pushes them to the viewer's server without waiting (``zmq.NOBLOCK``); the server process
turns the newest frame into meshcat commands and drops frames it had no time for
(``feed.py``). Nothing in the training process waits on the server or the browser, and no
thread competes with training for the GIL (a background thread cost 30% of training speed
when we measured it). If the server dies, ``update`` notices within a second, warns once,
and from then on only reads the clock.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from somarm.run.progress import end_line
from somarm.validation import check_int, check_number
from somarm.viewer.client import ViewerUnavailableWarning

__all__ = ["LiveView", "pack_frame"]

_HEALTH_CHECK_S = 1.0


def pack_frame(step: int, observation, action, reward) -> bytes:
    """One frame for the server's feed: float64 ``[step, reward, obs_dim, *observation, *action]``."""
    observation, action = np.ravel(observation), np.ravel(action)
    head = np.array([step, reward, observation.size], dtype=np.float64)
    return np.concatenate([head, observation, action]).tobytes()


class LiveView:
    """Live meshcat view of one trial of a training run.

    Args:
      task_name: registered task (``reach2``, ``reach20``, ``four_goals``, ``throw``, ...).
      host: address the page listens on (127.0.0.1: this machine only).
      port: web port; None picks a free one.
      max_rate_hz: at most this many frames a second are pushed. 30 looks smooth; the cost
        to training is measured by ``somarm bench viewer`` (about 1% when we measured it).
      trial: which trial of the batch is shown.
      task_params: the run's task parameters, so goals and targets are drawn where training
        puts them.

    Attributes:
      url: the page to open.
      frames_sent: frames pushed to the server (it may still drop stale ones).
      alive: False once the server died (viewing is then off; training carries on).

    Example::

        with LiveView("reach2") as view:
            print("open", view.url)
            train(config, on_step=view.update)

    Raises:
      ValueError: unknown task, bad rate or trial; RuntimeError: the server did not start.
    """

    def __init__(
        self,
        task_name: str,
        *,
        host: str = "127.0.0.1",
        port: int | None = None,
        max_rate_hz: float = 30.0,
        trial: int = 0,
        task_params: dict | None = None,
    ) -> None:
        import zmq

        from somarm import tasks
        from somarm.viewer.server import MeshcatServer, stop_on_signals

        tasks.record(task_name)  # an unknown task fails here, before a server starts
        rate = check_number("max_rate_hz", max_rate_hz, minimum=0.0, strict_minimum=True)
        self.trial = check_int("trial", trial, minimum=0)
        self._period = 1.0 / rate
        self._server = MeshcatServer(host=host, port=port, live_task=task_name, task_params=task_params).start()
        stop_on_signals(self._server)
        self.url: str = self._server.web_url
        self._zmq = zmq
        self._socket = zmq.Context.instance().socket(zmq.PUSH)
        self._socket.setsockopt(zmq.CONFLATE, 1)  # at most the newest frame waits in our queue
        self._socket.setsockopt(zmq.LINGER, 0)  # closing never waits for the server
        self._socket.connect(self._server.feed_url)
        self.frames_sent = 0
        self.alive = True
        self._next_time = 0.0
        self._next_check = time.perf_counter() + _HEALTH_CHECK_S

    def update(self, step: int, observations: np.ndarray, actions: np.ndarray, rewards: np.ndarray) -> None:
        """Offer the state after a training step; returns at once, whatever the server does.

        Args:
          step: steps done so far.
          observations: ``(n_trials, obs_dim)``.
          actions: ``(n_trials, action_dim)``.
          rewards: ``(n_trials,)``.

        Raises:
          ValueError: the batch has no trial ``trial`` (checked on the first frame).
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
        frame = pack_frame(step, observations[k], actions[k], rewards[k])
        try:
            self._socket.send(frame, self._zmq.NOBLOCK)
            self.frames_sent += 1
        except self._zmq.Again:  # the server is not taking frames right now: drop this one
            pass

    def _switch_off(self, reason: str) -> None:
        self.alive = False
        end_line()  # the warning gets a line of its own, not the end of the progress bar's
        warnings.warn(f"the meshcat viewer's server {reason}; viewing is off, training carries on",
                      ViewerUnavailableWarning, stacklevel=3)

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
