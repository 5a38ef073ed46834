"""What the viewer draws besides the model: markers, rings, segments, paths, grids, the camera, animations.

All functions return lowered meshcat commands (dicts) and talk to no server.
"""

from __future__ import annotations

import math

import meshcat.geometry as mg
import meshcat.transformations as tf
import numpy as np
from meshcat.commands import SetObject, SetProperty, SetTransform

from somarm.viewer.scene import path_of

__all__ = [
    "FOV_DEGREES",
    "animation_command",
    "background_commands",
    "camera_commands",
    "fit_camera",
    "grid_commands",
    "marker_commands",
    "nice_step",
    "path_line_command",
    "ribbon_command",
    "ring_commands",
    "segment_commands",
    "segment_matrix",
    "segments_command",
    "translation",
    "HIDDEN",
]

#: The camera's vertical field of view: narrower than meshcat's 75 degrees, so a top view of a
#: planar arm reads almost like a drawing (little perspective), as MuJoCo's own viewer's 45 do.
FOV_DEGREES = 40.0
#: The page's assumed width / height when a view is fitted (900 x 640 screenshots; wider windows
#: only add margin).
ASPECT = 1.4
#: A transform that shrinks a node to nothing: how an animation hides a node (meshcat animates
#: transforms, not visibility).
HIDDEN = np.diag([1e-9, 1e-9, 1e-9, 1.0])


def translation(xyz) -> np.ndarray:
    """``(4, 4)`` pure translation."""
    matrix = np.eye(4)
    matrix[:3, 3] = np.asarray(xyz, dtype=np.float64)
    return matrix


def _material(color: int, opacity: float) -> mg.MeshPhongMaterial:
    return mg.MeshPhongMaterial(color=color, opacity=opacity, transparent=opacity < 1.0)


def marker_commands(path, *, radius: float, color: int, opacity: float = 1.0) -> list[dict]:
    """A sphere at ``path`` (move it with ``set_transform``)."""
    return [SetObject(mg.Sphere(radius), _material(color, opacity), path_of(path)).lower()]


def ring_commands(path, *, radius: float, width: float, color: int, opacity: float = 1.0,
                  segments: int = 48) -> list[dict]:
    """A flat ring (an annulus in its x-y plane, seen from both sides) at ``path``; ``width`` = radius for a disc."""
    angles = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    inner = max(radius - width, 0.0)
    circle = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(segments)])
    vertices = np.vstack([radius * circle, inner * circle]).astype(np.float32)
    k = np.arange(segments)
    following = (k + 1) % segments
    up = np.vstack([np.column_stack([k, following, segments + k]),
                    np.column_stack([following, segments + following, segments + k])])
    faces = np.vstack([up, up[:, ::-1]]).astype(np.uint32)  # both windings: visible from above and below
    geometry = mg.TriangularMeshGeometry(vertices, faces)
    return [SetObject(geometry, _material(color, opacity), path_of(path)).lower()]


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


def segment_commands(path, *, radius: float, color: int, opacity: float = 1.0) -> list[dict]:
    """A unit cylinder at ``path``; place it with ``SetTransform(segment_matrix(a, b), path)``."""
    return [SetObject(mg.Cylinder(1.0, radius), _material(color, opacity), path_of(path)).lower()]


def path_line_command(path, points: np.ndarray, *, color: int, opacity: float = 1.0) -> dict:
    """A polyline through ``points`` ``(n_points, 3)``."""
    points = np.asarray(points, dtype=np.float32)
    material = mg.LineBasicMaterial(color=color, linewidth=2, opacity=opacity, transparent=opacity < 1.0)
    return SetObject(mg.Line(mg.PointsGeometry(points.T), material), path=path_of(path)).lower()


