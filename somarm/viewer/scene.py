"""MuJoCo geoms as meshcat objects and transforms: any MJCF model shows up with no new viewer code.

Pure: builds meshcat commands (the dicts meshcat's ``SetObject(...).lower()`` returns) and
never talks to a server, so every pose can be checked against MuJoCo in a test.

Four facts shape the translation (checked in tests/viewer/test_viewer_scene.py):
meshcat has no capsule, so a capsule is a cylinder and two spheres; meshcat's (three.js's)
cylinder axis is y while MuJoCo's is z; MuJoCo sizes are half-sizes, meshcat's are full;
and poses are computed here by ``mj_kinematics`` from a state's ``qpos``, because after
``mj_step`` an ``MjData``'s ``xpos`` still holds the pose of the step before.
"""

from __future__ import annotations

from dataclasses import dataclass

import meshcat.geometry as mg
import mujoco
import numpy as np
from meshcat.commands import SetObject, SetTransform
from meshcat.path import Path

__all__ = ["GeomPart", "MujocoScene", "geom_parts", "geom_transforms", "path_of", "rgb_int"]

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
    return mg.MeshPhongMaterial(color=rgb_int(rgba), opacity=float(rgba[3]), transparent=float(rgba[3]) < 1.0)


def rgb_int(rgba) -> int:
    """``0xRRGGBB`` of an (r, g, b[, a]) colour in [0, 1] (MuJoCo's ``rgba``)."""
    red, green, blue = (int(round(255 * min(max(float(c), 0.0), 1.0))) for c in list(rgba)[:3])
    return (red << 16) | (green << 8) | blue


def _pose(position, quaternion) -> np.ndarray:
    """``(4, 4)`` from a position and a MuJoCo (w, x, y, z) quaternion."""
    matrix = np.eye(4)
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, np.asarray(quaternion, dtype=np.float64))
    matrix[:3, :3] = rotation.reshape(3, 3)
    matrix[:3, 3] = position
    return matrix


def _name(model: mujoco.MjModel, kind: mujoco.mjtObj, index: int, fallback: str) -> str:
    return mujoco.mj_id2name(model, kind, index) or f"{fallback}{index}"


