"""The server side of ``LiveView``: snapshots of the greedy policy in, a cycle of goals on the page out.

The training process sends a snapshot now and then (``live.pack_snapshot``): the step, the
running mean reward, and the greedy answers for a fixed cycle of goals (or one greedy episode, or
one rollout of a MuJoCo model). Everything else (kinematics, flights, meshcat commands, msgpack,
websockets) runs here, in the server process, so it never competes with training for Python's
global lock. The server shows the cycle by its own clock: goal after goal, each held ``hold_s``
(a throw or an episode as long as it plays), always from the newest snapshot, and keeps going
after the last one (``finished``: "training finished", the final policy).
"""

from __future__ import annotations

import sys

import numpy as np
import umsgpack
import zmq
from meshcat.commands import Delete
from zmq.eventloop.zmqstream import ZMQStream

from somarm.viewer.text import number, text_command

__all__ = ["LiveFeed", "attach_feed", "own_task", "unpack_snapshot"]

_KINDS = ("goals", "paths", "states")


def unpack_snapshot(data: bytes) -> dict:
    """The dict ``somarm.viewer.live.pack_snapshot`` packed.

    Raises:
      ValueError: the bytes are not a snapshot.
    """
    try:
        snapshot = umsgpack.unpackb(data)
    except Exception as exc:  # umsgpack raises several types for bad bytes
        raise ValueError(f"a snapshot is msgpack, these {len(data)} bytes are not ({type(exc).__name__})") from None
    if not isinstance(snapshot, dict) or snapshot.get("kind") not in _KINDS or not isinstance(snapshot.get("items"),
                                                                                              dict):
        raise ValueError(f"a snapshot is a dict with a kind ({', '.join(_KINDS)}) and items")
    return snapshot


def own_task(task_name: str, task_params: dict | None):
    """A one-trial task of the viewer's own, built from the run's task parameters.

    The viewer never touches the training run's task object; it builds this one to know
    where goals are (four_goals moves them at a given step).
    """
    from somarm import tasks

    return tasks.make(task_name, n_trials=1, **(task_params or {}))


class _GoalPlayer:
    """One-step tasks: the arm (or the throw) for each goal of the cycle."""

    def __init__(self, task_name: str, task) -> None:
        from somarm.viewer.task_shows import show_for_task
        from somarm.viewer.throws import ThrowStream

        self.task = task
        self.show = show_for_task(task_name, task)
        self.throws = isinstance(self.show, ThrowStream)
        self.what = "greedy throw" if self.throws else "greedy pose"

    def setup(self) -> tuple[list[dict], dict]:
        commands = self.show.setup()
        view = self.show.show.view_text if self.throws else self.show.view_text
        return commands, {"key": self.show.key(), "labels": view["labels"]}

    def count(self, items: dict) -> int:
        return len(items.get("observations", []))

    def summary(self, items: dict) -> list[str]:
        if not items.get("greedy") or not self.count(items):
            return []
        errors = -np.asarray(self.task.evaluate(np.array(items["observations"]), np.array(items["actions"])))
        return [f"greedy error over the {len(errors)} goals: mean {number(errors.mean())}, worst {number(errors.max())}"]

    def item(self, items: dict, k: int) -> tuple[list[dict], float, list[str]]:
        n = self.count(items)
        observation, action = np.array(items["observations"][k]), np.array(items["actions"][k])
        if self.throws:
            commands = self.show.throws(observation, action[None])
            return commands, self.show.show.last_duration_s, self.show.caption(k, n, observation, action)
        commands = self.show.frame(observation, action)
        return commands, 0.0, self.show.caption(k, n, observation)


class _PathPlayer:
    """Tasks of episodes: a greedy episode animated along its MuJoCo path, its fingertip traced."""

    what = "greedy episode"

    def __init__(self, task_name: str, task) -> None:
        from somarm.viewer.motion import MotionShow, episode_describer
        from somarm.viewer.task_shows import show_for_task

        self.task = task
        self._goals: dict[int, np.ndarray] = {}  # each episode's goal, from its start observation
        self.show = MotionShow(show_for_task(task_name, task), episode_describer(task, self._goals.__getitem__))
        self.arm = self.show.arm

    def setup(self) -> tuple[list[dict], dict]:
        from somarm.viewer.motion import TRACE_COLOR
        from somarm.viewer.text import css

        commands = self.show.setup()
        return commands, {"key": self.arm.key() + [[css(TRACE_COLOR), "fingertip's path"]],
                          "labels": self.arm.view_text["labels"]}

    def count(self, items: dict) -> int:
        return len(items.get("paths", []))

    def summary(self, items: dict) -> list[str]:
        if not self.count(items):
            return []
        finals = np.array([path[-1] for path in items["paths"]])
        distances = np.asarray(self.task.distances(finals, self.task.goal_of(np.array(items["observations"]))))
        reached = int(np.sum(distances < self.task.params.tolerance))
        return [f"{reached} of {len(distances)} episodes shown reached the goal"]

    def item(self, items: dict, k: int) -> tuple[list[dict], float, list[str]]:
        from somarm.viewer.motion import motion_animation

        path = np.array(items["paths"][k])
        observation = np.array(items["observations"][k])
        index, of = int(items.get("indices", [k])[k]), int(items.get("of", self.count(items)))
        self._goals[index] = self.task.goal_of(observation)

        def describe(_k, _n, p, t):
            return self.show.describe(index, of, p, t)

        trace = self.arm.prefix.append("trace")
        animation, timeline, pieces = motion_animation(self.arm, observation[None], [path], describe=describe,
                                                       trace_prefix=trace)
        commands = [Delete(trace).lower(), *pieces, timeline.command(), animation]
        return commands, timeline.n_frames / timeline.fps, []