def ribbon_command(path, points: np.ndarray, *, width: float, color: int, normal=(0.0, 0.0, 1.0),
                   opacity: float = 1.0) -> dict:
    """A flat band ``width`` wide along ``points`` ``(n, 3)``, facing ``normal``, in one unlit colour.

    WebGL draws every line one pixel wide whatever its ``linewidth``; a band keeps a traced path or
    a flight visible at any zoom.
    """
    points = np.asarray(points, dtype=np.float64)
    if len(points) == 1:
        points = np.vstack([points, points])
    side = np.cross(np.gradient(points, axis=0), np.asarray(normal, dtype=np.float64))
    length = np.linalg.norm(side, axis=1, keepdims=True)
    side = side / np.where(length > 0, length, 1.0) * (width / 2.0)
    vertices = np.empty((2 * len(points), 3), dtype=np.float32)
    vertices[0::2], vertices[1::2] = points + side, points - side
    i = 2 * np.arange(len(points) - 1)
    faces = np.vstack([np.column_stack([i, i + 1, i + 2]), np.column_stack([i + 1, i + 3, i + 2])])
    faces = np.vstack([faces, faces[:, ::-1]]).astype(np.uint32)  # seen from both sides
    material = mg.MeshBasicMaterial(color=color, opacity=opacity, transparent=opacity < 1.0)
    return SetObject(mg.TriangularMeshGeometry(vertices, faces), material, path_of(path)).lower()


def segments_command(path, starts: np.ndarray, ends: np.ndarray, *, color: int, opacity: float = 1.0) -> dict:
    """Separate line segments ``starts[k]`` -> ``ends[k]`` (``(n, 3)`` each), drawn as one object."""
    points = np.empty((2 * len(starts), 3), dtype=np.float32)
    points[0::2], points[1::2] = starts, ends
    material = mg.LineBasicMaterial(color=color, opacity=opacity, transparent=opacity < 1.0)
    return SetObject(mg.LineSegments(mg.PointsGeometry(points.T), material), path=path_of(path)).lower()


def nice_step(span: float, *, n_lines: int = 10) -> float:
    """A round spacing (1, 2 or 5 times a power of ten) giving about ``n_lines`` lines over ``span``."""
    raw = max(float(span), 1e-9) / n_lines
    power = 10.0 ** math.floor(math.log10(raw))
    return next(m * power for m in (1.0, 2.0, 5.0, 10.0) if m * power >= raw)


def grid_commands(path, low, high, *, step: float, z: float = 0.0, color: int = 0xB8BEC8,
                  opacity: float = 0.6) -> list[dict]:
    """A faint square grid of spacing ``step`` over the x-y box ``low``-``high`` at height ``z``, lines on multiples of ``step``."""
    xs = np.arange(math.ceil(low[0] / step), math.floor(high[0] / step) + 1) * step
    ys = np.arange(math.ceil(low[1] / step), math.floor(high[1] / step) + 1) * step
    starts = [[x, low[1], z] for x in xs] + [[low[0], y, z] for y in ys]
    ends = [[x, high[1], z] for x in xs] + [[high[0], y, z] for y in ys]
    return [segments_command(path, np.array(starts), np.array(ends), color=color, opacity=opacity)]


def background_commands(top=(0.97, 0.98, 0.99), bottom=(0.86, 0.88, 0.91)) -> list[dict]:
    """A light, quiet background gradient (meshcat's default sky blue to midnight blue is loud)."""
    return [SetProperty("top_color", list(top), path_of("/Background")).lower(),
            SetProperty("bottom_color", list(bottom), path_of("/Background")).lower()]


def camera_commands(center, view_direction, distance: float, *, hide_grid: bool = True,
                    fov: float = FOV_DEGREES) -> list[dict]:
    """Look at ``center`` from ``distance`` along ``view_direction`` (world vectors).

    meshcat 0.3.2's orbiting camera always looks at the world origin, so the drawing under
    ``/meshcat`` is shifted by ``-center`` instead; and the camera's position is written in
    three.js's y-up frame, so a world offset (x, y, z) is given as (x, z, -y).
    """
    direction = np.asarray(view_direction, dtype=np.float64)
    direction = direction / np.linalg.norm(direction)
    offset = distance * direction
    camera = path_of("/Cameras/default/rotated/<object>")
    commands = [
        SetTransform(translation(-np.asarray(center, dtype=np.float64)), path_of("/meshcat")).lower(),
        SetProperty("position", [float(offset[0]), float(offset[2]), float(-offset[1])], camera).lower(),
        SetProperty("fov", float(fov), camera).lower(),
        # Depth precision goes as distance^2 / near: a near plane that grows with the distance keeps
        # marks a millimetre above a ground from flickering through it.
        SetProperty("near", float(max(0.01, 0.01 * distance)), camera).lower(),
        SetProperty("far", float(max(100.0, 200.0 * distance)), camera).lower(),
    ]
    if hide_grid:
        commands.append(SetProperty("visible", False, path_of("/Grid")).lower())
        commands.append(SetProperty("visible", False, path_of("/Axes")).lower())
    return commands