class MujocoScene:
    """A MuJoCo model drawn in meshcat under one path prefix: its geoms as meshes, moved by body.

    Each body with a drawn geom gets a node ``{prefix}/{body name}`` (``world`` for the world
    body, ``body{i}`` when unnamed) whose transform is the body's world pose (``xpos``, ``xmat``);
    each geom hangs below it at ``{body}/{geom name}`` (``geom{i}`` when unnamed) with its fixed
    pose in the body frame, and the geom's meshes below that. A state is drawn by moving the
    bodies only, as MuJoCo computes them. Geoms with zero alpha, in MuJoCo's hidden groups 3-5,
    or named in ``hidden`` are not drawn.

    Args:
      model: a compiled MuJoCo model (any: this project's, Gymnasium's, dm_control's).
      prefix: meshcat path under which the model is drawn, e.g. ``"/meshcat/arm2"``.
      hidden: names of geoms not to draw (a show that draws a marker of its own in their place).
    """

    def __init__(self, model: mujoco.MjModel, *, prefix: str = "/meshcat/model", hidden=()) -> None:
        self.model = model
        self.data = mujoco.MjData(model)
        self.prefix = path_of(prefix)
        geom_names = [_name(model, mujoco.mjtObj.mjOBJ_GEOM, i, "geom") for i in range(model.ngeom)]
        visible = (model.geom_rgba[:, 3] > 0) & (model.geom_group <= 2)
        visible &= np.array([name not in set(hidden) for name in geom_names], dtype=bool)
        self.geom_ids = np.flatnonzero(visible)
        self.names = [geom_names[i] for i in self.geom_ids]
        self.parts = {int(i): geom_parts(model, int(i)) for i in self.geom_ids}
        self.body_ids = np.unique(model.geom_bodyid[self.geom_ids]).astype(int)
        self.body_names = ["world" if b == 0 else _name(model, mujoco.mjtObj.mjOBJ_BODY, int(b), "body")
                           for b in self.body_ids]
        if len(set(self.body_names)) != len(self.body_names):
            raise ValueError("body names must be unique to be drawn")
        self._body_of = {int(g): self.body_names[int(np.searchsorted(self.body_ids, model.geom_bodyid[g]))]
                         for g in self.geom_ids}
        # Bodies welded to the world and not mocap never move: sent once, not every frame.
        self.moving = (model.body_weldid[self.body_ids] != 0) | (model.body_mocapid[self.body_ids] >= 0)

    def node(self, geom_name: str) -> Path:
        """The meshcat path of a drawn geom's node (below its body's)."""
        geom_id = int(self.geom_ids[self.names.index(geom_name)])
        return self.prefix.append(self._body_of[geom_id]).append(geom_name)

    def body_node(self, body_name: str) -> Path:
        """The meshcat path of a body's node."""
        return self.prefix.append(body_name)

    def setup_commands(self) -> list[dict]:
        """Every geom's meshes with their fixed poses (mesh in geom, geom in body)."""
        commands = []
        model = self.model
        for geom_id, name in zip(self.geom_ids, self.names, strict=True):
            node = self.node(name)
            commands.append(SetTransform(_pose(model.geom_pos[geom_id], model.geom_quat[geom_id]), node).lower())
            for part in self.parts[int(geom_id)]:
                path = node.append(part.name)
                commands.append(SetObject(part.geometry, _material(model, int(geom_id)), path).lower())
                commands.append(SetTransform(part.local, path).lower())
        return commands

    def set_state(self, state=None, *, mocap_pos: np.ndarray | None = None,
                  mocap_quat: np.ndarray | None = None) -> mujoco.MjData:
        """Put a state into the scene's own data and compute its kinematics.

        Args:
          state: joint positions ``(nq,)``, an ``MjData`` of this model (its ``qpos`` and mocap
            poses are read, never changed), or None for the model's ``qpos0``.
          mocap_pos, mocap_quat: ``(nmocap, 3)``, ``(nmocap, 4)`` mocap poses (override the state's).

        Returns:
          The scene's data, with body, geom and site poses of the state.

        Raises:
          ValueError: ``qpos`` not of shape ``(nq,)`` or mocap poses of the wrong shape.
        """
        model, data = self.model, self.data
        if isinstance(state, mujoco.MjData):
            data.qpos[:] = state.qpos
            data.mocap_pos[:] = state.mocap_pos
            data.mocap_quat[:] = state.mocap_quat
        elif state is None:
            data.qpos[:] = model.qpos0
        else:
            qpos = np.asarray(state, dtype=np.float64)
            if qpos.shape != (model.nq,):
                raise ValueError(f"qpos must have shape ({model.nq},), got {qpos.shape}")
            data.qpos[:] = qpos
        for name, value, width, target in (("mocap_pos", mocap_pos, 3, data.mocap_pos),
                                           ("mocap_quat", mocap_quat, 4, data.mocap_quat)):
            if value is not None:
                value = np.asarray(value, dtype=np.float64)
                if value.shape != (model.nmocap, width):
                    raise ValueError(f"{name} must have shape ({model.nmocap}, {width}), got {value.shape}")
                target[:] = value
        mujoco.mj_kinematics(model, data)
        return data

    def transforms(self, state=None, *, mocap_pos: np.ndarray | None = None) -> np.ndarray:
        """World poses ``(n_bodies, 4, 4)`` of the drawn bodies at ``state`` (as ``set_state``)."""
        data = self.set_state(state, mocap_pos=mocap_pos)
        poses = np.tile(np.eye(4), (len(self.body_ids), 1, 1))
        poses[:, :3, :3] = data.xmat[self.body_ids].reshape(-1, 3, 3)
        poses[:, :3, 3] = data.xpos[self.body_ids]
        return poses

    def geom_poses(self, state=None, *, mocap_pos: np.ndarray | None = None) -> np.ndarray:
        """World poses ``(n_drawn_geoms, 4, 4)`` of the drawn geoms: each body's pose times the geom's in it."""
        bodies = dict(zip(self.body_names, self.transforms(state, mocap_pos=mocap_pos), strict=True))
        return np.array([bodies[self._body_of[int(g)]] @ _pose(self.model.geom_pos[g], self.model.geom_quat[g])
                         for g in self.geom_ids])

    def pose_commands(self, state=None, *, mocap_pos: np.ndarray | None = None,
                      everything: bool = False) -> list[dict]:
        """``set_transform`` commands placing the bodies at ``state`` (only moving ones unless ``everything``)."""
        poses = self.transforms(state, mocap_pos=mocap_pos)
        return [
            SetTransform(poses[k], self.body_node(name)).lower()
            for k, name in enumerate(self.body_names)
            if everything or self.moving[k]
        ]

    def extent(self, state=None) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` world corners of the box around every drawn geom at ``state`` (planes aside).

        Each geom's own bounding box (``geom_aabb``, in the geom frame) is turned into the world, so a
        long thin capsule adds its length, not the sphere around it.
        """
        data = self.set_state(state)
        model = self.model
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
        keep = [int(g) for g in self.geom_ids if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_PLANE]
        if not keep:  # only planes: their centres
            centres = data.geom_xpos[self.geom_ids]
            return centres.min(axis=0), centres.max(axis=0)
        aabb = model.geom_aabb[keep]  # (n, 6): centre and half-sizes in the geom frame
        local = aabb[:, None, :3] + signs[None] * aabb[:, None, 3:]
        rotation = data.geom_xmat[keep].reshape(-1, 3, 3)
        world = np.einsum("nij,nkj->nki", rotation, local) + data.geom_xpos[keep][:, None, :]
        return world.reshape(-1, 3).min(axis=0), world.reshape(-1, 3).max(axis=0)
