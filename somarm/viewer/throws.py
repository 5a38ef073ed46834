"""What the viewer draws for the throwing tasks: throws flying along their simulated paths.

Seen from the side over a wide ground with distance ticks. Each ball has a colour of its own and
its trail takes that colour; where it lands a ring of the same colour appears. The launcher model's
own projectile is not drawn (the balls are the projectiles). The text names the target and the
conditions of each throw and how far each landed from the target.
"""

from __future__ import annotations

import colorsys
from collections.abc import Callable

import mujoco
import numpy as np
from meshcat.commands import SetTransform

from somarm.viewer import framing, overlays
from somarm.viewer.scene import MujocoScene, path_of
from somarm.viewer.task_readers import throw_readers
from somarm.viewer.text import Timeline, css, number, text_command

__all__ = ["ThrowShow", "ThrowStream", "ball_color", "throw_show"]

#: Flight time units played per second of animation (Table 3's flights last about 20-30 units).
_UNITS_PER_SECOND = 10.0
_FPS = 30.0
#: Frames a landed throw stays on screen before the next one flies (in a sequence of throws).
_HOLD_FRAMES = 24
TARGET_COLOR = 0xD62828
_BALL_RADIUS = 0.08


def ball_color(k: int, n: int) -> int:
    """Colour of ball ``k`` of ``n``: hues from orange through green to violet, distinct side by side."""
    hue = 0.08 + 0.7 * (k / max(n - 1, 1)) if n > 1 else 0.58
    red, green, blue = colorsys.hsv_to_rgb(hue, 0.8, 0.82)
    return (int(red * 255) << 16) | (int(green * 255) << 8) | int(blue * 255)


