"""What the viewer streams per task: the arm at its greedy pose, a sweep of postures, the throws.

A show turns one trial's (observation, action, reward) into meshcat commands. It never draws
random numbers and never talks to a server itself, so the CLI, the training hook and the HTML
export share it, and tests can check its poses against MuJoCo. Each show also knows how a
viewing session is recorded (``record``: a static page) and played (``play``: goal after goal).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import mujoco
import numpy as np
from meshcat.commands import SetTransform

from somarm.tasks.assets import load_model
from somarm.viewer import overlays
from somarm.viewer.adapters import goal_adapter, throw_adapters
from somarm.viewer.scene import MujocoScene, path_of

__all__ = ["ArmShow", "SweepShow", "ThrowShow", "load_model", "show_for_task", "arm_animation",
           "joint_path"]

_TIP_COLOR, _ERROR_COLOR, _INPUT_COLOR = 0xFFD21F, 0xE0301E, 0x3050C0
#: Frames of joint-space interpolation between two goals in the HTML animation.
_FRAMES_BETWEEN_GOALS = 12
_FRAMES_HOLDING_GOAL = 18


def _plane_view(model: mujoco.MjModel) -> np.ndarray:
    """A view direction for a planar mechanism: along its hinge axes, tilted a little for depth."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    hinges = model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE
    if hinges.any() and np.allclose(np.abs(data.xaxis[hinges][:, 2]), 1.0):
        return np.array([0.0, -0.35, 1.0])  # arms in the x-y plane: from above
    return np.array([0.0, -1.0, 0.25])  # flights in the x-z plane: from the side


class ArmShow:
    """A planar arm at the greedy pose for a goal, with fingertip, goal and the error between them.

    Args:
      model: the arm's MuJoCo model; the action is its joint angles (``nq`` values), the goal
        a mocap body, the fingertip a site named ``fingertip``.
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
        self.scene = MujocoScene(model, prefix=prefix)
        self.prefix = path_of(prefix)
        self.shows_input = goal_of is not None
        self.goal_of = goal_of or (lambda observation: np.asarray(observation, dtype=np.float64)[:2])
        self.tip_site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "fingertip")
        if self.tip_site < 0:
            raise ValueError("an arm model needs a site named 'fingertip'")
        self.size = float(model.stat.extent)
        self.last_error = float("nan")

    def setup(self) -> list[dict]:
        """Objects, the static geoms' poses, the markers and the camera."""
        commands = self.scene.setup_commands() + self.scene.pose_commands(everything=True)
        commands += overlays.marker_commands(
            self.prefix.append("fingertip"), radius=0.02 * self.size, color=_TIP_COLOR
        )
        commands += overlays.segment_commands(self.prefix.append("error"), radius=0.005 * self.size,
                                              color=_ERROR_COLOR)
        if self.shows_input:
            commands += overlays.marker_commands(self.prefix.append("input"), radius=0.012 * self.size,
                                                 color=_INPUT_COLOR)
        center = self.model.stat.center.copy()
        commands += overlays.camera_commands(center, _plane_view(self.model), 0.95 * self.size)
        return commands

    def with_goal(self, goal: np.ndarray) -> ArmShow:
        """The same show with a fixed goal (x, y) instead of one read from each observation."""
        fixed = np.asarray(goal, dtype=np.float64)[:2].copy()
        self.goal_of = lambda observation: fixed
        return self

    def qpos_of(self, action: np.ndarray) -> np.ndarray:
        """Joint angles of an action, inside the joints' ranges."""
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (self.model.nq,):
            raise ValueError(f"action must have shape ({self.model.nq},) (joint angles), got {action.shape}")
        low, high = self.model.jnt_range[:, 0], self.model.jnt_range[:, 1]
        limited = self.model.jnt_limited.astype(bool)
        return np.where(limited, np.clip(action, low, high), action)

    def frame(self, observation: np.ndarray, action: np.ndarray, reward: float | None = None) -> list[dict]:
        """Poses for one goal: the arm at ``action``, the goal, the fingertip and the error segment."""
        goal = np.zeros(3)
        goal[:2] = self.goal_of(observation)
        mocap = np.tile(goal, (self.model.nmocap, 1)) if self.model.nmocap else None
        pose = action if self.pose_of is None else self.pose_of(observation, action)
        commands = self.scene.pose_commands(self.qpos_of(pose), mocap_pos=mocap)
        tip = self.scene.data.site_xpos[self.tip_site].copy()  # current: pose_commands ran mj_kinematics
        self.last_error = float(np.linalg.norm(tip[:2] - goal[:2]))
        commands.append(SetTransform(overlays.translation(tip), self.prefix.append("fingertip")).lower())
        commands.append(SetTransform(overlays.segment_matrix(tip, goal), self.prefix.append("error")).lower())
        if self.shows_input:
            where = np.array([*np.asarray(observation, dtype=np.float64)[:2], 0.0])
            commands.append(SetTransform(overlays.translation(where), self.prefix.append("input")).lower())
        return commands

    def record(self, session, sink) -> None:
        """A session for a static page: the scene and one looping animation through its goals."""
        sink.send_batch(self.setup())
        sink.send_batch(self.frame(session.observations[0], session.actions[0]))
        sink.send(arm_animation(self, session.observations, session.actions))

    def play(self, session, sink, *, interval_s: float, once: bool, log) -> None:
        """Stream a session goal after goal, ``interval_s`` apart, until Ctrl-C (one pass if ``once``)."""
        sink.send_batch(self.setup())
        _stream(session, sink, lambda observation, action: self.frame(observation, action),
                lambda: interval_s, once=once, log=log)


