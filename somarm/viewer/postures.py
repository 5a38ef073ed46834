"""Fig. 11 in the viewer: the arm's greedy postures for a sweep of goals, all drawn at once."""

from __future__ import annotations

import mujoco
import numpy as np

from somarm.viewer.scene import path_of
from somarm.viewer.shows import ERROR_COLOR, GOAL_COLOR, ArmShow, hold, shade
from somarm.viewer.text import css, number, text_command

__all__ = ["SweepShow"]


class SweepShow:
    """Fig. 11: the arm's greedy postures for a sweep of goals, all at once, shaded along the sweep.

    Goals (green rings) and errors (red) have one colour; each posture and its fingertip are
    shaded from blue (the first goal of the sweep) to red (the last).

    Args:
      model: the arm model (as ``ArmShow``).
      n_postures: how many goals of the sweep are drawn together.
      goal_of: as in ``ArmShow``.
    """

    def __init__(self, model: mujoco.MjModel, n_postures: int, *, goal_of=None,
                 prefix: str = "/meshcat/sweep") -> None:
        self.model = model
        self.prefix = path_of(prefix)
        self.arms = [ArmShow(model, goal_of=goal_of, prefix=f"{prefix}/posture{k:02d}") for k in range(n_postures)]
        for k, arm in enumerate(self.arms):
            arm.tip_color = shade(k / max(n_postures - 1, 1))
        self.errors = np.full(n_postures, np.nan)

    def setup(self, points: np.ndarray | None = None) -> list[dict]:
        """Every posture's moving parts in its shade; the table, base, grid and camera once."""
        commands = []
        for k, arm in enumerate(self.arms):
            world = arm.scene.body_node("world").lower()
            moving = {arm.scene.body_node(name).lower() for name, m in zip(arm.scene.body_names, arm.scene.moving,
                                                                        strict=True) if m}
            for command in arm.setup(points):
                path = command["path"]
                if k and (path.startswith(world) or not path.startswith(arm.prefix.lower())
                          or path.startswith(arm.prefix.append("grid").lower())
                          or path.startswith(arm.prefix.append("scale").lower())):
                    continue  # the table, the base, the grid, the scale and the camera: once is enough
                if command["type"] == "set_object" and any(path.startswith(m + "/") for m in moving):
                    for material in command["object"]["materials"]:
                        material["color"] = arm.tip_color
                commands.append(command)
        return commands

    def frame(self, observations: np.ndarray, actions: np.ndarray) -> list[dict]:
        """Posture k at ``actions[k]`` for goal ``observations[k]``; shapes ``(n_postures, dim)``."""
        commands = []
        for k, (arm, observation, action) in enumerate(zip(self.arms, observations, actions, strict=True)):
            commands += arm.frame(observation, action)
            self.errors[k] = arm.last_error
        return commands

    def text(self, session) -> dict:
        """Title, run, the errors of the sweep, the key, and which end is the first goal."""
        n = len(self.arms)
        worst = int(np.nanargmax(self.errors))
        arm = self.arms[0]
        key = [[css(shade(0.0)), "posture of goal 1"], [css(shade(1.0)), f"goal {n}"], [css(GOAL_COLOR), "goals"],
               [css(ERROR_COLOR), "errors"]] + arm.view_text["key"]
        labels = arm.view_text["labels"] + [[self.arms[0].prefix.append("goal_label").lower(), "goal 1"],
                                            [self.arms[-1].prefix.append("goal_label").lower(), f"goal {n}"]]
        caption = [f"{n} goals swept in order; mean error {number(np.nanmean(self.errors))}, "
                   f"worst {number(self.errors[worst])} (goal {worst + 1})"]
        return text_command(title=session.title(), lines=session.lines(), caption=caption, key=key, labels=labels,
                            timeline=None)

    def record(self, session, sink) -> None:
        """Every posture of the session's sweep at once."""
        sink.send_batch(self.setup(self.arms[0].session_points(session)))
        sink.send_batch(self.frame(session.observations, session.actions))
        sink.send(self.text(session))

    def play(self, session, sink, *, interval_s: float, once: bool, log) -> None:
        """The sweep, drawn once and kept on screen until Ctrl-C (or at once if ``once``)."""
        hold(self, session, sink, interval_s=interval_s, once=once, log=log)