class _StatePlayer:
    """Any MuJoCo model: a greedy rollout animated in real time."""

    what = "greedy rollout"

    def __init__(self, model) -> None:
        from somarm.viewer.model_view import ModelShow

        self.show = ModelShow(model)

    def setup(self) -> tuple[list[dict], dict]:
        return self.show.setup(), {"key": [], "labels": []}

    def count(self, items: dict) -> int:
        return len(items.get("paths", []))

    def summary(self, items: dict) -> list[str]:
        if not self.count(items):
            return []
        returns = [float(np.sum(r)) for r in items.get("rewards", [])]
        return [f"return of the episode shown {number(returns[-1])}"] if returns else []

    def item(self, items: dict, k: int) -> tuple[list[dict], float, list[str]]:
        from somarm.viewer.model_view import Rollout

        states = np.array(items["paths"][k])
        rewards = np.array(items.get("rewards", [[]])[k], dtype=np.float64)
        done = Rollout(states, rewards, [], float(items["timestep"]))
        animation, timeline = self.show.animation(list(states), timestep=done.timestep,
                                                  describe=lambda i: done.describe(i))
        return [timeline.command(), animation], timeline.n_frames / timeline.fps, []


class LiveFeed:
    """Shows the newest snapshot's cycle on a bridge, goal after goal, by the server's own clock."""

    def __init__(self, bridge, player, name: str, *, task=None) -> None:
        self.bridge = bridge
        self.player = player
        self.name = name
        self.task = task
        self.snapshot: dict | None = None
        self.k = 0
        self.stats: list[str] = []
        self.caption: list[str] = []
        commands, text = player.setup()
        self.apply(commands)
        self.apply([text_command(title=f"{name}: live training", lines=[], caption=["waiting for training ..."],
                                 status="training", timeline=None, **text)])

    def apply(self, commands: list[dict]) -> None:
        for command in commands:
            self.bridge.apply_command(command["type"], command.get("path", ""), umsgpack.packb(command))

    def take(self, snapshot: dict) -> None:
        """A new snapshot: newer greedy answers, step and reward (an empty one keeps the answers shown)."""
        first = self.snapshot is None
        if self.snapshot is not None and not self.player.count(snapshot["items"]):
            snapshot = {**snapshot, "items": self.snapshot["items"]}
        self.snapshot = snapshot
        if self.task is not None:
            self.task.set_step(int(snapshot["step"]))  # four_goals: the goals move at a given step
        n = self.player.count(snapshot["items"])
        step = int(snapshot["step"])
        total = snapshot.get("n_steps")
        if snapshot["finished"]:
            status = f"training finished after {step:,} steps: the final greedy policy, shown until the viewer stops"
        else:
            status = f"training: step {step:,}" + (f" of {int(total):,}" if total else "")
        what = self.player.what if snapshot["items"].get("greedy", True) else "action being tried (no policy given)"
        title = f"{self.name}: {what}" + (f", a cycle of {n}" if n > 1 else "")
        reward = snapshot.get("mean_reward")
        self.stats = ([] if reward is None else
                      [f"running mean reward {number(reward)} (last {snapshot['window']} sampled steps of "
                       f"trial {snapshot['trial']})"]) + self.player.summary(snapshot["items"])
        self.apply([text_command(title=title, lines=list(snapshot.get("lines", [])), status=status,
                                 caption=self.caption + self.stats)])
        if first:
            self.show_next()

    def show_next(self) -> None:
        """Show the next goal of the cycle and come back when it has been held long enough."""
        snapshot = self.snapshot
        items = snapshot["items"]
        n = self.player.count(items)
        hold = float(snapshot.get("hold_s", 0.75))
        if n:
            k = self.k % n
            try:
                commands, duration, caption = self.player.item(items, k)
            except Exception as exc:  # a bad snapshot must not stop the server; say so in its log
                print(f"live feed: goal {k} not shown: {exc!r}", file=sys.stderr, flush=True)
                commands, duration, caption = [], 0.0, []
            self.caption = caption
            self.apply(commands + [text_command(caption=caption + self.stats)])
            self.k += 1
        else:
            duration = 0.0
        self.bridge.ioloop.call_later(max(hold, duration), self.show_next)


def attach_feed(bridge, *, task_name: str | None = None, model_path: str | None = None,
                task_params: dict | None = None) -> str:
    """Draw a task (or a saved MuJoCo model) in ``bridge`` and listen for snapshots; returns the feed's zmq address."""
    if task_name is not None:
        task = own_task(task_name, task_params)
        player = _PathPlayer(task_name, task) if task.episodic else _GoalPlayer(task_name, task)
        feed = LiveFeed(bridge, player, task_name, task=task)
    else:
        import mujoco

        model = mujoco.MjModel.from_binary_path(model_path)
        feed = LiveFeed(bridge, _StatePlayer(model), bridge.title)
    socket = bridge.context.socket(zmq.PULL)
    socket.setsockopt(zmq.CONFLATE, 1)  # only the newest snapshot waits; older ones are dropped
    socket.setsockopt(zmq.LINGER, 0)
    socket.bind("tcp://127.0.0.1:*")
    failures = []

    def on_snapshot(frames: list[bytes]) -> None:
        try:
            feed.take(unpack_snapshot(frames[-1]))
        except Exception as exc:  # a bad snapshot must not stop the server; say so once, in its log
            if not failures:
                print(f"live feed: snapshot dropped: {exc!r}", file=sys.stderr, flush=True)
            failures.append(exc)

    ZMQStream(socket).on_recv(on_snapshot)
    bridge.feed_socket = socket  # held by the bridge so the socket lives as long as the server
    bridge.feed = feed
    return socket.getsockopt(zmq.LAST_ENDPOINT).decode()