class ThrowShow:
    """The launcher, the ground, the target and throws flying along their simulated paths.

    Args:
      model: the launcher's MuJoCo model (target as a mocap body).
      trajectory: ``(ux, uy) -> (times (T,), xz (T, 2))``: the simulated flight (time, x, height),
        used unless a call passes its own (the conditions may change with the observation).
      n_balls: how many throws are drawn at once (the action units of a fan, or 1).
    """

    def __init__(self, model: mujoco.MjModel, trajectory: Callable | None = None, *, n_balls: int = 1,
                 prefix: str = "/meshcat/throw") -> None:
        self.model = model
        self.scene = MujocoScene(model, prefix=f"{prefix}/launcher", hidden=("projectile", "ground"))
        self.prefix = path_of(prefix)
        self.trajectory = trajectory
        self.n_balls = n_balls
        self.radius = _BALL_RADIUS
        self.view_text: dict = {"key": [], "labels": []}
        self.trail_width = 0.03
        self.last_duration_s = 0.0  #: playing time of the last animation built

    def _node(self, kind: str, k: int):
        return self.prefix.append(f"{kind}{k:02d}")

    def setup(self, low=(-0.5, 0.0), high=(8.0, 3.0)) -> list[dict]:
        """Objects, static poses, one ball and landing ring per throw, the ground and a side view of ``low``-``high`` (x, z)."""
        commands = self.scene.setup_commands() + self.scene.pose_commands(everything=True)
        span = float(high[0] - low[0])
        self.radius = max(_BALL_RADIUS, 0.01 * span)  # a ball stays visible however far the throws go
        for k in range(self.n_balls):
            color = ball_color(k, self.n_balls)
            commands += overlays.marker_commands(self._node("ball", k), radius=self.radius, color=color)
            commands += overlays.ring_commands(self._node("landing", k), radius=1.5 * self.radius,
                                               width=0.5 * self.radius, color=color)
            commands.append(SetTransform(overlays.HIDDEN, self._node("landing", k)).lower())
        view, self.view_text = framing.ground_view(self.prefix, low, high)
        self.trail_width = 0.0035 * span
        return commands + view

    def _trail(self, k: int, points: np.ndarray, color: int) -> dict:
        return overlays.ribbon_command(self._node("trail", k), points, width=self.trail_width, color=color,
                                       normal=(0.0, 1.0, 0.0))

    def paths(self, actions: np.ndarray, trajectory=None) -> list[tuple[np.ndarray, np.ndarray]]:
        """The flights of ``actions`` ``(n_throws, 2)``: ``(times (T,), points (T, 3))`` each."""
        trajectory = trajectory or self.trajectory
        if trajectory is None:
            raise ValueError("ThrowShow needs a trajectory function (ux, uy) -> (times, xz)")
        out = []
        for ux, uy in np.asarray(actions, dtype=np.float64)[:, :2]:
            times, xz = trajectory(float(ux), float(uy))
            xz = np.asarray(xz, dtype=np.float64)
            out.append((np.asarray(times, dtype=np.float64), np.column_stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]])))
        return out

    @staticmethod
    def resampled(times: np.ndarray, points: np.ndarray) -> np.ndarray:
        """The points at every frame time (``_UNITS_PER_SECOND`` time units a second), the landing last."""
        n = max(2, int(np.ceil((times[-1] - times[0]) / _UNITS_PER_SECOND * _FPS)) + 1)
        at = np.linspace(times[0], times[-1], n)
        return np.column_stack([np.interp(at, times, points[:, i]) for i in range(3)])

    def box(self, paths, targets) -> tuple[np.ndarray, np.ndarray]:
        """The (x, z) box holding the launcher, the targets and every flight."""
        points = np.vstack([p for _, p in paths] + [[[x, 0.0, 0.0]] for x in targets])
        low = np.minimum(points.min(axis=0)[[0, 2]], [0.0, 0.0]) - [0.3, 0.0]
        high = np.maximum(points.max(axis=0)[[0, 2]], [0.0, 0.5]) + [0.3, 0.1]
        return low, high

    def throw_commands(self, actions: np.ndarray, target_x: float, *, trajectory=None) -> list[dict]:
        """Target placed, one trail per throw, and an animation of all balls flying at once."""
        mocap = np.array([[target_x, 0.0, 0.0]] * self.model.nmocap)
        commands = self.scene.pose_commands(mocap_pos=mocap)
        flights = [self.resampled(t, p) for t, p in self.paths(actions, trajectory)]
        n_frames = max(len(p) for p in flights)
        frames: list[list[dict]] = [[] for _ in range(n_frames)]
        for k, points in enumerate(flights):
            color = ball_color(k, self.n_balls)
            commands.append(self._trail(k, points, color))
            for i in range(n_frames):
                frames[i].append(SetTransform(overlays.translation(points[min(i, len(points) - 1)]),
                                              self._node("ball", k)).lower())
            landed = len(points) - 1
            for i, matrix in ((0, overlays.HIDDEN), (max(landed - 1, 0), overlays.HIDDEN),
                              (landed, overlays.translation(points[-1] + [0.0, 0.0, 2e-3]))):
                frames[i].append(SetTransform(matrix, self._node("landing", k)).lower())
        commands += frames[-1]  # where the balls rest if animations are off
        self.last_duration_s = n_frames / _FPS
        commands.append(overlays.animation_command(frames + [frames[-1]] * _HOLD_FRAMES, fps=_FPS))
        return commands

    def sequence_commands(self, actions, targets, trajectories, captions) -> tuple[list[dict], Timeline]:
        """One throw after another (one ball), each at its own target, landing, then held; and its text.

        Throw ``j`` flies from ``actions[j]`` at ``targets[j]`` along ``trajectories[j]``; its trail
        shows only while it flies and lands, its ring only once it has landed.
        """
        frames: list[list[dict]] = []
        timeline = Timeline(_FPS)
        commands, bounds = [], []
        ball, landing = self._node("ball", 0), self._node("landing", 0)
        for j, (action, target_x, trajectory) in enumerate(zip(actions, targets, trajectories, strict=True)):
            (times, points), = self.paths(np.asarray(action)[None], trajectory)
            flight = self.resampled(times, points)
            mocap = np.array([[target_x, 0.0, 0.0]] * self.model.nmocap)
            commands.append(self._trail(j, flight, ball_color(0, 1)))
            start = len(frames)
            for i in range(len(flight) + _HOLD_FRAMES):
                frame = self.scene.pose_commands(mocap_pos=mocap) if i in (0, len(flight) + _HOLD_FRAMES - 1) else []
                frame.append(SetTransform(overlays.translation(flight[min(i, len(flight) - 1)]), ball).lower())
                frames.append(frame)
            landed = start + len(flight) - 1
            frames[start].append(SetTransform(overlays.HIDDEN, landing).lower())
            frames[landed - 1].append(SetTransform(overlays.HIDDEN, landing).lower())
            frames[landed].append(SetTransform(overlays.translation(flight[-1] + [0.0, 0.0, 2e-3]), landing).lower())
            frames[-1].append(SetTransform(overlays.translation(flight[-1] + [0.0, 0.0, 2e-3]), landing).lower())
            timeline.add(len(flight) + _HOLD_FRAMES, captions[j])
            bounds.append((start, len(frames) - 1))
        for j, (begin, end) in enumerate(bounds):
            trail = self._node("trail", j)
            shown = [(begin, np.eye(4)), (end, np.eye(4))]
            if begin:
                shown = [(0, overlays.HIDDEN), (begin - 1, overlays.HIDDEN)] + shown
            if end < len(frames) - 1:
                shown += [(end + 1, overlays.HIDDEN)]
            for i, matrix in shown:
                frames[i].append(SetTransform(matrix, trail).lower())
        self.last_duration_s = len(frames) / _FPS
        commands.append(overlays.animation_command(frames, fps=_FPS))
        return commands, timeline

    def frame(self, observation: np.ndarray, action: np.ndarray, reward: float | None = None,
              *, target_x: float, trajectory=None) -> list[dict]:
        """One throw, still: its trail, the ball at its landing point and the landing ring."""
        mocap = np.array([[target_x, 0.0, 0.0]] * self.model.nmocap)
        commands = self.scene.pose_commands(mocap_pos=mocap)
        (_, points), = self.paths(np.asarray(action)[None, :2], trajectory)
        commands.append(self._trail(0, points, ball_color(0, 1)))
        commands.append(SetTransform(overlays.translation(points[-1]), self._node("ball", 0)).lower())
        commands.append(SetTransform(overlays.translation(points[-1] + [0.0, 0.0, 2e-3]),
                                     self._node("landing", 0)).lower())
        return commands