class SweepShow:
    """Fig. 11: the arm's greedy postures for a sweep of goals, all at once, shaded along the sweep.

    Args:
      model: the arm model (as ``ArmShow``).
      n_postures: how many goals of the sweep are drawn together.
      goal_of: as in ``ArmShow``.
    """

    def __init__(self, model: mujoco.MjModel, n_postures: int, *, goal_of=None,
                 prefix: str = "/meshcat/sweep") -> None:
        self.arms = [ArmShow(model, goal_of=goal_of, prefix=f"{prefix}/posture{k:02d}") for k in range(n_postures)]

    def setup(self) -> list[dict]:
        """Every posture's moving parts, shaded from blue (first goal) to red (last); static parts once."""
        commands = []
        n = len(self.arms)
        for k, arm in enumerate(self.arms):
            share = k / max(n - 1, 1)
            color = (int(220 * share + 30) << 16) | (60 << 8) | int(220 * (1 - share) + 30)
            static = {arm.scene.node(name).lower() for name, moving in zip(arm.scene.names, arm.scene.moving,
                                                                        strict=True) if not moving}
            for command in arm.setup():
                node = command["path"].rsplit("/", 1)[0]
                if k and (node in static or command["path"] in static or not command["path"].startswith("/meshcat")):
                    continue  # the floor, the base and the camera: once is enough
                if command["type"] == "set_object" and node not in static and "/fingertip" not in command["path"]:
                    for material in command["object"]["materials"]:
                        material["color"] = color
                commands.append(command)
        return commands

    def frame(self, observations: np.ndarray, actions: np.ndarray) -> list[dict]:
        """Posture k at ``actions[k]`` for goal ``observations[k]``; shapes ``(n_postures, dim)``."""
        commands = []
        for arm, observation, action in zip(self.arms, observations, actions, strict=True):
            commands += arm.frame(observation, action)
        return commands

    def record(self, session, sink) -> None:
        """Every posture of the session's sweep at once."""
        sink.send_batch(self.setup())
        sink.send_batch(self.frame(session.observations, session.actions))

    def play(self, session, sink, *, interval_s: float, once: bool, log) -> None:
        """The sweep, drawn once and kept on screen until Ctrl-C (or at once if ``once``)."""
        _hold(self, session, sink, interval_s=interval_s, once=once, log=log)


