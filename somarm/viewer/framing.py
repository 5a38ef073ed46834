"""How a scene is framed: planar arms from the top on a grid with a scale, flights from the side on a
ground with distance ticks, any other model as MuJoCo's own viewer first shows it.

Each function returns lowered meshcat commands (camera, background, grid, labels' anchor nodes)
and the overlay text that goes with them (``key`` and ``labels`` for ``text.text_command``).
"""

from __future__ import annotations

import math

import meshcat.geometry as mg
import mujoco
import numpy as np
from meshcat.commands import SetObject, SetTransform

from somarm.viewer import overlays
from somarm.viewer.scene import path_of
from somarm.viewer.text import css

__all__ = ["GRID_COLOR", "TICK_COLOR", "floor_height", "free_view", "ground_view", "top_view"]

GRID_COLOR, TICK_COLOR, SCALE_COLOR, GROUND_COLOR = 0xAEB6C4, 0x4A5263, 0x2A3140, 0xD3DEC8
#: The ground of a flight, square: wide and deep enough to reach the horizon of a side view.
_GROUND_DEPTH = 2000.0


def floor_height(model: mujoco.MjModel) -> float:
    """Height of the top of the highest world-body box or plane at or below z = 0 (a table), else 0."""
    tops = [0.0 if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE else model.geom_pos[g, 2] + model.geom_size[g, 2]
            for g in range(model.ngeom)
            if model.geom_bodyid[g] == 0 and model.geom_type[g] in (mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_PLANE)]
    below = [float(t) for t in tops if t <= 1e-9]
    return max(below) if below else 0.0


def top_view(prefix, low, high, *, floor: float = 0.0, margin: float = 0.06,
             room_left: float = 0.4) -> tuple[list[dict], dict]:
    """A planar scene seen from straight above, the x-y box ``low``-``high`` filling the frame.

    A faint grid at a round spacing covers the framed area just above ``floor``, and a scale bar
    one grid square long sits in its lower-left corner, labelled with its length. The frame
    leaves ``room_left`` of the box's width free on the left, where the text panel sits.

    Returns:
      ``(commands, overlay)``: the meshcat commands and ``{"key": ..., "labels": ...}`` for the text.
    """
    low, high = np.asarray(low, dtype=np.float64)[:2], np.asarray(high, dtype=np.float64)[:2]
    span = high - low
    pad = 0.04 * float(span.max())
    low, high = low - pad, high + pad
    step = overlays.nice_step(float(span.max()), n_lines=8)
    prefix = path_of(prefix)
    z = floor + 1e-3
    commands = overlays.background_commands()
    commands += overlays.grid_commands(prefix.append("grid"), low, high, step=step, z=z, color=GRID_COLOR)
    start = np.array([math.ceil(low[0] / step) * step, math.ceil(low[1] / step) * step, z + 1e-3])
    if start[0] + step > high[0]:
        start[0] = low[0]
    end = start + [step, 0.0, 0.0]
    tick = [0.0, 0.12 * step, 0.0]
    commands.append(overlays.segments_command(prefix.append("scale"), np.array([start, start - tick, end - tick]),
                                              np.array([end, start + tick, end + tick]), color=SCALE_COLOR))
    commands.append(SetTransform(overlays.translation((start + end) / 2 - [0.0, 0.1 * step, 0.0]),
                                 prefix.append("scale_label")).lower())
    box_low, box_high = [low[0] - room_left * (high[0] - low[0]), low[1], floor], [*high, floor + 0.05]
    commands += overlays.fit_camera(box_low, box_high, [0.0, -1e-3, 1.0], margin=margin)
    text = {"key": [[css(GRID_COLOR), f"grid {_length(step)}"]],
            "labels": [[prefix.append("scale_label").lower(), _length(step)]]}
    return commands, text


def ground_view(prefix, low, high, *, tick_every: float | None = None,
                room_top: float = 0.5) -> tuple[list[dict], dict]:
    """Flights in the x-z plane from the side: a ground to the horizon, ticks across it at round distances.

    ``low``-``high`` is the (x, z) box that must be in the frame (launcher, target, every flight);
    ``room_top`` of its height is left free above it, where the text panel sits. Ticks come every
    ``tick_every`` (default: a round step giving about ten).

    Returns:
      ``(commands, overlay)`` as ``top_view``.
    """
    prefix = path_of(prefix)
    x0, x1 = float(low[0]), float(high[0])
    commands = overlays.background_commands(top=(0.93, 0.96, 0.99), bottom=(0.80, 0.86, 0.92))
    reach = max(x1 - x0, 1.0)
    tick_every = tick_every or overlays.nice_step(reach, n_lines=10)
    ground = mg.Box([_GROUND_DEPTH, _GROUND_DEPTH, 1e-3 * reach])
    commands.append(SetObject(ground, mg.MeshBasicMaterial(color=GROUND_COLOR), prefix.append("ground")).lower())
    commands.append(SetTransform(overlays.translation([(x0 + x1) / 2, 0.0, -2e-3 * reach]),
                                 prefix.append("ground")).lower())
    ticks = np.arange(math.floor(x0 / tick_every), math.floor(x1 / tick_every) + 1) * tick_every
    width = 0.025 * reach
    starts = np.column_stack([ticks, np.full(len(ticks), -width), np.zeros(len(ticks))])
    ends = np.column_stack([ticks, np.full(len(ticks), width), np.zeros(len(ticks))])
    axis = [[x0, 0.0, 0.0]], [[x1, 0.0, 0.0]]
    commands.append(overlays.segments_command(prefix.append("ticks"), np.vstack([starts, *axis[:1]]),
                                              np.vstack([ends, *axis[1:]]), color=TICK_COLOR))
    labels = []
    for k, x in enumerate(ticks):
        node = prefix.append(f"tick{k:02d}")
        commands.append(SetTransform(overlays.translation([x, -width, 0.0]), node).lower())
        labels.append([node.lower(), _length(x)])
    top = float(high[1]) + room_top * (float(high[1]) - min(float(low[1]), 0.0))
    box_low, box_high = [x0, -width, min(float(low[1]), 0.0)], [x1, width, top]
    commands += overlays.fit_camera(box_low, box_high, [0.0, -1.0, 0.12], margin=0.08)
    return commands, {"key": [[css(TICK_COLOR), f"ticks every {_length(tick_every)}"]], "labels": labels}


def free_view(low, high, model: mujoco.MjModel | None = None) -> list[dict]:
    """MuJoCo's free camera (the model's ``visual/global`` azimuth and elevation) holding the box ``low``-``high``."""
    azimuth, elevation = (90.0, -45.0) if model is None else (model.vis.global_.azimuth, model.vis.global_.elevation)
    a, e = math.radians(azimuth), math.radians(elevation)
    # MuJoCo's camera looks along (cos e cos a, cos e sin a, sin e); the camera sits opposite.
    looking = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    return overlays.background_commands() + overlays.fit_camera(low, high, -looking, margin=0.05)


def _length(value: float) -> str:
    """A length for a label: ``0.1``, ``2``, ``0.25``."""
    text = f"{value:.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text