class ThrowStream:
    """A ``ThrowShow`` of a task: the target where the task puts it, the flight under each observation's conditions."""

    def __init__(self, show: ThrowShow, task, trajectory_of, target_of: Callable[[np.ndarray], float]) -> None:
        self.show = show
        self.model = show.model
        self.task = task
        self.trajectory_of = trajectory_of
        self.target_of = target_of

    def setup(self, observations=None, actions=None) -> list[dict]:
        """The scene framed on the flights of ``actions`` under ``observations`` (default: a target's reach)."""
        if observations is None:
            return self.show.setup()
        paths = [self.show.paths(np.asarray(a)[None], self.trajectory_of(o))[0]
                 for o, a in zip(observations, actions, strict=True)]
        return self.show.setup(*self.show.box(paths, [self.target_of(o) for o in observations]))

    def landing_miss(self, observation: np.ndarray, action: np.ndarray) -> tuple[float, float]:
        """Where the throw of ``action`` lands (x) and how far from the target."""
        (_, points), = self.show.paths(np.asarray(action)[None], self.trajectory_of(observation))
        x = float(points[-1, 0])
        return x, abs(x - self.target_of(observation))

    def conditions_text(self, observation: np.ndarray) -> str:
        """The conditions that vary with the observation (target, wind, drag, mass), as text."""
        names = {"X": "target x", "W": "wind", "Fr": "drag", "M": "mass"}
        values = self.task.conditions(np.asarray(observation, dtype=np.float64)[None])
        shown = ["X"] + [k for k in getattr(self.task, "varied", ()) if k != "X" and k in names]
        return ", ".join(f"{names[k]} {number(float(np.ravel(values[k])[0]), 2)}" for k in shown).replace(
            "target x", "target x =", 1)

    def caption(self, k: int, n: int, observation: np.ndarray, action: np.ndarray) -> list[str]:
        landed, miss = self.landing_miss(observation, action)
        return [f"throw {k + 1} of {n}: {self.conditions_text(observation)}",
                f"landed at x = {number(landed, 2)}, miss {number(miss)}"]

    def key(self) -> list[list[str]]:
        return [[css(TARGET_COLOR), "target"], [css(ball_color(0, 1)), "ball, its trail, its landing"]] + \
            self.show.view_text["key"]

    def frame(self, observation: np.ndarray, action: np.ndarray, reward: float | None = None) -> list[dict]:
        return self.show.frame(observation, action, reward, target_x=self.target_of(observation),
                               trajectory=self.trajectory_of(observation))

    def throws(self, observation: np.ndarray, actions: np.ndarray) -> list[dict]:
        """All ``actions`` ``(n, 2)`` thrown under ``observation``'s conditions, animated."""
        return self.show.throw_commands(actions, self.target_of(observation),
                                        trajectory=self.trajectory_of(observation))

    def record(self, session, sink) -> None:
        """The fan of every action unit (the single-state throw), or every goal's throw in turn, animated."""
        if session.fan is not None:
            self._record_fan(session, sink)
            return
        observations, actions = session.observations, session.actions
        n = len(observations)
        self.show.n_balls = 1
        sink.send_batch(self.setup(observations, actions))
        commands, timeline = self.show.sequence_commands(
            actions, [self.target_of(o) for o in observations],
            [self.trajectory_of(o) for o in observations],
            [self.caption(k, n, o, a) for k, (o, a) in enumerate(zip(observations, actions, strict=True))])
        sink.send(text_command(title=session.title(), lines=session.lines(), key=self.key(),
                               labels=self.show.view_text["labels"], caption=[]))
        sink.send(timeline.command())
        sink.send_batch(commands)

    def _record_fan(self, session, sink) -> None:
        observation, fan = session.observations[0], np.asarray(session.fan)
        n = len(fan)
        self.show.n_balls = n
        sink.send_batch(self.setup([observation] * n, fan))
        sink.send_batch(self.throws(observation, fan))
        misses = np.array([self.landing_miss(observation, a)[1] for a in fan])
        chips = [[css(ball_color(k, n)), f"{m:.3f}"] for k, m in enumerate(misses)]
        caption = [f"{self.conditions_text(observation)}; {n} throws, one per action unit",
                   f"landing miss: mean {number(misses.mean())}, best {number(misses.min())}, "
                   f"worst {number(misses.max())}; each throw's miss, in its ball's colour:"]
        key = [[css(TARGET_COLOR), "target"]] + self.show.view_text["key"] + chips
        sink.send(text_command(title=session.title(), lines=session.lines(), caption=caption, key=key,
                               labels=self.show.view_text["labels"], timeline=None))

    def play(self, session, sink, *, interval_s: float, once: bool, log) -> None:
        """Record the session's animation (the fan, or one throw per goal) and keep it on screen."""
        from somarm.viewer.shows import hold

        hold(self, session, sink, interval_s=interval_s, once=once, log=log)


def throw_show(task_name: str, task, model: mujoco.MjModel) -> ThrowStream:
    """The show of a throwing task."""
    trajectory_of, target_of = throw_readers(task)
    return ThrowStream(ThrowShow(model, prefix=f"/meshcat/{task_name}"), task, trajectory_of, target_of)
