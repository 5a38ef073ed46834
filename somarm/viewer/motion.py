"""Driven arms in the viewer: the arm animated along the joint trajectories MuJoCo integrated.

An actuated reach moves from the start pose to where its servos settle; a reach2_obstacle
episode moves step after step around the wall. A ``MotionShow`` wraps the task's ``ArmShow``
(so every frame is that show's, at MuJoCo's pose) and records a session's paths as one
looping animation in real time.
"""

from __future__ import annotations

import time

import numpy as np

from somarm.viewer.overlays import animation_command
from somarm.viewer.shows import ArmShow

__all__ = ["MotionShow", "motion_animation", "pose_frame"]

#: Playback: every second 0.01 s timestep at 50 frames a second (real time); each end held 0.36 s.
_STRIDE, _FPS, _HOLD_FRAMES = 2, 50.0, 18


def pose_frame(show: ArmShow, observation: np.ndarray, angles: np.ndarray) -> list[dict]:
    """The show's frame with the arm at ``angles`` ``(nq,)``, whatever its ``pose_of`` would read."""
    pose_of, show.pose_of = show.pose_of, None
    try:
        return show.frame(observation, angles)
    finally:
        show.pose_of = pose_of


def motion_animation(show: ArmShow, observations: np.ndarray, paths: list[np.ndarray]) -> dict:
    """A looping animation along ``paths`` (one ``(n_frames, nq)`` array per observation).

    Frame ``k`` of path ``i`` is the arm at ``paths[i][2 k]`` (the last pose always included), shown
    at ``k / 50`` s from the path's start; the last pose is held before the next path begins.
    """
    frames = []
    for observation, path in zip(observations, paths, strict=True):
        picked = list(path[::_STRIDE])
        if (len(path) - 1) % _STRIDE:
            picked.append(path[-1])
        frames += [pose_frame(show, observation, angles) for angles in picked]
        frames += [frames[-1]] * _HOLD_FRAMES
    return animation_command(frames, fps=_FPS)


class MotionShow:
    """A session of driven-arm paths (``session.paths``) drawn by the task's ``ArmShow``."""

    def __init__(self, arm: ArmShow) -> None:
        self.arm = arm
        self.model = arm.model

    def setup(self) -> list[dict]:
        return self.arm.setup()

    def frame(self, observation: np.ndarray, action: np.ndarray, reward: float | None = None) -> list[dict]:
        return self.arm.frame(observation, action, reward)

    def record(self, session, sink) -> None:
        """The scene, the first path's start, and one animation through every path."""
        sink.send_batch(self.setup())
        sink.send_batch(pose_frame(self.arm, session.observations[0], session.paths[0][0]))
        sink.send(motion_animation(self.arm, session.observations, session.paths))

    def play(self, session, sink, *, interval_s: float, once: bool, log) -> None:
        """Record the animation, then keep it playing until Ctrl-C (or return at once if ``once``)."""
        self.record(session, sink)
        log(f"{session.task_name}: {len(session.observations)} paths, mean final error "
            f"{session.errors.mean():.4f}")
        while not once:
            time.sleep(interval_s)
