"""Driven arms in the viewer: the arm animated along the joint trajectories MuJoCo integrated.

An actuated reach moves from the start pose to where its servos settle; a reach2_obstacle
episode moves step after step around the wall. A ``MotionShow`` wraps the task's ``ArmShow``
(so every frame is that show's, at MuJoCo's pose) and records a session's paths as one looping
animation in real time, the fingertip's path traced as it goes, with text that follows it
(episode and step, return so far, success; or the time and the error now).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from meshcat.commands import SetTransform

from somarm.viewer import overlays
from somarm.viewer.shows import ArmShow
from somarm.viewer.text import Timeline, css, number, text_command

__all__ = ["MotionShow", "episode_describer", "motion_animation", "pose_frame", "settle_describer"]

#: Playback: every second 0.01 s timestep at 50 frames a second (real time); each end held 0.6 s.
_STRIDE, _FPS, _HOLD_FRAMES = 2, 50.0, 30
#: The traced path is drawn in at most this many pieces per path (each appears as the tip passes it).
_TRACE_PIECES = 40
TRACE_COLOR = 0xB07A00

#: ``describe(k, n, path, t) -> lines``: the text for path ``k`` of ``n`` at timestep ``t`` of ``path``.
Describe = Callable[[int, int, np.ndarray, int], list[str]]


def pose_frame(show: ArmShow, observation: np.ndarray, angles: np.ndarray) -> list[dict]:
    """The show's frame with the arm at ``angles`` ``(nq,)``, whatever its ``pose_of`` would read."""
    pose_of, show.pose_of = show.pose_of, None
    try:
        return show.frame(observation, angles)
    finally:
        show.pose_of = pose_of


def _picked(path: np.ndarray) -> list[int]:
    """The timesteps of ``path`` that become frames: every ``_STRIDE``-th and the last."""
    picked = list(range(0, len(path), _STRIDE))
    if picked[-1] != len(path) - 1:
        picked.append(len(path) - 1)
    return picked


def motion_animation(show: ArmShow, observations: np.ndarray, paths: list[np.ndarray], *,
                     describe: Describe | None = None, trace_prefix=None) -> tuple[dict, Timeline, list[dict]]:
    """A looping animation along ``paths`` (one ``(n_frames, nq)`` array per observation), its text and trace.

    Frame ``k`` of path ``i`` is the arm at ``paths[i][2 k]`` (the last pose always included), shown
    at ``k / 50`` s from the path's start; the last pose is held before the next path begins.

    Returns:
      ``(set_animation command, timeline, trace objects)``: the trace is the fingertip's path of
      each path in pieces (``set_object`` commands under ``trace_prefix``), each piece shown from
      the frame the tip reaches its end until its path ends.
    """
    frames: list[list[dict]] = []
    timeline = Timeline(_FPS)
    trace_prefix = trace_prefix or show.prefix.append("trace")
    objects: list[dict] = []
    trace_keys: list[tuple[int, dict]] = []
    z = 0.012 * show.reach
    n = len(paths)
    for k, (observation, path) in enumerate(zip(observations, paths, strict=True)):
        start = len(frames)
        tips = []
        for t in _picked(path):
            frames.append(pose_frame(show, observation, path[t]))
            tips.append(show.scene.data.site_xpos[show.tip_site][:2].copy())
            lines = describe(k, n, path, t) if describe is not None else [f"path {k + 1} of {n}"]
            if show.last_crossing:
                lines = lines + [f"(the error is the straight line, through the {show.last_crossing})"]
            timeline.add(1, lines)
        frames += [list(frames[-1]) for _ in range(_HOLD_FRAMES)]
        timeline.add(_HOLD_FRAMES, timeline.frames[-1][1])
        end = len(frames) - 1
        tips = np.column_stack([np.array(tips), np.full(len(tips), z)])
        size = max(1, int(np.ceil((len(tips) - 1) / _TRACE_PIECES)))
        for j, first in enumerate(range(0, max(len(tips) - 1, 1), size)):
            last = min(first + size, len(tips) - 1)
            node = trace_prefix.append(f"path{k:02d}").append(f"piece{j:02d}")
            objects.append(overlays.ribbon_command(node, tips[first:last + 1], width=0.007 * show.reach,
                                                   color=TRACE_COLOR))
            shown_from = start + last
            keys = [(0, overlays.HIDDEN), (shown_from - 1, overlays.HIDDEN)] if shown_from > 0 else []
            keys += [(shown_from, np.eye(4)), (end, np.eye(4)), (end + 1, overlays.HIDDEN)]
            trace_keys += [(i, SetTransform(matrix, node).lower()) for i, matrix in keys]
    for i, command in trace_keys:
        if i < len(frames):  # a piece hides in the next path's first frame (the last path's: at the loop)
            frames[i].append(command)
    return overlays.animation_command(frames, fps=_FPS), timeline, objects