class ThrowShow:
    """The launcher, the ground, the target and throws flying along their simulated paths.

    Args:
      model: the launcher's MuJoCo model (target as a mocap body).
      trajectory: ``(ux, uy) -> (n_points, 2)`` of (x, height): the simulated flight, used
        unless a call passes its own (the conditions may change with the observation).
      n_balls: how many throws are drawn at once (the action units of a fan, or 1).
    """

    def __init__(self, model: mujoco.MjModel, trajectory: Callable[[float, float], np.ndarray] | None = None, *,
                 n_balls: int = 1, prefix: str = "/meshcat/throw") -> None:
        self.model = model
        self.scene = MujocoScene(model, prefix=f"{prefix}/launcher")
        self.prefix = path_of(prefix)
        self.trajectory = trajectory
        self.n_balls = n_balls
        self.radius = 0.08
        self.last_duration_s = 0.0  #: playing time of the last ``throw_commands`` animation

    def _ball(self, k: int):
        return self.prefix.append(f"ball{k:02d}")

    def setup(self, *, center=(4.0, 0.0, 1.0), distance: float = 9.0) -> list[dict]:
        """Objects, static poses, one ball per throw, and a side view of the flight."""
        commands = self.scene.setup_commands() + self.scene.pose_commands(everything=True)
        for k in range(self.n_balls):
            share = k / max(self.n_balls - 1, 1)
            color = (int(200 * share + 40) << 16) | (80 << 8) | int(200 * (1 - share) + 40)
            commands += overlays.marker_commands(self._ball(k), radius=self.radius, color=color)
        commands += overlays.camera_commands(center, np.array([0.0, -1.0, 0.15]), distance)
        return commands

    def camera_fitting(self, points: np.ndarray, target_x: float) -> list[dict]:
        """A side view that holds the launcher, the target and every point of ``points`` ``(n, 3)``."""
        low = np.minimum(points.min(axis=0), [0.0, 0.0, 0.0])
        high = np.maximum(points.max(axis=0), [target_x, 0.0, 0.5])
        center = (low + high) / 2
        span = max(high[0] - low[0], 1.4 * (high[2] - low[2]))
        return overlays.camera_commands(center, np.array([0.0, -1.0, 0.12]), 0.85 * span + 1.0)

    def paths(self, actions: np.ndarray, trajectory=None) -> list[np.ndarray]:
        """The flights of ``actions`` ``(n_throws, 2)`` as ``(n_points, 3)`` world points."""
        trajectory = trajectory or self.trajectory
        if trajectory is None:
            raise ValueError("ThrowShow needs a trajectory function (ux, uy) -> (n_points, 2)")
        out = []
        for ux, uy in np.asarray(actions, dtype=np.float64):
            xz = np.asarray(trajectory(float(ux), float(uy)), dtype=np.float64)
            out.append(np.column_stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]]))
        return out

    def throw_commands(self, actions: np.ndarray, target_x: float, *, fps: float = 30.0,
                       trajectory=None) -> list[dict]:
        """Target placed, one trail per throw, and an animation of the balls along their paths.

        One animation frame per simulation step: at 30 fps a flight of the Table 3 world
        (about 25 time units at the tasks' step of 0.25) plays in a few seconds.
        """
        mocap = np.array([[target_x, 0.0, 0.0]] * self.model.nmocap)
        commands = self.scene.pose_commands(mocap_pos=mocap)
        paths = self.paths(actions, trajectory)
        for k, points in enumerate(paths):
            commands.append(overlays.path_line_command((self.prefix.append(f"trail{k:02d}")), points,
                                                       color=0xFFFFFF))
        n_frames = max(len(p) for p in paths)
        self.last_duration_s = n_frames / fps
        frames = [
            [SetTransform(overlays.translation(p[min(i, len(p) - 1)]), self._ball(k)).lower()
             for k, p in enumerate(paths)]
            for i in range(n_frames)
        ]
        commands += frames[-1]  # where the balls rest if animations are off
        commands += self.camera_fitting(np.concatenate(paths), target_x)
        commands.append(overlays.animation_command(frames, fps=fps))
        return commands

    def frame(self, observation: np.ndarray, action: np.ndarray, reward: float | None = None,
              *, target_x: float, trajectory=None) -> list[dict]:
        """One throw during training: its trail and the ball at its landing point (no animation)."""
        mocap = np.array([[target_x, 0.0, 0.0]] * self.model.nmocap)
        commands = self.scene.pose_commands(mocap_pos=mocap)
        points = self.paths(np.asarray(action)[None, :2], trajectory)[0]
        commands.append(overlays.path_line_command((self.prefix.append("trail00")), points, color=0xFFFFFF))
        commands.append(SetTransform(overlays.translation(points[-1]), self._ball(0)).lower())
        return commands


