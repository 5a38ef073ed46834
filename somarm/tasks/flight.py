"""Projectile flights simulated in MuJoCo: many projectiles per model, landing located in-step.

Every projectile has a slide joint ``x`` and a slide joint ``height``; gravity is the model's,
the drag ``-Fr v_x`` is joint damping and the constant ``-Fr W`` a generalised force held
through the flight, so RK4 integrates the whole law inside each step. The flight ends in the
step where the height reaches 0. The height is exactly quadratic inside a step (constant
acceleration, which RK4 integrates exactly), so the crossing time is the root of that
quadratic, and x at that time is the cubic Hermite interpolant of the positions and
velocities at both ends of the step (no extra step, no lag).

The RK4 step is chosen per throw from an a-priori bound on the landing error. Horizontally
RK4 multiplies ``u = v + W`` by the quartic Taylor polynomial R of exp(-k h) each step, and
the position sums those steps exactly, so after N steps the simulated landing differs from
Eq. 7 by ``u0 (exp(-kT) - R^N) / k``; to leading order that is at most
``|u0| k^3 h^4 / (120 e)``, and the Hermite interpolation adds at most ``|u0| k^3 h^4 / 384``.
``step_for`` picks the largest step of a fixed ladder whose bound stays under the tolerance:
drag-free throws take the largest step, the strongest drag and wind of Table 6 0.25. The
bound is the leading term in k h, good while k h stays small (k h <= 0.2 in Table 6). A throw's
step depends only on its own velocity and parameters, never on the rest of the batch, so a
throw lands at the same x alone or in any batch.

Large batches are sorted by step and u_y (the flight time grows with it), cut into chunks of similar
flights, and the chunks shared between threads, each with its own model copy: a chunk stops
when its longest flight lands, and MuJoCo releases the GIL while it steps.
"""

from __future__ import annotations

import math
import threading

import mujoco
import numpy as np

from somarm.tasks.assets import model_path
from somarm.tasks.pool import shared_pool

__all__ = ["DEFAULT_TOLERANCE", "STEP_LADDER", "error_bound", "step_for", "fly", "max_steps_for",
           "ProjectileBatch", "landing_x"]

#: This project's bound on the landing error of one throw, used to pick its RK4 step: half of
#: 1e-6, and about twice what the largest errors measured over Table 6's box reach.
DEFAULT_TOLERANCE = 5e-7
#: The steps a throw may use, largest first (round values, so that flight times of round u_y
#: fall on whole steps, the case where interpolation error hides; the tests use random u_y).
STEP_LADDER: tuple[float, ...] = (1.0, 0.8, 0.5, 0.4, 0.25, 0.2, 0.125, 0.1, 0.05, 0.025)
_BOUND_FACTOR = 1.0 / (120.0 * math.e) + 1.0 / 384.0
_CHUNK = 256
#: Threads for batches of more than one chunk (2 by default: a small machine); see ``tasks.set_threads``.
THREADS = 2


def error_bound(ux, W, k, step) -> np.ndarray:
    """Leading-order bound on the simulated landing error: ``|ux + W| k^3 h^4 (1/(120 e) + 1/384)``."""
    return np.abs(np.asarray(ux) + W) * np.asarray(k) ** 3 * np.asarray(step) ** 4 * _BOUND_FACTOR


def step_for(ux, W, k, *, tolerance: float = DEFAULT_TOLERANCE) -> np.ndarray:
    """The largest step of ``STEP_LADDER`` whose ``error_bound`` is within ``tolerance``, per throw.

    Args:
      ux, W, k: launch x velocity, wind and drag rate Fr / M (arrays that broadcast).
      tolerance: the bound to respect (> 0); throws that no step satisfies get the smallest.

    Returns:
      Steps of the broadcast shape.
    """
    ux, W, k = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (ux, W, k)))
    step = np.full(ux.shape, STEP_LADDER[-1])
    for h in reversed(STEP_LADDER[:-1]):
        step = np.where(error_bound(ux, W, k, h) <= tolerance, h, step)
    return step


