"""What the viewer draws besides the model: markers, segments, paths, the camera, animations.

All functions return lowered meshcat commands (dicts) and talk to no server.
"""

from __future__ import annotations

import meshcat.geometry as mg
import meshcat.transformations as tf
import numpy as np
from meshcat.commands import SetObject, SetProperty, SetTransform

from somarm.viewer.scene import path_of

__all__ = [
    "animation_command",
    "camera_commands",
    "marker_commands",
    "path_line_command",
    "segment_commands",
    "segment_matrix",
    "translation",
]


def translation(xyz) -> np.ndarray:
    """``(4, 4)`` pure translation."""
    matrix = np.eye(4)
    matrix[:3, 3] = np.asarray(xyz, dtype=np.float64)
    return matrix


def marker_commands(path, *, radius: float, color: int, opacity: float = 1.0) -> list[dict]:
    """A sphere at ``path`` (move it with ``set_transform``)."""
    material = mg.MeshPhongMaterial(color=color, opacity=opacity, transparent=opacity < 1.0)
    return [SetObject(mg.Sphere(radius), material, path_of(path)).lower()]


def segment_matrix(start, end) -> np.ndarray:
    """Pose of a unit-height y-axis cylinder stretched to join ``start`` and ``end`` (3-vectors)."""
    start, end = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    axis = end - start
    length = float(np.linalg.norm(axis))
    matrix = translation((start + end) / 2.0)
    if length < 1e-12:
        matrix[:3, :3] = np.diag([1.0, 1e-9, 1.0])  # an invisible sliver, not a NaN
        return matrix
    y = axis / length
    helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    matrix[:3, :3] = np.column_stack([x, y * length, z])
    return matrix


def segment_commands(path, *, radius: float, color: int) -> list[dict]:
    """A unit cylinder at ``path``; place it with ``SetTransform(segment_matrix(a, b), path)``."""
    return [SetObject(mg.Cylinder(1.0, radius), mg.MeshPhongMaterial(color=color), path_of(path)).lower()]


def path_line_command(path, points: np.ndarray, *, color: int) -> dict:
    """A polyline through ``points`` ``(n_points, 3)``."""
    points = np.asarray(points, dtype=np.float32)
    geometry = mg.PointsGeometry(points.T)
    return SetObject(mg.Line(geometry, mg.LineBasicMaterial(color=color, linewidth=2)), path=path_of(path)).lower()


def camera_commands(center, view_direction, distance: float, *, hide_grid: bool = True) -> list[dict]:
    """Look at ``center`` from ``distance`` along ``view_direction`` (world vectors).

    meshcat 0.3.2's orbiting camera always looks at the world origin, so the drawing under
    ``/meshcat`` is shifted by ``-center`` instead; and the camera's position is written in
    three.js's y-up frame, so a world offset (x, y, z) is given as (x, z, -y).
    """
    direction = np.asarray(view_direction, dtype=np.float64)
    direction = direction / np.linalg.norm(direction)
    offset = distance * direction
    commands = [
        SetTransform(translation(-np.asarray(center, dtype=np.float64)), path_of("/meshcat")).lower(),
        SetProperty("position", [float(offset[0]), float(offset[2]), float(-offset[1])],
                    path_of("/Cameras/default/rotated/<object>")).lower(),
    ]
    if hide_grid:
        commands.append(SetProperty("visible", False, path_of("/Grid")).lower())
        commands.append(SetProperty("visible", False, path_of("/Axes")).lower())
    return commands


def animation_command(frames: list[list[dict]], *, fps: float = 30.0, repetitions: int = 1000) -> dict:
    """Turn frames of ``set_transform`` commands into one meshcat ``set_animation`` command.

    Args:
      frames: frame k is the list of ``set_transform`` commands that hold at time ``k / fps``;
        other command types are ignored (meshcat animates transforms only).
      fps: frames per second of playback.
      repetitions: how many times the clip plays (meshcat has no "forever").

    Returns:
      A lowered ``set_animation`` command with position, quaternion and scale tracks.
    """
    clips: dict[str, dict[str, list]] = {}
    for k, frame in enumerate(frames):
        for command in frame:
            if command["type"] != "set_transform":
                continue
            matrix = np.asarray(command["matrix"], dtype=np.float64).reshape(4, 4).T  # meshcat is column-major
            scale = np.linalg.norm(matrix[:3, :3], axis=0)
            rotation = np.eye(4)
            rotation[:3, :3] = matrix[:3, :3] / np.where(scale > 0, scale, 1.0)
            w, x, y, z = tf.quaternion_from_matrix(rotation)
            tracks = clips.setdefault(command["path"], {"position": [], "quaternion": [], "scale": []})
            tracks["position"].append({"time": k, "value": [float(v) for v in matrix[:3, 3]]})
            tracks["quaternion"].append({"time": k, "value": [float(x), float(y), float(z), float(w)]})
            tracks["scale"].append({"time": k, "value": [float(v) for v in scale]})
    kinds = {"position": "vector3", "quaternion": "quaternion", "scale": "vector3"}
    animations = [
        {
            "path": path,
            "clip": {
                "fps": float(fps),
                "name": "default",
                "tracks": [{"name": "." + name, "type": kinds[name], "keys": keys} for name, keys in tracks.items()],
            },
        }
        for path, tracks in clips.items()
    ]
    return {"type": "set_animation", "animations": animations, "options": {"play": True, "repetitions": repetitions},
            "path": ""}