class _ThrowStream:
    """A ``ThrowShow`` fed one throw at a time, with the target where the task puts it."""

    def __init__(self, show: ThrowShow, trajectory_of, target_of: Callable[[np.ndarray], float]) -> None:
        self.show = show
        self.trajectory_of = trajectory_of
        self.target_of = target_of

    def setup(self) -> list[dict]:
        return self.show.setup()

    def frame(self, observation: np.ndarray, action: np.ndarray, reward: float | None = None) -> list[dict]:
        return self.show.frame(observation, action, reward, target_x=self.target_of(observation),
                               trajectory=self.trajectory_of(observation))

    def throws(self, observation: np.ndarray, actions: np.ndarray) -> list[dict]:
        """All ``actions`` ``(n, 2)`` thrown under ``observation``'s conditions, animated."""
        return self.show.throw_commands(actions, self.target_of(observation),
                                        trajectory=self.trajectory_of(observation))

    def record(self, session, sink) -> None:
        """The fan of every action unit (the single-state throw), or the first goal's throw, animated."""
        throws = session.fan if session.fan is not None else session.actions[:1]
        self.show.n_balls = len(throws)
        sink.send_batch(self.setup())
        sink.send_batch(self.throws(session.observations[0], throws))

    def play(self, session, sink, *, interval_s: float, once: bool, log) -> None:
        """A fan is held on screen; otherwise one throw per goal, each watched to its landing."""
        if session.fan is not None:
            _hold(self, session, sink, interval_s=interval_s, once=once, log=log)
            return
        self.show.n_balls = 1
        sink.send_batch(self.setup())
        _stream(session, sink, lambda observation, action: self.throws(observation, action[None]),
                lambda: max(interval_s, self.show.last_duration_s), once=once, log=log)


def _hold(show, session, sink, *, interval_s: float, once: bool, log) -> None:
    """Record the session, then keep it on screen until Ctrl-C (or return at once if ``once``)."""
    show.record(session, sink)
    log(f"{session.task_name}: {len(session.observations)} goals, mean error {session.errors.mean():.4f}")
    while not once:
        time.sleep(interval_s)


def _stream(session, sink, commands_of, pause_s: Callable[[], float], *, once: bool, log) -> None:
    """Send ``commands_of(observation, action)`` goal after goal, ``pause_s()`` apart."""
    while True:
        for observation, action, error in zip(session.observations, session.actions, session.errors, strict=True):
            sink.send_batch(commands_of(observation, action))
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


def arm_animation(show: ArmShow, observations: np.ndarray, actions: np.ndarray) -> dict:
    """A looping animation through the goals: hold each pose, then move in joint space to the next."""
    frames = []
    n = len(observations)
    for k in range(n):
        frames += [show.frame(observations[k], actions[k])] * _FRAMES_HOLDING_GOAL
        following = (k + 1) % n
        for share in np.linspace(0.0, 1.0, _FRAMES_BETWEEN_GOALS + 2)[1:-1]:
            frames.append(show.frame(observations[following], joint_path(actions[k], actions[following], share)))
    return overlays.animation_command(frames)


def show_for_task(task_name: str, task=None, *, sweep: int | None = None):
    """What ``somarm view`` and ``LiveView`` stream for a task: ``setup()`` then ``frame(obs, action, reward)``.

    Args:
      task_name: registered task name; its record names the model that draws it.
      task: the task object (it tells where goals and targets are); None builds a one-trial one.
      sweep: draw this many postures at once (Fig. 11's sweep, an arm task) instead of one arm.

    Raises:
      ValueError: unknown task name (the names are listed).
    """
    from somarm import tasks

    model_name = tasks.record(task_name).model
    task = tasks.make(task_name) if task is None else task
    model = load_model(model_name)
    if model_name == "launcher":
        trajectory_of, target_of = throw_adapters(task)
        return _ThrowStream(ThrowShow(model, prefix=f"/meshcat/{task_name}"), trajectory_of, target_of)
    if sweep is not None:
        return SweepShow(model, sweep, goal_of=goal_adapter(task))
    if task.episodic:  # reach2_obstacle: the arm where it is and the episode's goal, both observed
        return ArmShow(model, prefix=f"/meshcat/{task_name}", goal_of=task.goal_of,
                       pose_of=lambda observation, action: np.asarray(observation)[:2])
    return ArmShow(model, goal_of=goal_adapter(task), prefix=f"/meshcat/{task_name}")