def fit_camera(low, high, view_direction, *, margin: float = 0.06, fov: float = FOV_DEGREES,
               aspect: float = ASPECT) -> list[dict]:
    """Camera commands that look along ``-view_direction`` and hold the box ``low``-``high`` in the frame.

    The box's eight corners are projected on the camera's screen axes (screen up is the world z
    seen from the side, the world y seen from above); the distance is the least at which every
    corner lies within the field of view, plus ``margin`` of the frame on each side.
    """
    low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    center = (low + high) / 2.0
    back = np.asarray(view_direction, dtype=np.float64)
    back = back / np.linalg.norm(back)
    right = np.cross([0.0, 0.0, 1.0], back)
    if np.linalg.norm(right) < 1e-6:  # straight down: screen up is the world y
        right = np.array([1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    tan_v = math.tan(math.radians(fov) / 2.0) * (1.0 - 2.0 * margin)
    tan_h = tan_v * aspect
    corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                        for z in (low[2], high[2])]) - center
    distance = max(float(c @ back) + max(abs(float(c @ right)) / tan_h, abs(float(c @ up)) / tan_v)
                   for c in corners)
    return camera_commands(center, back, max(distance, 1e-3), fov=fov)


def animation_command(frames: list[list[dict]], *, fps: float = 30.0, repetitions: int = 1000) -> dict:
    """Turn frames of ``set_transform`` commands into one meshcat ``set_animation`` command.

    Args:
      frames: frame k is the list of ``set_transform`` commands that hold at time ``k / fps``;
        other command types are ignored (meshcat animates transforms only). A node need not be
        in every frame: between two frames that give it, it moves linearly from one pose to the
        other (give it in two neighbouring frames to jump); before its first and after its last
        it holds still. Every node's clip runs from frame 0 to the last frame, so all loop together.
      fps: frames per second of playback.
      repetitions: how many times the clip plays (meshcat has no "forever").

    Returns:
      A lowered ``set_animation`` command with position, quaternion and scale tracks.
    """
    keys: dict[str, list[tuple[int, list, list, list]]] = {}
    for k, frame in enumerate(frames):
        for command in frame:
            if command["type"] != "set_transform":
                continue
            matrix = np.asarray(command["matrix"], dtype=np.float64).reshape(4, 4).T  # meshcat is column-major
            scale = np.linalg.norm(matrix[:3, :3], axis=0)
            rotation = np.eye(4)
            rotation[:3, :3] = matrix[:3, :3] / np.where(scale > 0, scale, 1.0)
            w, x, y, z = tf.quaternion_from_matrix(rotation)
            track = keys.setdefault(command["path"], [])
            value = ([float(v) for v in matrix[:3, 3]], [float(x), float(y), float(z), float(w)],
                     [float(v) for v in scale])
            if track and track[-1][0] == k:
                track[-1] = (k, *value)  # the last command for a node in a frame wins
            else:
                track.append((k, *value))
    last = len(frames) - 1
    animations = []
    for path, track in keys.items():
        if track[0][0] != 0:
            track.insert(0, (0, *track[0][1:]))
        if track[-1][0] != last:
            track.append((last, *track[-1][1:]))
        tracks = [
            {"name": "." + name, "type": kind, "keys": _without_repeats([{"time": key[0], "value": key[i]}
                                                                        for key in track])}
            for i, (name, kind) in enumerate((("position", "vector3"), ("quaternion", "quaternion"),
                                              ("scale", "vector3")), start=1)
        ]
        animations.append({"path": path, "clip": {"fps": float(fps), "name": "default", "tracks": tracks}})
    return {"type": "set_animation", "animations": animations, "options": {"play": True, "repetitions": repetitions},
            "path": ""}


def _without_repeats(keys: list[dict]) -> list[dict]:
    """The keys without those equal to both neighbours (interpolating between the neighbours gives them)."""
    kept = keys[:1]
    for k in range(1, len(keys) - 1):
        if not (keys[k]["value"] == kept[-1]["value"] == keys[k + 1]["value"]):
            kept.append(keys[k])
    return kept + keys[1:][-1:]
