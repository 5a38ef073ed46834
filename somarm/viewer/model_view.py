"""Any MuJoCo model in the viewer: its geoms drawn from the ``MjModel``, its bodies moved by a sequence of states.

This is how a model that is not one of this project's tasks is watched, a Gymnasium MuJoCo
environment for one (``env.unwrapped.model`` / ``.data``)::

    import gymnasium
    from somarm.viewer.model_view import rollout, view_states

    env = gymnasium.make("Reacher-v5")
    states = rollout(env, policy=None, n_steps=200, seed=0)      # random actions, seeded
    view_states(env.unwrapped.model, states.qpos, timestep=states.timestep,
                title="Reacher-v5", html="reacher.html")

A state is a ``qpos`` vector or an ``MjData`` of the model; the scene computes the bodies' poses
itself (``mj_kinematics``), so an ``MjData`` straight after ``mj_step`` is drawn where it is now.
The camera is MuJoCo's free camera (the model's ``visual/global`` azimuth and elevation) backed
off until every state is in the frame.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import mujoco
import numpy as np

from somarm.viewer import framing, overlays
from somarm.viewer.scene import MujocoScene
from somarm.viewer.text import Timeline, number, text_command

__all__ = ["ModelShow", "Rollout", "record_states", "rollout", "view_states"]

#: Playback is in real time, at most this many frames a second (states in between are skipped).
_MAX_FPS = 50.0
_HOLD_S = 0.6


class ModelShow:
    """A MuJoCo model drawn from its geoms, its bodies moved from states.

    Args:
      model: any compiled MuJoCo model.
      prefix: meshcat path of the drawing.
    """

    def __init__(self, model: mujoco.MjModel, *, prefix: str = "/meshcat/model") -> None:
        self.model = model
        self.scene = MujocoScene(model, prefix=prefix)
        self.prefix = self.scene.prefix

    def box(self, states) -> tuple[np.ndarray, np.ndarray]:
        """The world box holding every drawn geom (planes aside) over ``states`` (at most 40 of them looked at)."""
        states = list(states) or [None]
        picked = states[:: max(1, len(states) // 40)] + [states[-1]]
        corners = np.array([corner for state in picked for corner in self.scene.extent(state)])
        return corners.min(axis=0), corners.max(axis=0)

    def setup(self, states=()) -> list[dict]:
        """The meshes, the first state's poses, and MuJoCo's free camera holding every state."""
        states = list(states)
        commands = self.scene.setup_commands()
        commands += self.scene.pose_commands(states[0] if states else None, everything=True)
        low, high = self.box(states)
        return commands + self._floor_grids(low, high) + framing.free_view(low, high, self.model)

    def _floor_grids(self, low, high) -> list[dict]:
        """A faint grid on each level plane of the world body (MuJoCo draws its floors checkered)."""
        model, commands = self.model, []
        span = float(np.max(high[:2] - low[:2]))
        step = overlays.nice_step(span, n_lines=6)
        for geom_id, name in zip(self.scene.geom_ids, self.scene.names, strict=True):
            level = abs(abs(model.geom_quat[geom_id][0]) - 1.0) < 1e-9
            if model.geom_type[geom_id] != mujoco.mjtGeom.mjGEOM_PLANE or model.geom_bodyid[geom_id] != 0 or not level:
                continue
            half = model.geom_size[geom_id, :2]
            centre = model.geom_pos[geom_id, :2]
            reach = np.where(half > 0, half, 1.5 * span + step)
            a, b = np.maximum(centre - reach, low[:2] - span), np.minimum(centre + reach, high[:2] + span)
            commands += overlays.grid_commands(self.prefix.append(f"{name}_grid"), a, b, step=step,
                                               z=float(model.geom_pos[geom_id, 2]) + 1e-3 * span, color=0x9AA3B2)
        return commands

    def frame(self, state) -> list[dict]:
        """The moving bodies at ``state`` (``qpos`` or ``MjData``)."""
        return self.scene.pose_commands(state)

    def animation(self, states, *, timestep: float, describe=None) -> tuple[dict, Timeline]:
        """A looping real-time animation through ``states`` and its text.

        Args:
          states: ``qpos`` vectors or ``MjData`` objects, ``timestep`` seconds apart.
          describe: ``describe(i) -> lines`` for state ``i`` (default: its index and time).
        """
        states = list(states)
        stride = max(1, int(np.ceil(1.0 / (_MAX_FPS * timestep)))) if timestep > 0 else 1
        fps = 1.0 / (stride * timestep) if timestep > 0 else 30.0
        picked = list(range(0, len(states), stride))
        if picked[-1] != len(states) - 1:
            picked.append(len(states) - 1)
        frames, timeline = [], Timeline(fps)
        for i in picked:
            frames.append(self.frame(states[i]))
            lines = describe(i) if describe is not None else [
                f"state {i + 1} of {len(states)}, t = {i * timestep:.2f} s"]
            timeline.add(1, lines)
        hold = int(round(_HOLD_S * fps))
        frames += [frames[-1]] * hold
        timeline.add(hold, timeline.frames[-1][1])
        return overlays.animation_command(frames, fps=fps), timeline


def record_states(model: mujoco.MjModel, states, sink, *, timestep: float, title: str, lines=(),
                  describe=None, prefix: str = "/meshcat/model") -> ModelShow:
    """Send the scene, the text and a looping animation through ``states`` to ``sink`` (server or recorder).

    Raises:
      ValueError: no states, or a ``qpos`` of the wrong shape.
    """
    states = list(states)
    if not states:
        raise ValueError("states is empty: give at least one qpos or MjData")
    show = ModelShow(model, prefix=prefix)
    sink.send_batch(show.setup(states))
    animation, timeline = show.animation(states, timestep=timestep, describe=describe)
    sink.send(text_command(title=title, lines=list(lines), caption=[], key=[], labels=[]))
    sink.send(timeline.command())
    sink.send(animation)
    return show


def view_states(model: mujoco.MjModel, states, *, timestep: float, title: str = "MuJoCo model", lines=(),
                describe=None, html=None, host: str = "127.0.0.1", port: int | None = None, log=print):
    """Watch ``states`` of ``model``: write an offline page to ``html``, or serve it until Ctrl-C.

    ``describe(i) -> lines`` is the text for state ``i`` (``Rollout.describe``: episode, step, return).

    Returns:
      The path written (with ``html``); otherwise returns only on Ctrl-C (KeyboardInterrupt is raised).
    """
    if html is not None:
        from somarm.viewer.client import Recorder
        from somarm.viewer.html import write_html

        recorder = Recorder()
        record_states(model, states, recorder, timestep=timestep, title=title, lines=lines, describe=describe)
        return write_html(html, recorder.commands(), title=title)
    from somarm.viewer.client import MeshcatClient
    from somarm.viewer.server import MeshcatServer, stop_on_signals

    with MeshcatServer(host=host, port=port, title=title) as server:
        stop_on_signals(server)
        client = MeshcatClient(server.zmq_url)
        try:
            record_states(model, states, client, timestep=timestep, title=title, lines=lines, describe=describe)
            log(f"{title}: open {server.web_url}  (Ctrl-C to stop)")
            while True:
                time.sleep(1.0)
        finally:
            client.close()


@dataclass
class Rollout:
    """States of an environment run: ``qpos (n_states, nq)``, ``rewards (n_states - 1,)`` (reward
    ``i`` came with the step to state ``i + 1``), ``resets``: the states after which the environment
    was reset (an episode's last; the next state is the new episode's first step), and the seconds
    between states."""

    qpos: np.ndarray
    rewards: np.ndarray
    resets: list[int]
    timestep: float

    def describe(self, i: int) -> list[str]:
        """Text for state ``i``: the episode, its step and the return so far."""
        starts = [0] + [r for r in self.resets if r < i]
        begin = starts[-1]
        returned = float(self.rewards[begin:i].sum()) if i > begin else 0.0
        return [f"episode {len(starts)}: step {i - begin}, t = {(i - begin) * self.timestep:.2f} s",
                f"return so far {number(returned)}"]


def rollout(env, policy=None, *, n_steps: int = 200, seed: int = 0, until_done: bool = False) -> Rollout:
    """Run a Gymnasium-style MuJoCo environment and keep its states.

    Args:
      env: anything with Gymnasium's ``reset(seed=)`` / ``step(action)`` whose ``unwrapped`` has
        ``model`` and ``data`` (every ``gymnasium.envs.mujoco`` environment).
      policy: ``policy(observation) -> action``; None takes random actions from the action space,
        seeded with ``seed``.
      n_steps: environment steps; an episode that ends is started again (or, with ``until_done``,
        ends the rollout).
      seed: the reset's seed.

    Returns:
      A ``Rollout``; ``timestep`` is the environment's ``dt`` (model timestep times frame skip).
    """
    base = getattr(env, "unwrapped", env)
    if not (hasattr(base, "model") and hasattr(base, "data")):
        raise ValueError("env.unwrapped must have MuJoCo's model and data (a gymnasium.envs.mujoco environment)")
    if policy is None:
        env.action_space.seed(seed)
        policy = lambda observation: env.action_space.sample()  # noqa: E731
    observation, _ = env.reset(seed=seed)
    qpos, rewards, resets = [base.data.qpos.copy()], [], []
    for i in range(n_steps):
        observation, reward, terminated, truncated, _ = env.step(policy(observation))
        rewards.append(float(reward))
        qpos.append(base.data.qpos.copy())
        if terminated or truncated:
            if until_done:
                break
            observation, _ = env.reset()
            resets.append(i + 1)
    timestep = float(getattr(base, "dt", base.model.opt.timestep))
    return Rollout(np.array(qpos), np.array(rewards), resets, timestep)
