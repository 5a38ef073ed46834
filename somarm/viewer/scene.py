"""MuJoCo geoms as meshcat objects and transforms: any MJCF model shows up with no new viewer code.

Pure: builds meshcat commands (the dicts meshcat's ``SetObject(...).lower()`` returns) and
never talks to a server, so every pose can be checked against MuJoCo in a test.

Four facts shape the translation (checked in tests/test_viewer_scene.py):
meshcat has no capsule, so a capsule is a cylinder and two spheres; meshcat's (three.js's)
cylinder axis is y while MuJoCo's is z; MuJoCo sizes are half-sizes, meshcat's are full;
and geom poses must be read after ``mj_kinematics``, because after ``mj_step`` ``geom_xpos``
still holds the pose of the step before.
"""

from __future__ import annotations

from dataclasses import dataclass

import meshcat.geometry as mg
import mujoco
import numpy as np
from meshcat.commands import SetObject, SetTransform
from meshcat.path import Path

__all__ = ["GeomPart", "MujocoScene", "geom_parts", "geom_transforms", "path_of"]

#: x rotated by +90 degrees: carries three.js's cylinder axis (y) onto MuJoCo's (z).
_Y_TO_Z = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
#: An infinite MuJoCo plane (size 0) is drawn this many model extents wide.
_INFINITE_PLANE_EXTENTS = 3.0
_PLANE_THICKNESS = 1e-3


@dataclass(frozen=True)
class GeomPart:
    """One meshcat mesh of a geom, fixed in the geom's frame.

    Attributes:
      name: child path under the geom's node ("shape", or "cylinder"/"cap0"/"cap1" of a capsule).
      geometry: a meshcat geometry with full (not half) sizes.
      local: ``(4, 4)`` pose of the part in the geom frame.
    """

    name: str
    geometry: mg.Geometry
    local: np.ndarray


def path_of(parts: str | tuple[str, ...] | Path) -> Path:
    """A meshcat ``Path`` from ``"/a/b"``, ``("a", "b")`` or a ``Path``."""
    if isinstance(parts, Path):
        return parts
    if isinstance(parts, str):
        parts = tuple(p for p in parts.split("/") if p)
    return Path(tuple(parts))


def _translation(xyz) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = xyz
    return matrix


def geom_parts(model: mujoco.MjModel, geom_id: int) -> list[GeomPart]:
    """The meshcat meshes that draw geom ``geom_id`` of ``model``.

    Args:
      model: a compiled MuJoCo model.
      geom_id: index into ``model.geom_*``.

    Returns:
      One part per mesh (three for a capsule), with full sizes and poses in the geom frame.

    Raises:
      ValueError: a geom type this viewer cannot draw (height fields, signed-distance fields).
    """
    kind = int(model.geom_type[geom_id])
    size = np.asarray(model.geom_size[geom_id], dtype=np.float64)
    g = mujoco.mjtGeom
    if kind == g.mjGEOM_SPHERE:
        return [GeomPart("shape", mg.Sphere(size[0]), np.eye(4))]
    if kind == g.mjGEOM_BOX:
        return [GeomPart("shape", mg.Box(list(2.0 * size)), np.eye(4))]
    if kind == g.mjGEOM_ELLIPSOID:
        # A unit sphere scaled by the radii, which are MuJoCo's three half-sizes.
        return [GeomPart("shape", mg.Sphere(1.0), np.diag([*size, 1.0]))]
    if kind == g.mjGEOM_CYLINDER:
        return [GeomPart("shape", mg.Cylinder(2.0 * size[1], size[0]), _Y_TO_Z)]
    if kind == g.mjGEOM_CAPSULE:
        radius, half = size[0], size[1]
        return [
            GeomPart("cylinder", mg.Cylinder(2.0 * half, radius), _Y_TO_Z),
            GeomPart("cap0", mg.Sphere(radius), _translation([0.0, 0.0, -half])),
            GeomPart("cap1", mg.Sphere(radius), _translation([0.0, 0.0, half])),
        ]
    if kind == g.mjGEOM_PLANE:
        half_x, half_y = size[0], size[1]
        default = _INFINITE_PLANE_EXTENTS * max(float(model.stat.extent), 1e-3)
        half_x = half_x if half_x > 0 else default
        half_y = half_y if half_y > 0 else default
        # A thin box whose top face is the plane, so nothing pokes through it.
        box = mg.Box([2.0 * half_x, 2.0 * half_y, _PLANE_THICKNESS])
        return [GeomPart("shape", box, _translation([0.0, 0.0, -_PLANE_THICKNESS / 2]))]
    if kind == g.mjGEOM_MESH:
        mesh_id = int(model.geom_dataid[geom_id])
        v0, nv = model.mesh_vertadr[mesh_id], model.mesh_vertnum[mesh_id]
        f0, nf = model.mesh_faceadr[mesh_id], model.mesh_facenum[mesh_id]
        vertices = model.mesh_vert[v0 : v0 + nv]
        faces = model.mesh_face[f0 : f0 + nf]
        return [GeomPart("shape", mg.TriangularMeshGeometry(vertices, faces), np.eye(4))]
    name = mujoco.mjtGeom(kind).name
    raise ValueError(f"geom {geom_id} has type {name}; the viewer draws plane, sphere, capsule, "
                     "ellipsoid, cylinder, box and mesh geoms")