def _locate(z0, w0, x0, v0, x1, v1, *, gravity: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """x where the height crosses 0 inside a step from (z0, w0) to below 0, and the time into the step."""
    disc = np.sqrt(np.maximum(w0 * w0 + 2.0 * gravity * z0, 0.0))
    rising = w0 >= 0.0
    # Two forms of the same positive root, each free of cancellation on its side.
    tau = np.where(rising, (w0 + disc) / gravity, 2.0 * z0 / np.where(rising, 1.0, disc - w0))
    s = np.clip(tau / dt, 0.0, 1.0)
    s2 = s * s
    s3 = s2 * s
    x = ((2 * s3 - 3 * s2 + 1) * x0 + (s3 - 2 * s2 + s) * dt * v0
         + (3 * s2 - 2 * s3) * x1 + (s3 - s2) * dt * v1)
    return x, s * dt


def fly(model: mujoco.MjModel, data: mujoco.MjData, *, x: slice | np.ndarray, z: slice | np.ndarray,
        max_steps: int, previous: tuple[np.ndarray, np.ndarray] | None = None,
        history: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step from the current state until every projectile is back at height 0.

    Args:
      model, data: a model whose projectiles have x dofs ``x`` and height dofs ``z`` (qpos and
        qvel addresses coincide for slide joints), launched already (qpos, qvel set).
      max_steps: a bound on the steps (the longest flight plus a margin).
      previous: ``(qpos, qvel)`` before a step already taken (the dm_env path takes the first
        step itself); that step is checked for a landing like the others.
      history: (one projectile only) also return the times ``(T,)`` and qpos ``(T, nq)`` of
        the launch and of every step, the last row replaced by the located landing point.

    Returns:
      Landing x of every projectile, shape ``(n,)``; with ``history``, ``(landing, times, qpos)``.

    Raises:
      RuntimeError: a projectile is still in the air after ``max_steps``.
    """
    gravity = -float(model.opt.gravity[2])
    dt = float(model.opt.timestep)
    qpos, qvel = data.qpos, data.qvel
    positions = np.empty((max_steps + 2, model.nq))
    velocities = np.empty((max_steps + 2, model.nv))
    if previous is None:
        positions[0], velocities[0] = qpos, qvel
        row = 0
    else:
        positions[0], velocities[0] = previous
        positions[1], velocities[1] = qpos, qvel
        row = 1
    # Launched from height 0, a projectile has landed once it is at or below 0 after a step, and
    # it keeps falling after that: "all landed" is "a step taken and the highest height <= 0".
    while row == 0 or positions[row, z].max() > 0.0:
        if row > max_steps:
            raise RuntimeError(f"projectile(s) still flying after {max_steps} steps")
        mujoco.mj_step(model, data)
        row += 1
        positions[row], velocities[row] = qpos, qvel
    heights = positions[1:row + 1, z]
    after = np.argmax(heights <= 0.0, axis=0) + 1  # first row at or below the ground, >= 1
    cols = np.arange(heights.shape[1])
    px, pz = positions[:, x], positions[:, z]
    vx, vz = velocities[:, x], velocities[:, z]
    before = after - 1
    landing, tau = _locate(pz[before, cols], vz[before, cols], px[before, cols], vx[before, cols],
                           px[after, cols], vx[after, cols], gravity=gravity, dt=dt)
    if not history:
        return landing
    if heights.shape[1] != 1:
        raise ValueError("history is for a single projectile")
    last = int(after[0])
    times = np.arange(last + 1) * dt
    times[last] = before[0] * dt + tau[0]
    path = positions[:last + 1].copy()
    path[last, x], path[last, z] = landing, 0.0
    return landing, times, path


def max_steps_for(uy_max: float, *, G: float, dt: float) -> int:
    """Steps that cover a flight launched upwards at ``uy_max``, with a margin of two."""
    return int(math.ceil(2.0 * max(uy_max, 0.0) / (G * dt))) + 2


class ProjectileBatch:
    """``n`` projectiles in one MuJoCo model, built from ``models/launcher.xml``'s options.

    Args:
      n: projectiles in the model (a chunk of a larger batch).
      G: gravity.
    """

    def __init__(self, n: int, *, G: float):
        base = mujoco.MjModel.from_xml_path(str(model_path("launcher")))
        body = base.body("projectile")
        mass, inertia = float(body.mass[0]), " ".join(f"{v:.17g}" for v in body.inertia)
        projectiles = "".join(
            f'<body name="projectile{i}"><inertial pos="0 0 0" mass="{mass:.17g}" diaginertia="{inertia}"/>'
            f'<joint name="x{i}" axis="1 0 0"/><joint name="height{i}" axis="0 0 1"/></body>'
            for i in range(n)
        )
        xml = (f'<mujoco model="launcher_batch"><option gravity="0 0 {-G!r}"/>'
               f'<default><joint type="slide" limited="false"/></default>'
               f"<worldbody>{projectiles}</worldbody></mujoco>")
        self.model = mujoco.MjModel.from_xml_string(xml)
        # The same integrator and switched-off features as the launcher model itself.
        self.model.opt.integrator = base.opt.integrator
        self.model.opt.disableflags = base.opt.disableflags
        self.data = mujoco.MjData(self.model)
        self.n, self.G = n, float(G)
        self._x, self._z = slice(0, 2 * n, 2), slice(1, 2 * n, 2)

    def land(self, ux, uy, Fr, W, M, *, dt: float) -> np.ndarray:
        """Landing x for up to ``n`` throws (1-D arrays of length ``m <= n``) with RK4 step ``dt``."""
        m = len(ux)
        model, data = self.model, self.data
        mass = np.ones(self.n)
        mass[:m] = M
        if not np.array_equal(model.body_mass[1:], mass):
            model.body_mass[1:] = mass
            mujoco.mj_setConst(model, data)  # the cached diagonal mass must follow body_mass
        mujoco.mj_resetData(model, data)
        model.opt.timestep = dt
        model.dof_damping[self._x] = 0.0
        model.dof_damping[self._x][:m] = Fr
        data.qfrc_applied[self._x][:m] = -np.asarray(Fr) * W
        data.qvel[self._x][:m] = ux
        data.qvel[self._z][:m] = uy  # unused slots stay at rest and land in the first step
        steps = max_steps_for(float(np.max(uy, initial=0.0)), G=self.G, dt=dt)
        return fly(model, data, x=self._x, z=self._z, max_steps=steps)[:m]


_local = threading.local()


def _batch_for_thread(n: int, G: float) -> ProjectileBatch:
    cache = getattr(_local, "batches", None)
    if cache is None:
        cache = _local.batches = {}
    if (n, G) not in cache:
        cache[(n, G)] = ProjectileBatch(n, G=G)
    return cache[(n, G)]


def _model_size(m: int, largest: int) -> int:
    """Projectiles in the model for a chunk of ``m``: a power of two, so that every projectile
    stepped is (mostly) a real throw and only a few model sizes are ever built."""
    return min(largest, max(8, 1 << (m - 1).bit_length()))


def _run_chunks(chunks: list[np.ndarray], arrays, out: np.ndarray, G: float, size: int) -> None:
    ux, uy, Fr, W, M, step = arrays
    for idx in chunks:
        batch = _batch_for_thread(_model_size(len(idx), size), G)
        out[idx] = batch.land(ux[idx], uy[idx], Fr[idx], W[idx], M[idx], dt=float(step[idx[0]]))


def landing_x(ux, uy, *, G: float = 0.05, Fr=0.1, W=0.0, M=1.0, tolerance: float = DEFAULT_TOLERANCE,
              n_threads: int | None = None, chunk: int = _CHUNK) -> np.ndarray:
    """Landing x of many throws simulated in MuJoCo (unchecked: the tasks validate first).

    Args:
      ux, uy: launch velocities, broadcast with the parameters to one shape ``(...)``.
      G: gravity (a scalar for the whole batch). Fr, W, M: drag, wind and mass, per throw or scalar.
      tolerance: landing error bound that picks each throw's step (``step_for``).
      n_threads: threads for batches of more than one chunk (default ``THREADS``).
      chunk: throws per model.

    Returns:
      Landing x of shape ``(...)``.
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (ux, uy, Fr, W, M)))
    shape = arrays[0].shape
    flat = [np.ascontiguousarray(a).ravel() for a in arrays]
    total = flat[0].size
    out = np.empty(total)
    if total == 0:
        return out.reshape(shape)
    size = min(chunk, total)
    ux_, uy_, Fr_, W_, M_ = flat
    step = step_for(ux_, W_, Fr_ / M_, tolerance=tolerance)
    flat.append(step)
    order = np.lexsort((uy_, step))  # one step per chunk; similar flight times share a chunk
    bounds = np.flatnonzero(np.diff(step[order])) + 1
    chunks = [group[i:i + size] for group in np.split(order, bounds) for i in range(0, len(group), size)]
    workers = max(1, min(THREADS if n_threads is None else n_threads, len(chunks)))
    if workers == 1:
        _run_chunks(chunks, flat, out, G, size)
    else:
        pool = shared_pool(workers)
        # Interleave so that every thread gets short and long flights alike.
        futures = [pool.submit(_run_chunks, chunks[w::workers], flat, out, G, size)
                   for w in range(workers)]
        for future in futures:
            future.result()
    return out.reshape(shape)
