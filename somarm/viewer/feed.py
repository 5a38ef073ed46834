"""The server side of ``LiveView``: raw training rows in, meshcat commands out, inside the server.

The training process only packs one trial's numbers into a few bytes and pushes them without
waiting. Everything else (kinematics, meshcat commands, msgpack, websockets) runs here, in
the server process, so it never competes with training for Python's global lock: a
background *thread* in the training process did, and cost 30% of training speed at 30 Hz.

A frame is one float64 array: ``[step, reward, obs_dim, *observation, *action]``. The socket
keeps only the newest frame (``ZMQ_CONFLATE``): frames the server had no time for are dropped.
"""

from __future__ import annotations

import sys

import numpy as np
import umsgpack
import zmq
from zmq.eventloop.zmqstream import ZMQStream

__all__ = ["unpack_frame", "own_task", "attach_feed"]


def unpack_frame(data: bytes) -> tuple[int, np.ndarray, np.ndarray, float]:
    """``(step, observation, action, reward)`` from ``somarm.viewer.live.pack_frame``'s bytes.

    Raises:
      ValueError: the bytes are not a frame.
    """
    if len(data) % 8 or len(data) < 24:
        raise ValueError(f"a frame is a float64 array of at least 3 values, got {len(data)} bytes")
    values = np.frombuffer(data, dtype=np.float64)
    obs_dim = int(values[2])
    if not 0 < obs_dim < values.size - 3:
        raise ValueError(f"frame says obs_dim={obs_dim} but carries {values.size - 3} values")
    return int(values[0]), values[3 : 3 + obs_dim].copy(), values[3 + obs_dim :].copy(), float(values[1])


def own_task(task_name: str, task_params: dict | None):
    """A one-trial task of the viewer's own, built from the run's task parameters.

    The viewer never touches the training run's task object; it builds this one to know
    where goals are (four_goals moves them at a given step).
    """
    from somarm import tasks

    return tasks.make(task_name, n_trials=1, **(task_params or {}))


def attach_feed(bridge, task_name: str, task_params: dict | None) -> str:
    """Draw ``task_name``'s scene in ``bridge`` and listen for frames; returns the feed's zmq address."""
    from somarm.viewer.shows import show_for_task

    task = own_task(task_name, task_params)
    show = show_for_task(task_name, task)

    def apply(commands: list[dict]) -> None:
        for command in commands:
            bridge.apply_command(command["type"], command.get("path", ""), umsgpack.packb(command))

    apply(show.setup())
    socket = bridge.context.socket(zmq.PULL)
    socket.setsockopt(zmq.CONFLATE, 1)  # only the newest frame waits; older ones are dropped
    socket.setsockopt(zmq.LINGER, 0)
    socket.bind("tcp://127.0.0.1:*")
    failures = []

    def on_frame(frames: list[bytes]) -> None:
        try:
            step, observation, action, reward = unpack_frame(frames[-1])
            task.set_step(step)  # four_goals: the goals move at a given step
            apply(show.frame(observation, action, reward))
        except Exception as exc:  # a bad frame must not stop the server; say so once, in its log
            if not failures:
                print(f"live feed: frame dropped: {exc!r}", file=sys.stderr, flush=True)
            failures.append(exc)

    ZMQStream(socket).on_recv(on_frame)
    bridge.feed_socket = socket  # held by the bridge so the socket lives as long as the server
    return socket.getsockopt(zmq.LAST_ENDPOINT).decode()
