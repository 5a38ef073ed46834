"""What the viewer draws for the arm tasks: the arm at its greedy pose per goal, and a sweep of postures.

A show turns one trial's (observation, action) into meshcat commands and overlay text. It never
draws random numbers and never talks to a server itself, so the CLI, the live training view and
the HTML export share it, and tests can check its poses against MuJoCo. Each show also knows how
a viewing session is recorded (``record``: a page with one looping animation) and played
(``play``: goal after goal on a live server). Sweeps of postures are in ``postures.py``, throws in
``throws.py``, arms driven along MuJoCo trajectories in ``motion.py``, any other MuJoCo model in
``model_view.py``.

Planar arms are seen from straight above, the table filling the frame, on a faint grid with a
scale. The goal is a green ring above the arm, larger than the fingertip (a small amber ball), so
a reached goal shows the fingertip inside it; the error is a red segment between them, drawn
faint (and said so in the text) where it passes through the model's geometry.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import mujoco
import numpy as np
from meshcat.commands import SetTransform

from somarm.tasks.assets import load_model
from somarm.viewer import framing, overlays
from somarm.viewer.scene import MujocoScene, path_of
from somarm.viewer.text import Timeline, css, number, text_command

__all__ = ["ArmShow", "TIP_COLOR", "GOAL_COLOR", "ERROR_COLOR", "INPUT_COLOR", "arm_animation", "hold",
           "joint_path", "load_model", "shade"]

TIP_COLOR, GOAL_COLOR, ERROR_COLOR, INPUT_COLOR = 0xE8A200, 0x1E9E4A, 0xD62828, 0x3060D0
#: Frames of joint-space interpolation between two goals in the HTML animation, and frames a goal is held.
_FRAMES_BETWEEN_GOALS = 12
_FRAMES_HOLDING_GOAL = 24
_FPS = 30.0
#: Heights above the arm's plane: the fingertip ball, the error segment and the goal ring (in reaches).
_TIP_Z, _ERROR_Z, _GOAL_Z = 0.02, 0.025, 0.045


def shade(share: float) -> int:
    """The colour of posture ``share`` (0 first, 1 last) of a sweep: blue through purple to red."""
    blue, red = np.array([0x25, 0x5C, 0xB8]), np.array([0xD0, 0x38, 0x1C])
    r, g, b = (blue + float(share) * (red - blue)).round().astype(int)
    return (int(r) << 16) | (int(g) << 8) | int(b)


class ArmShow:
    """A planar arm at the greedy pose for a goal, with fingertip, goal and the error between them.

    Args:
      model: the arm's MuJoCo model; the action is its joint angles (``nq`` values), the fingertip
        a site named ``fingertip``; a geom named ``goal`` (a mocap body or fixed) is drawn as the ring.
      goal_of: maps an observation ``(obs_dim,)`` to the goal's (x, y); default: its first two
        values. When given (four_goals), the observation itself is drawn too, as a blue dot.
      prefix: meshcat path of the drawing.
      pose_of: maps ``(observation, action)`` to the joint angles drawn; default: the action (the
        reach tasks' setpoint). reach2_obstacle observes the angles and acts by changing targets.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        *,
        goal_of: Callable[[np.ndarray], np.ndarray] | None = None,
        prefix: str = "/meshcat/arm",
        pose_of: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
    ) -> None:
        self.model = model
        self.pose_of = pose_of
        self.scene = MujocoScene(model, prefix=prefix, hidden=("goal",))
        self.prefix = path_of(prefix)
        self.shows_input = goal_of is not None
        self.goal_of = goal_of or (lambda observation: np.asarray(observation, dtype=np.float64)[:2])
        self.tip_site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "fingertip")
        if self.tip_site < 0:
            raise ValueError("an arm model needs a site named 'fingertip'")
        data = self.scene.set_state(np.zeros(model.nq))  # stretched out: the tip is one reach from the base
        self.base = data.xpos[1].copy()
        self.reach = float(np.linalg.norm(data.site_xpos[self.tip_site] - self.base))
        self.floor = framing.floor_height(model)
        self.obstacles = self._obstacles()
        self.last_error = float("nan")
        self.last_crossing: str | None = None
        self.tip_color = TIP_COLOR
        self.view_text: dict = {"key": [], "labels": []}  # the framing's part of the text, set by ``setup``

    def _obstacles(self) -> list[tuple[int, str]]:
        """The fixed geoms other than the table (walls, the base) that an error segment may cross."""
        model, found = self.model, []
        for geom_id, name in zip(self.scene.geom_ids, self.scene.names, strict=True):
            if model.geom_bodyid[geom_id] != 0 or model.geom_type[geom_id] == mujoco.mjtGeom.mjGEOM_PLANE:
                continue
            if not self._is_table(int(geom_id)):
                found.append((int(geom_id), name))
        return found

    def _is_table(self, geom_id: int) -> bool:
        model = self.model
        return (model.geom_bodyid[geom_id] == 0 and model.geom_type[geom_id] == mujoco.mjtGeom.mjGEOM_BOX
                and model.geom_pos[geom_id, 2] + model.geom_size[geom_id, 2] <= self.floor + 1e-9)

    def crossing(self, start: np.ndarray, end: np.ndarray) -> str | None:
        """Name of a fixed geom the straight segment ``start``-``end`` (3-vectors) passes through, or None."""
        vector = np.asarray(end, dtype=np.float64) - start
        if not np.any(vector):
            return None
        data = self.scene.data
        for geom_id, name in self.obstacles:
            hit = mujoco.mju_rayGeom(data.geom_xpos[geom_id], data.geom_xmat[geom_id], self.model.geom_size[geom_id],
                                    np.asarray(start, dtype=np.float64), vector, int(self.model.geom_type[geom_id]))
            if 0.0 <= hit <= 1.0:
                return name
        return None

    def _markers(self, prefix, *, tip_color: int) -> list[dict]:
        r = self.reach
        return (overlays.marker_commands(prefix.append("fingertip"), radius=0.016 * r, color=tip_color)
                + overlays.ring_commands(prefix.append("goal"), radius=0.04 * r, width=0.014 * r, color=GOAL_COLOR)
                + overlays.ring_commands(prefix.append("goal_fill"), radius=0.04 * r, width=0.04 * r,
                                         color=GOAL_COLOR, opacity=0.18)
                + overlays.segment_commands(prefix.append("error"), radius=0.005 * r, color=ERROR_COLOR)
                + overlays.segment_commands(prefix.append("error_through"), radius=0.004 * r, color=ERROR_COLOR,
                                            opacity=0.3))

    def workspace(self, points: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The x-y box to frame: the table (the world's boxes under the arm), the base, and ``points`` ``(n, 2+)``."""
        model = self.model
        corners = [self.base[:2] - 0.05 * self.reach, self.base[:2] + 0.05 * self.reach]
        for g in range(model.ngeom):
            if self._is_table(g):
                corners += [model.geom_pos[g, :2] - model.geom_size[g, :2], model.geom_pos[g, :2] + model.geom_size[g, :2]]
        if points is not None and len(points):
            corners += list(np.asarray(points, dtype=np.float64)[:, :2])
        corners = np.array(corners)
        return corners.min(axis=0), corners.max(axis=0)

    def setup(self, points: np.ndarray | None = None) -> list[dict]:
        """Objects, the static poses, the markers, and a top view framing the table and ``points``."""
        commands = self.scene.setup_commands() + self.scene.pose_commands(everything=True)
        commands += self._markers(self.prefix, tip_color=self.tip_color)
        if self.shows_input:
            commands += overlays.marker_commands(self.prefix.append("input"), radius=0.014 * self.reach,
                                                 color=INPUT_COLOR)
        low, high = self.workspace(points)
        view, self.view_text = framing.top_view(self.prefix, low, high, floor=self.floor)
        return commands + view

    def key(self) -> list[list[str]]:
        """The colour key of this show (the grid's entry comes from the framing)."""
        key = [[css(self.tip_color), "fingertip"], [css(GOAL_COLOR), "goal"], [css(ERROR_COLOR), "error"]]
        if self.shows_input:
            key.append([css(INPUT_COLOR), "observed point"])
        return key + self.view_text["key"]

    def text(self, **fields) -> dict:
        """The overlay command for this show: its key and labels, and ``fields``."""
        return text_command(key=self.key(), labels=self.view_text["labels"], **fields)

    def qpos_of(self, action: np.ndarray) -> np.ndarray:
        """Joint angles of an action, inside the joints' ranges."""
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (self.model.nq,):
            raise ValueError(f"action must have shape ({self.model.nq},) (joint angles), got {action.shape}")
        low, high = self.model.jnt_range[:, 0], self.model.jnt_range[:, 1]
        limited = self.model.jnt_limited.astype(bool)
        return np.where(limited, np.clip(action, low, high), action)

    def goal_point(self, observation: np.ndarray) -> np.ndarray:
        """The goal of ``observation`` as a point ``(3,)`` in the arm's plane."""
        goal = np.zeros(3)
        goal[:2] = self.goal_of(observation)
        return goal

    def frame(self, observation: np.ndarray, action: np.ndarray, reward: float | None = None) -> list[dict]:
        """Poses for one goal: the arm at ``action``, the goal, the fingertip and the error segment."""
        goal = self.goal_point(observation)
        mocap = np.tile(goal, (self.model.nmocap, 1)) if self.model.nmocap else None
        pose = action if self.pose_of is None else self.pose_of(observation, action)
        commands = self.scene.pose_commands(self.qpos_of(pose), mocap_pos=mocap)
        tip = self.scene.data.site_xpos[self.tip_site].copy()  # current: pose_commands ran mj_kinematics
        self.last_error = float(np.linalg.norm(tip[:2] - goal[:2]))
        self.last_crossing = self.crossing(np.array([*tip[:2], 0.0]), np.array([*goal[:2], 0.0]))
        r = self.reach
        up = np.array([0.0, 0.0, 1.0])
        segment = overlays.segment_matrix(np.array([*tip[:2], 0.0]) + _ERROR_Z * r * up, goal + _ERROR_Z * r * up)
        solid, faint = (overlays.HIDDEN, segment) if self.last_crossing else (segment, overlays.HIDDEN)
        commands += [
            SetTransform(overlays.translation(np.array([*tip[:2], 0.0]) + _TIP_Z * r * up),
                         self.prefix.append("fingertip")).lower(),
            SetTransform(overlays.translation(goal + _GOAL_Z * r * up), self.prefix.append("goal")).lower(),
            SetTransform(overlays.translation(goal + (_GOAL_Z - 0.002) * r * up),
                         self.prefix.append("goal_fill")).lower(),
            SetTransform(solid, self.prefix.append("error")).lower(),
            SetTransform(faint, self.prefix.append("error_through")).lower(),
            SetTransform(overlays.translation(goal - [0.0, 0.06 * r, 0.0]), self.prefix.append("goal_label")).lower(),
        ]
        if self.shows_input:
            where = np.array([*np.asarray(observation, dtype=np.float64)[:2], _TIP_Z * r])
            commands.append(SetTransform(overlays.translation(where), self.prefix.append("input")).lower())
        return commands

    def caption(self, k: int, n: int, observation: np.ndarray) -> list[str]:
        """What the text says about the goal just framed (``frame`` sets the error it reports)."""
        gx, gy = self.goal_of(observation)[:2]
        where = f"goal {k + 1} of {n} at ({gx:.3f}, {gy:.3f})"
        if self.shows_input:
            x, y = np.asarray(observation, dtype=np.float64)[:2]
            where = f"goal {k + 1} of {n}: observed ({x:.3f}, {y:.3f}), goal ({gx:.3f}, {gy:.3f})"
        error = f"error {number(self.last_error)}"
        if self.last_crossing:
            error += f" (straight line, through the {self.last_crossing})"
        return [where, error]

    def record(self, session, sink) -> None:
        """A session for a static page: the scene, the text, and one looping animation through its goals."""
        sink.send_batch(self.setup(self.session_points(session)))
        sink.send_batch(self.frame(session.observations[0], session.actions[0]))
        animation, timeline = arm_animation(self, session.observations, session.actions)
        sink.send(self.text(title=session.title(), lines=session.lines(), caption=[]))
        sink.send(timeline.command())
        sink.send(animation)

    def session_points(self, session) -> np.ndarray:
        """Every body position, fingertip and goal of the session's poses ``(n, 3)``, to frame them."""
        points = []
        for observation, action in zip(session.observations, session.actions, strict=True):
            pose = action if self.pose_of is None else self.pose_of(observation, action)
            data = self.scene.set_state(self.qpos_of(pose))
            points += [data.xpos[1:].copy(), data.site_xpos[self.tip_site][None].copy(), self.goal_point(observation)[None]]
            if self.shows_input:
                points.append(np.array([[*np.asarray(observation, dtype=np.float64)[:2], 0.0]]))
        return np.vstack(points)

    def play(self, session, sink, *, interval_s: float, once: bool, log) -> None:
        """Stream a session goal after goal, ``interval_s`` apart, until Ctrl-C (one pass if ``once``)."""
        sink.send_batch(self.setup(self.session_points(session)))
        sink.send(self.text(title=session.title(), lines=session.lines(), timeline=None))
        n = len(session.observations)

        def show(k: int) -> list[dict]:
            commands = self.frame(session.observations[k], session.actions[k])
            return commands + [text_command(caption=self.caption(k, n, session.observations[k]))]

        _stream(session, sink, show, lambda: interval_s, once=once, log=log)


def hold(show, session, sink, *, interval_s: float, once: bool, log) -> None:
    """Record the session, then keep it on screen until Ctrl-C (or return at once if ``once``)."""
    show.record(session, sink)
    log(f"{session.task_name}: {len(session.observations)} goals, mean error {session.errors.mean():.4f}")
    while not once:
        time.sleep(interval_s)


def _stream(session, sink, commands_of, pause_s: Callable[[], float], *, once: bool, log) -> None:
    """Send ``commands_of(k)`` for goal after goal, ``pause_s()`` apart."""
    while True:
        for k, (observation, error) in enumerate(zip(session.observations, session.errors, strict=True)):
            sink.send_batch(commands_of(k))
            log(f"goal {np.array2string(observation, precision=3)}  error {error:.4f}")
            time.sleep(pause_s())
        if once:
            return


def joint_path(start: np.ndarray, end: np.ndarray, share: float) -> np.ndarray:
    """Joint angles ``share`` of the way from ``start`` to ``end``, each joint the shorter way round.

    The arms' joints turn freely, so -pi and pi are one pose: a learner whose angles wrap
    (``periodic_actions``) may answer neighbouring goals from both ends of the box, and the arm
    must not swing a full turn between them.
    """
    step = np.mod(end - start + np.pi, 2.0 * np.pi) - np.pi
    return start + share * step


def arm_animation(show: ArmShow, observations: np.ndarray, actions: np.ndarray) -> tuple[dict, Timeline]:
    """A looping animation through the goals, and its text: hold each pose, then move in joint space to the next."""
    frames = []
    timeline = Timeline(_FPS)
    n = len(observations)
    for k in range(n):
        held = show.frame(observations[k], actions[k])
        frames += [held] * _FRAMES_HOLDING_GOAL
        timeline.add(_FRAMES_HOLDING_GOAL, show.caption(k, n, observations[k]))
        following = (k + 1) % n
        moving = np.linspace(0.0, 1.0, _FRAMES_BETWEEN_GOALS + 2)[1:-1]
        for share in moving:
            frames.append(show.frame(observations[following], joint_path(actions[k], actions[following], share)))
        timeline.add(len(moving), [f"moving to goal {following + 1} of {n}", ""])
    return overlays.animation_command(frames, fps=_FPS), timeline