def episode_describer(task, goal_for: Callable[[int], np.ndarray]) -> Describe:
    """Text for a greedy episode of an episodic task: episode and step, return so far, distance, success.

    Uses the task's ``control_steps`` (timesteps per step), ``distances``, ``reward_of`` and
    ``params.tolerance`` / ``params.step_limit``; ``goal_for(k)`` is episode k's goal (x, y).
    """
    per_step = int(task.control_steps)

    def describe(k: int, n: int, path: np.ndarray, t: int) -> list[str]:
        goal = np.asarray(goal_for(k), dtype=np.float64)
        step = int(np.ceil(t / per_step))
        ends = path[[min(j * per_step, len(path) - 1) for j in range(1, step + 1)]]
        distances = np.asarray(task.distances(ends, goal), dtype=np.float64) if step else np.zeros(0)
        returned = float(np.sum(task.reward_of(distances))) if step else 0.0
        reached = bool(step and distances[-1] < task.params.tolerance)
        now = float(np.asarray(task.distances(path[t][None], goal))[0])
        last = (len(path) - 1) // per_step
        verdict = "goal reached" if reached else ("step limit, goal not reached" if t == len(path) - 1 else "")
        return [f"episode {k + 1} of {n}: step {step} of {last} (limit {task.params.step_limit})",
                f"return so far {number(returned)}, distance to goal {number(now)}" + (f"; {verdict}" if verdict
                                                                                       else "")]

    return describe


def settle_describer(task, goals: np.ndarray, errors: np.ndarray, timestep: float) -> Describe:
    """Text for an actuated reach: the goal, the time since the servos got their targets, the error read."""

    def describe(k: int, n: int, path: np.ndarray, t: int) -> list[str]:
        gx, gy = np.asarray(goals[k], dtype=np.float64)[:2]
        return [f"goal {k + 1} of {n} at ({gx:.3f}, {gy:.3f}): t = {t * timestep:.2f} s of "
                f"{(len(path) - 1) * timestep:.2f} s", f"error when read {number(errors[k])}"]

    return describe


class MotionShow:
    """A session of driven-arm paths (``session.paths``) drawn by the task's ``ArmShow``.

    Args:
      arm: the task's arm show.
      describe: the text per path and timestep (``episode_describer``, ``settle_describer``).
    """

    def __init__(self, arm: ArmShow, describe: Describe | None = None) -> None:
        self.arm = arm
        self.model = arm.model
        self.describe = describe

    def setup(self, points: np.ndarray | None = None) -> list[dict]:
        return self.arm.setup(points)

    def frame(self, observation: np.ndarray, action: np.ndarray, reward: float | None = None) -> list[dict]:
        return self.arm.frame(observation, action, reward)

    def points(self, paths: list[np.ndarray]) -> np.ndarray:
        """Body positions and fingertips along the paths ``(n, 3)``, to frame them."""
        points = []
        for path in paths:
            for angles in path[:: max(1, len(path) // 20)]:
                data = self.arm.scene.set_state(self.arm.qpos_of(angles))
                points += [data.xpos[1:].copy(), data.site_xpos[self.arm.tip_site][None].copy()]
        return np.vstack(points)

    def record(self, session, sink) -> None:
        """The scene, the first path's start, the text, and one animation through every path."""
        sink.send_batch(self.setup(self.points(session.paths)))
        sink.send_batch(pose_frame(self.arm, session.observations[0], session.paths[0][0]))
        animation, timeline, trace = motion_animation(self.arm, session.observations, session.paths,
                                                      describe=self.describe)
        sink.send_batch(trace)
        key = self.arm.key() + [[css(TRACE_COLOR), "fingertip's path"]]
        sink.send(text_command(title=session.title(), lines=session.lines(), caption=[], key=key,
                               labels=self.arm.view_text["labels"]))
        sink.send(timeline.command())
        sink.send(animation)

    def play(self, session, sink, *, interval_s: float, once: bool, log) -> None:
        """Record the animation, then keep it playing until Ctrl-C (or return at once if ``once``)."""
        self.record(session, sink)
        log(f"{session.task_name}: {len(session.observations)} paths, mean final error "
            f"{session.errors.mean():.4f}")
        while not once:
            time.sleep(interval_s)