def geom_transforms(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """World poses of all geoms for ``data.qpos`` (and mocap poses), after ``mj_kinematics``.

    Args:
      model, data: the model and a data whose ``qpos``/``mocap_*`` are set.

    Returns:
      ``(n_geom, 4, 4)`` homogeneous transforms.
    """
    mujoco.mj_kinematics(model, data)
    transforms = np.zeros((model.ngeom, 4, 4))
    transforms[:, :3, :3] = data.geom_xmat.reshape(-1, 3, 3)
    transforms[:, :3, 3] = data.geom_xpos
    transforms[:, 3, 3] = 1.0
    return transforms


def _material(model: mujoco.MjModel, geom_id: int) -> mg.MeshPhongMaterial:
    mat_id = int(model.geom_matid[geom_id])
    rgba = model.mat_rgba[mat_id] if mat_id >= 0 else model.geom_rgba[geom_id]
    red, green, blue = (int(round(255 * float(c))) for c in rgba[:3])
    alpha = float(rgba[3])
    return mg.MeshPhongMaterial(
        color=(red << 16) | (green << 8) | blue, opacity=alpha, transparent=alpha < 1.0
    )


class MujocoScene:
    """A MuJoCo model drawn in meshcat under one path prefix.

    Each visible geom gets a node ``{prefix}/{geom name}`` (``geom{i}`` when unnamed) whose
    transform is the geom's world pose; its meshes hang below it with fixed local poses.
    Geoms with zero alpha, or in MuJoCo's hidden groups 3-5, are not drawn.

    Args:
      model: a compiled MuJoCo model.
      prefix: meshcat path under which the model is drawn, e.g. ``"/meshcat/arm2"``.
    """

    def __init__(self, model: mujoco.MjModel, *, prefix: str = "/meshcat/model") -> None:
        self.model = model
        self.data = mujoco.MjData(model)
        self.prefix = path_of(prefix)
        visible = (model.geom_rgba[:, 3] > 0) & (model.geom_group <= 2)
        self.geom_ids = np.flatnonzero(visible)
        self.names = [
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(i)) or f"geom{i}" for i in self.geom_ids
        ]
        if len(set(self.names)) != len(self.names):
            raise ValueError("geom names must be unique to be drawn")
        self.parts = {int(i): geom_parts(model, int(i)) for i in self.geom_ids}
        # Geoms on the world body or on static bodies never move: sent once, not every frame.
        static = model.body_weldid[model.geom_bodyid[self.geom_ids]] == 0
        static &= model.body_mocapid[model.geom_bodyid[self.geom_ids]] < 0
        self.moving = ~static

    def node(self, geom_name: str) -> Path:
        """The meshcat path of a geom's node."""
        return self.prefix.append(geom_name)

    def setup_commands(self) -> list[dict]:
        """``set_object`` and fixed local ``set_transform`` commands for every part of every geom."""
        commands = []
        for geom_id, name in zip(self.geom_ids, self.names, strict=True):
            for part in self.parts[int(geom_id)]:
                path = self.node(name).append(part.name)
                commands.append(SetObject(part.geometry, _material(self.model, int(geom_id)), path).lower())
                commands.append(SetTransform(part.local, path).lower())
        return commands

    def transforms(self, qpos: np.ndarray | None = None, *, mocap_pos: np.ndarray | None = None) -> np.ndarray:
        """World poses ``(n_drawn, 4, 4)`` of the drawn geoms at ``qpos`` (default: the model's qpos0).

        Raises:
          ValueError: ``qpos`` not of shape ``(nq,)`` or ``mocap_pos`` not ``(nmocap, 3)``.
        """
        model, data = self.model, self.data
        if qpos is None:
            data.qpos[:] = model.qpos0
        else:
            qpos = np.asarray(qpos, dtype=np.float64)
            if qpos.shape != (model.nq,):
                raise ValueError(f"qpos must have shape ({model.nq},), got {qpos.shape}")
            data.qpos[:] = qpos
        if mocap_pos is not None:
            mocap_pos = np.asarray(mocap_pos, dtype=np.float64)
            if mocap_pos.shape != (model.nmocap, 3):
                raise ValueError(f"mocap_pos must have shape ({model.nmocap}, 3), got {mocap_pos.shape}")
            data.mocap_pos[:] = mocap_pos
        return geom_transforms(model, data)[self.geom_ids]

    def pose_commands(
        self, qpos: np.ndarray | None = None, *, mocap_pos: np.ndarray | None = None, everything: bool = False
    ) -> list[dict]:
        """``set_transform`` commands placing the geoms at ``qpos`` (only moving ones unless ``everything``)."""
        poses = self.transforms(qpos, mocap_pos=mocap_pos)
        return [
            SetTransform(poses[k], self.node(name)).lower()
            for k, name in enumerate(self.names)
            if everything or self.moving[k]
        ]
