"""The training hook: stream the trial being trained to the browser, throttled, never blocking.

``update`` is called after every training step. When throttled it only reads the clock
(well under a microsecond); otherwise it copies one trial's row and hands it to a background
thread, which turns the newest frame into meshcat commands and sends them in one round trip.
A frame not yet sent when a newer one arrives is dropped. If the server dies the client
times out once, warns once, and from then on ``update`` only reads the clock.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from somarm.validation import check_int, check_number

__all__ = ["LiveView"]


def _own_task(task_name: str, task_params: dict | None):
    """A one-trial task of our own, or None when the tasks cannot make it (then the show guesses)."""
    try:
        from somarm import tasks

        return tasks.make(task_name, n_trials=1, **(task_params or {}))
    except (ImportError, AttributeError):  # no task registry yet: fall back on the models' conventions
        return None


class LiveView:
    """Live meshcat view of one trial of a training run.

    Args:
      task_name: registered task (``reach2``, ``reach20``, ``four_goals``, ``throw``, ...).
      host: address the page listens on (127.0.0.1: this machine only).
      port: web port; None picks a free one.
      max_rate_hz: at most this many frames a second reach the browser. Rule of thumb: 30
        looks smooth and costs the training loop well under 5% (see ``somarm bench viewer``
        in the notes); lower it on a loaded machine.
      trial: which trial of the batch is shown.
      timeout_s: longest wait for the server before the viewer switches itself off.
      task_params: the run's task parameters, so goals and targets are drawn where training
        puts them (the viewer builds its own task object; it never touches the training's).

    Attributes:
      url: the page to open.
      frames_sent: frames that reached the server.

    Example::

        with LiveView("reach2") as view:
            print("open", view.url)
            train(config, on_step=view.update)
    """

    def __init__(
        self,
        task_name: str,
        *,
        host: str = "127.0.0.1",
        port: int | None = None,
        max_rate_hz: float = 30.0,
        trial: int = 0,
        timeout_s: float = 2.0,
        task_params: dict | None = None,
    ) -> None:
        from somarm.viewer.client import MeshcatClient
        from somarm.viewer.server import MeshcatServer, stop_on_signals
        from somarm.viewer.shows import show_for_task

        rate = check_number("max_rate_hz", max_rate_hz, minimum=0.0, strict_minimum=True)
        self.trial = check_int("trial", trial, minimum=0)
        self._period = 1.0 / rate
        self._task = _own_task(task_name, task_params)
        self._stream = show_for_task(task_name, self._task)  # fails fast on an unknown task, before any server
        self._server = MeshcatServer(host=host, port=port).start()
        stop_on_signals(self._server)
        self.url: str = self._server.web_url
        self._client = MeshcatClient(self._server.zmq_url, timeout_s=timeout_s)
        self.frames_sent = 0
        self._next_time = 0.0
        self._latest: tuple | None = None
        self._wake = threading.Event()
        self._closed = False
        self._thread = threading.Thread(target=self._run, name="somarm-live-view", daemon=True)
        self._thread.start()

    def update(self, step: int, observations: np.ndarray, actions: np.ndarray, rewards: np.ndarray) -> None:
        """Offer the state after a training step; returns at once.

        Args:
          step: steps done so far.
          observations: ``(n_trials, obs_dim)``.
          actions: ``(n_trials, action_dim)``.
          rewards: ``(n_trials,)``.
        """
        now = time.perf_counter()
        if now < self._next_time:
            return
        self._next_time = now + self._period
        k = self.trial
        # Copies of one row: the training loop may reuse its arrays after we return.
        self._latest = (step, np.array(observations[k], dtype=np.float64),
                        np.array(actions[k], dtype=np.float64), float(rewards[k]))
        self._wake.set()

    def _run(self) -> None:
        client = self._client
        client.send_batch(self._stream.setup())
        while not self._closed and not client.dead:
            self._wake.wait(timeout=0.25)
            self._wake.clear()
            frame, self._latest = self._latest, None
            if frame is None:
                continue
            step, observation, action, reward = frame
            if hasattr(self._task, "set_step"):
                self._task.set_step(step)  # four_goals: the goals move at a given step
            if client.send_batch(self._stream.frame(observation, action, reward)):
                self.frames_sent += 1

    @property
    def alive(self) -> bool:
        """False once the server stopped answering (viewing is then off)."""
        return not self._client.dead

    def close(self) -> None:
        """Stop the sender thread and the server. Idempotent."""
        if self._closed:
            return
        self._closed = True
        self._wake.set()
        self._thread.join(timeout=self._client.timeout_ms / 1000 + 1.0)
        self._client.close()
        self._server.stop()

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
