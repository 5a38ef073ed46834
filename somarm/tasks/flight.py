"""Projectile flights simulated in MuJoCo: many projectiles per model, landing located in-step.

Every projectile has a slide joint ``x`` and a slide joint ``height``; gravity is the model's,
the drag ``-Fr v_x`` is joint damping and the constant ``-Fr W`` a generalised force held
through the flight, so RK4 integrates the whole law inside each step. The flight ends in the
step where the height reaches 0. The height is exactly quadratic inside a step (constant
acceleration, which RK4 integrates exactly), so the crossing time is the root of that
quadratic, and x at that time is the cubic Hermite interpolant of the positions and
velocities at both ends of the step (no extra step, no lag).

The RK4 step is chosen per throw from a bound on its landing error. Vertically the motion has
constant acceleration, which RK4 integrates exactly, so the flight time ``T = 2 u_y / G`` is known
before the throw; each throw takes ``N`` equal steps of ``h = T / N`` and lands at the end of its
last step, so no interpolation error enters. Horizontally RK4 multiplies ``u = v + W`` by the
quartic Taylor polynomial R(z) of exp(-z), ``z = k h``, each step, and moves x by exactly
``(1 - R) u / k``, so after N steps the simulated landing differs from Eq. 7 by
``|u0| (R^N - exp(-kT)) / k``. The alternating tail of exp(-z) gives
``1 <= R exp(z) <= 1 + d``, ``d = exp(z) z^5 / 120`` (for z <= 1), hence the bound
``|u0| exp(-kT) expm1(N d) / k``, about ``|u0| k^4 h^4 T exp(-kT) / 120``. ``step_for`` picks
the smallest N within the tolerance: drag-free throws take one step, Table 6's strongest drag and
wind about 60. (A fixed ladder of round step sizes under a leading-order bound over every flight
time would take about twice the steps.)

Throws of different steps share one model through a change of time scale: a throw whose step
is ``c`` is simulated in the time ``s = t / c`` with the model's step ``SCALED_STEP = 1``, its
height divided by ``c^2`` (so gravity stays the model's) and its drag rate multiplied by ``c``
(damping ``c Fr / M`` on a unit mass, force ``-c Fr W / M``; the launch velocity is
``(u_x, u_y / c)``). RK4 commutes with that linear change of variables, so each throw gets
exactly its own step's accuracy; its landing is ``c`` times the scaled x. A throw's step and
scaling depend only on the throw itself, and projectiles in one model do not interact, so a
throw lands at the same x alone, in any batch, and in the dm_env launcher.

A batch flies as the bodies of one model built for its size (and cached): the staircase. The
throws are sorted by flight length (in model steps); the model steps them all from the launch,
one native ``mujoco.rollout`` per segment (no Python per step), and after each segment the throws
that have landed are located and leave: the rest go on from their state in a model of their own
size. So a throw pays for its own steps, and the batch pays MuJoCo's fixed cost per model step
once per step of its longest flight, not once per group of similar flights. Where the segments end
is chosen by dynamic programming over a cost model (``_stairs``). A batch of more than ``cap``
throws is cut into chunks of similar flights (``_chunks``), and one that two threads finish
sooner is split in two, each group its own staircase; groups are shared between threads, each
with its own models, and MuJoCo releases the GIL while it steps. Moving a throw between models
copies its state exactly, so it lands where it lands alone.
"""

from __future__ import annotations

import math
import threading
from typing import NamedTuple

import mujoco
import numba
import numpy as np
from mujoco import rollout as mj_rollout

from somarm.tasks.assets import model_path
from somarm.tasks.ballistics import flight_time
from somarm.tasks.pool import shared_pool, threads_here

__all__ = ["DEFAULT_TOLERANCE", "MAX_KH", "SCALED_STEP", "error_bound", "step_for", "fly",
           "max_steps_for", "ProjectileBatch", "landing_x"]

#: This project's bound on the landing error of one throw, used to pick its RK4 step: 1e-6 (the
#: tasks' promise to Eq. 7) less a margin for rounding.
DEFAULT_TOLERANCE = 9e-7
#: Largest drag rate times step (the bound's alternating-series argument holds for k h <= 1).
MAX_KH = 1.0
#: The models' own step: a throw of step c runs in the time t / c (see the module docstring).
SCALED_STEP = 1.0
#: Most throws in one model: a larger batch flies as several staircases (``_groups``).
_CAP = 256
#: The fixed cost of one model step, and of one segment of a staircase (a native rollout with its
#: set-up and landings), in projectile-steps (measured: about 3.5 us per RK4 step of a model, 0.45 us
#: per projectile in it, and some 12 us per segment); they decide where the segments end.
_STEP_COST = 7.0
_SEGMENT_COST = 30.0
#: What handing a share of a batch to another thread costs, in projectile-steps (measured: about
#: 0.4 ms of submitting, waiting and sharing the GIL; below some 60 throws one thread is sooner).
_THREAD_COST = 600.0
#: Projectiles per model: a segment runs in the smallest of these that holds its throws (few models built).
_SIZES = (*range(1, 17), *range(20, 65, 4), *range(80, 257, 16))
#: ``_SIZE_OF[m]``: the model size for ``m`` throws (index 0 unused), as floats for ``_stairs``.
_SIZE_OF = np.array([0.0] + [min(s for s in _SIZES if s >= m) for m in range(1, _SIZES[-1] + 1)])
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
_FORCE = mujoco.mjtState.mjSTATE_QFRC_APPLIED
#: Threads for large batches (2 by default: a small machine); see ``tasks.set_threads``.
THREADS = 2


def _bound(u0, k, T, n):
    """``u0 exp(-kT) expm1(n d) / k`` with ``d = exp(z) z^5 / 120``, ``z = k T / n`` (0 where k = 0)."""
    safe = np.where(k > 0.0, k, 1.0)
    z = safe * T / n
    d = np.exp(z) * z ** 5 / 120.0
    with np.errstate(over="ignore"):  # a far too long step: the bound is inf, as it should read
        return np.where(k > 0.0, u0 * np.exp(-safe * T) * np.expm1(n * d) / safe, 0.0)


def error_bound(ux, uy, W, k, step, *, G: float) -> np.ndarray:
    """Bound on the simulated landing error of throws flown with RK4 step ``step`` (arrays broadcast).

    When the flight time T is a whole number N of steps (as ``step_for`` picks it) the bound is
    ``|ux + W| exp(-kT) expm1(N d) / k`` (module docstring); otherwise the landing is interpolated
    inside the last step and ``|ux + W| k^3 h^4 / 384`` (the cubic Hermite term) is added.
    """
    k, h = np.asarray(k, dtype=np.float64), np.asarray(step, dtype=np.float64)
    T = flight_time(np.maximum(uy, 0.0), G)
    u0 = np.abs(np.asarray(ux) + W)
    steps = T / h
    whole = np.abs(steps - np.round(steps)) <= 1e-9 * np.maximum(steps, 1.0)
    return _bound(u0, k, T, np.maximum(np.ceil(steps - 1e-9), 1.0)) + np.where(whole, 0.0, u0 * k ** 3 * h ** 4 / 384.0)


def step_for(ux, uy, W, k, *, G: float, tolerance: float = DEFAULT_TOLERANCE) -> np.ndarray:
    """Each throw's RK4 step: its flight time split into the fewest equal steps within ``tolerance``.

    Args:
      ux, uy, W, k: launch velocity, wind and drag rate Fr / M (arrays that broadcast).
      G: gravity.
      tolerance: the bound (``error_bound``) to respect (> 0).

    Returns:
      Steps ``T / N`` of the broadcast shape (1 for a throw that does not leave the ground).
    """
    if all(isinstance(a, float) for a in (ux, uy, W, k)):  # one throw (the dm_env path): no arrays
        return np.float64(_one_step(ux, uy, W, k, G, tolerance))
    ux, uy, W, k = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (ux, uy, W, k)))
    T = flight_time(np.maximum(uy, 0.0), G)
    u0 = np.abs(ux + W)
    # The leading term u0 k^4 h^4 T exp(-kT) / 120 gives N; the exact bound then adds a step or two.
    lead = u0 * k ** 4 * T * np.exp(-k * T) / 120.0
    with np.errstate(divide="ignore"):
        longest = np.minimum((tolerance / lead) ** 0.25, MAX_KH / np.where(k > 0.0, k, 0.0))
    n = np.maximum(np.ceil(T / longest), 1.0)
    while (over := _bound(u0, k, T, n) > tolerance).any():
        n = n + over
    return np.where(T > 0.0, T / n, 1.0)


def _one_step(ux: float, uy: float, W: float, k: float, G: float, tolerance: float) -> float:
    """``step_for`` of one throw in plain floats (the same arithmetic as the arrays')."""
    T = 2.0 * max(uy, 0.0) / G
    if T <= 0.0:
        return 1.0
    if k <= 0.0:
        return T
    u0 = abs(ux + W)
    lead = u0 * k ** 4 * T * math.exp(-k * T) / 120.0
    longest = min((tolerance / lead) ** 0.25 if lead > 0.0 else math.inf, MAX_KH / k)
    n = max(math.ceil(T / longest), 1.0)
    decay = u0 * math.exp(-k * T) / k
    while decay * math.expm1(n * math.exp(k * T / n) * (k * T / n) ** 5 / 120.0) > tolerance:
        n += 1.0
    return T / n


def _hermite(s, x0, v0, x1, v1, dt):
    """The cubic Hermite interpolant of a step's end states at the fraction ``s`` (floats or arrays)."""
    s2 = s * s
    s3 = s2 * s
    return ((2 * s3 - 3 * s2 + 1) * x0 + (s3 - 2 * s2 + s) * dt * v0
            + (3 * s2 - 2 * s3) * x1 + (s3 - s2) * dt * v1)


def _locate(z0, w0, x0, v0, x1, v1, *, gravity: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """x where the height crosses 0 inside a step from (z0, w0) to below 0, and the time into the step."""
    disc = np.sqrt(np.maximum(w0 * w0 + 2.0 * gravity * z0, 0.0))
    rising = w0 >= 0.0
    # Two forms of the same positive root, each free of cancellation on its side.
    tau = np.where(rising, (w0 + disc) / gravity, 2.0 * z0 / np.where(rising, 1.0, disc - w0))
    s = np.clip(tau / dt, 0.0, 1.0)
    return _hermite(s, x0, v0, x1, v1, dt), s * dt


#: ``_hermite`` compiled for floats (the same source, so the same arithmetic).
_hermite_one = numba.njit(cache=True, nogil=True)(_hermite)


@numba.njit(cache=True, nogil=True)
def _locate_one(z0, w0, x0, v0, x1, v1, gravity, dt):
    """``_locate``'s landing x of one projectile in floats, compiled (the dm_env path and the
    batches' ``_land_rows``): the same arithmetic in the same order (no fastmath)."""
    disc = math.sqrt(max(w0 * w0 + 2.0 * gravity * z0, 0.0))
    tau = (w0 + disc) / gravity if w0 >= 0.0 else 2.0 * z0 / (disc - w0)
    return _hermite_one(min(max(tau / dt, 0.0), 1.0), x0, v0, x1, v1, dt)


def _landings(positions: np.ndarray, velocities: np.ndarray, x, z, *, gravity: float, dt: float):
    """Landing x, step index after the landing and time into that step, from rows of states.

    ``positions`` ``(rows, nq)`` and ``velocities`` ``(rows, nv)`` start at a state before any
    landing; every projectile must be at or below 0 in the last row.
    """
    heights = positions[1:, z]
    after = np.argmax(heights <= 0.0, axis=0) + 1  # first row at or below the ground, >= 1
    cols = np.arange(heights.shape[1])
    px, pz = positions[:, x], positions[:, z]
    vx, vz = velocities[:, x], velocities[:, z]
    before = after - 1
    landing, tau = _locate(pz[before, cols], vz[before, cols], px[before, cols], vx[before, cols],
                           px[after, cols], vx[after, cols], gravity=gravity, dt=dt)
    return landing, after, tau


def fly(model: mujoco.MjModel, data: mujoco.MjData, *, x: slice | np.ndarray, z: slice | np.ndarray,
        max_steps: int, previous: tuple[np.ndarray, np.ndarray] | None = None,
        history: bool = False, scale: float = 1.0) -> np.ndarray | tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step from the current state until every projectile is back at height 0.

    Args:
      model, data: a model whose projectiles have x dofs ``x`` and height dofs ``z`` (qpos and
        qvel addresses coincide for slide joints), launched already (qpos, qvel set).
      max_steps: a bound on the steps (the longest flight plus a margin).
      previous: ``(qpos, qvel)`` before a step already taken (the dm_env path takes the first
        step itself); that step is checked for a landing like the others.
      history: (one projectile only) also return the times ``(T,)`` and qpos ``(T, nq)`` of
        the launch and of every step, the last row replaced by the located landing point.
      scale: the flight's time scale c (its real step per model step): x, height and time
        are returned as ``c x``, ``c^2 height`` and ``c t``.

    Returns:
      Landing x of every projectile, shape ``(n,)``; with ``history``, ``(landing, times, qpos)``.

    Raises:
      RuntimeError: a projectile is still in the air after ``max_steps``.
    """
    gravity = -float(model.opt.gravity[2])
    dt = float(model.opt.timestep)
    qpos, qvel = data.qpos, data.qvel
    if not history and np.size(qpos[z]) == 1:
        dofs = np.arange(model.nq)  # slide joints: qpos and qvel addresses coincide
        landing = _fly_one(model, data, int(dofs[x].item()), int(dofs[z].item()), max_steps=max_steps,
                           previous=previous, gravity=gravity, dt=dt)
        return np.array([landing * scale])
    if not history:
        # Heights are exactly quadratic: no projectile lands before its analytic landing time,
        # so step natively to two steps short of the earliest and record only from there.
        rise = np.maximum(qvel[z], 0.0)
        earliest = float(np.min((rise + np.sqrt(rise * rise + 2.0 * gravity * np.maximum(qpos[z], 0.0))) / gravity))
        skip = min(int(earliest / dt) - 2, max_steps)
        if skip > 0:
            mujoco.mj_step(model, data, nstep=skip)
            max_steps -= skip
            previous = None
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
    landing, after, tau = _landings(positions[:row + 1], velocities[:row + 1], x, z, gravity=gravity, dt=dt)
    landing = landing * scale
    if not history:
        return landing
    if len(landing) != 1:
        raise ValueError("history is for a single projectile")
    last = int(after[0])
    times = np.arange(last + 1) * dt
    times[last] = (last - 1) * dt + tau[0]
    path = positions[:last + 1].copy()
    path[:, x] *= scale
    path[:, z] *= scale * scale
    path[last, x], path[last, z] = landing, 0.0
    return landing, times * scale, path


def _fly_one(model: mujoco.MjModel, data: mujoco.MjData, x: int, z: int, *, max_steps: int,
             previous: tuple[np.ndarray, np.ndarray] | None, gravity: float, dt: float) -> float:
    """``fly`` for one projectile in plain floats (a dm_env episode): landing x in model units."""
    qpos, qvel = data.qpos, data.qvel
    rise = max(float(qvel[z]), 0.0)
    earliest = (rise + math.sqrt(rise * rise + 2.0 * gravity * max(float(qpos[z]), 0.0))) / gravity
    skip = min(int(earliest / dt) - 2, max_steps)
    if skip > 0:  # the height is exactly quadratic: no landing before this
        mujoco.mj_step(model, data, nstep=skip)
        max_steps -= skip
        previous = None
    before = None if previous is None else (float(previous[0][x]), float(previous[0][z]),
                                            float(previous[1][x]), float(previous[1][z]))
    after = (float(qpos[x]), float(qpos[z]), float(qvel[x]), float(qvel[z]))
    steps = 0
    while before is None or after[1] > 0.0:
        if steps > max_steps:
            raise RuntimeError(f"projectile(s) still flying after {max_steps} steps")
        mujoco.mj_step(model, data)
        steps += 1
        before, after = after, (float(qpos[x]), float(qpos[z]), float(qvel[x]), float(qvel[z]))
    return _locate_one(before[1], before[3], before[0], before[2], after[0], after[2], gravity, dt)


def max_steps_for(uy_max: float, *, G: float, dt: float) -> int:
    """Steps that cover a flight launched upwards at ``uy_max``: its flight time in steps (less a
    rounding allowance, for flights of a whole number of steps) and one more."""
    return int(math.ceil(2.0 * max(uy_max, 0.0) / (G * dt) - 1e-9)) + 1


class ProjectileBatch:
    """``n`` projectiles of unit mass in one MuJoCo model, with ``models/launcher.xml``'s options.

    Projectile ``i`` is body ``projectile{i}`` with the slide joints ``x{i}`` (dof 2i) and
    ``height{i}`` (dof 2i + 1). The model's step is ``SCALED_STEP``: each throw gets its own
    step by scaling (module docstring). Built once per size and thread (``_batch_for_thread``).

    Args:
      n: projectiles in the model.
      G: gravity.
    """

    def __init__(self, n: int, *, G: float):
        base = _base_model()
        inertia = " ".join(f"{v:.17g}" for v in base.body("projectile").inertia)
        projectiles = "".join(
            f'<body name="projectile{i}"><inertial pos="0 0 0" mass="1" diaginertia="{inertia}"/>'
            f'<joint name="x{i}" axis="1 0 0"/><joint name="height{i}" axis="0 0 1"/></body>'
            for i in range(n)
        )
        xml = (f'<mujoco model="launcher_batch"><option gravity="0 0 {-G!r}" timestep="{SCALED_STEP!r}"/>'
               f'<default><joint type="slide" limited="false"/></default>'
               f"<worldbody>{projectiles}</worldbody></mujoco>")
        self.model = mujoco.MjModel.from_xml_string(xml)
        # The same integrator and switched-off features as the launcher model itself.
        self.model.opt.integrator = base.opt.integrator
        self.model.opt.disableflags = base.opt.disableflags
        self.data = mujoco.MjData(self.model)
        self.n, self.G = n, float(G)
        self.n_state = mujoco.mj_stateSize(self.model, _STATE)
        #: Where qvel starts in a full-physics state row (time, qpos, qvel, ...).
        self.qvel = 1 + self.model.nq
        # Views of the x dofs' damping (the drag rate) and applied force (the wind's share of the drag).
        self._damping = self.model.dof_damping[0::2]
        self._wind = self.data.qfrc_applied[0::2]

    def roll(self, start: np.ndarray, nstep: int, rate: np.ndarray, push: np.ndarray) -> np.ndarray:
        """``nstep`` RK4 steps in one native rollout from a full-physics state row.

        Args:
          start: the state row ``(n_state,)`` to start from.
          nstep: steps to take (>= 1).
          rate, push: the drag rate (the x dofs' damping) and the force on the x dofs of the
            first ``len(rate)`` projectiles; the rest get none.

        Returns:
          The rows ``(nstep + 1, n_state)``: ``start``, then the state after every step.
        """
        m = len(rate)
        self._damping[:m] = rate
        self._damping[m:] = 0.0
        self._wind[:m] = push
        self._wind[m:] = 0.0
        rows = np.empty((nstep + 1, self.n_state))
        rows[0] = start
        # control=None with qfrc_applied in the spec: the rollout keeps the data's force throughout.
        mj_rollout.rollout([self.model], [self.data], rows[:1], None, control_spec=_FORCE, nstep=nstep,
                           state=rows[None, 1:], skip_checks=True)
        return rows


_base: list[mujoco.MjModel] = []


def _base_model() -> mujoco.MjModel:
    """``models/launcher.xml``, parsed once (its options and inertia shape every batch model)."""
    if not _base:
        _base.append(mujoco.MjModel.from_xml_path(str(model_path("launcher"))))
    return _base[0]


_local = threading.local()


def _batch_for_thread(n: int, G: float) -> ProjectileBatch:
    cache = getattr(_local, "batches", None)
    if cache is None:
        cache = _local.batches = {}
    if (n, G) not in cache:
        cache[(n, G)] = ProjectileBatch(n, G=G)
    return cache[(n, G)]


def _model_size(m: int) -> int:
    """Projectiles in the model for ``m`` throws: the smallest of ``_SIZES`` that holds them."""
    return int(_SIZE_OF[m]) if m < len(_SIZE_OF) else m


def _model_steps(lengths: np.ndarray) -> np.ndarray:
    """Model steps that cover flights of these lengths (in model steps): ``max_steps_for``'s count."""
    return np.ceil(lengths - 1e-9) + 1.0


@numba.njit(cache=True)
def _stairs_kernel(steps, size_of, step_cost, segment_cost):
    """``_stairs`` compiled: segment ends ``(landed, step)`` and the cost, by dynamic programming.

    A segment may end only after the last flight of a given length, so the choices are the
    distinct lengths: ``best[u]`` is the cheapest way to finish once the flights of the first u
    distinct lengths have landed.
    """
    n = steps.shape[0]
    ends = np.empty(n, np.int64)  # after the last flight of each distinct length
    u = 0
    for i in range(n):
        if i == n - 1 or steps[i + 1] != steps[i]:
            ends[u] = i + 1
            u += 1
    distinct = u
    best = np.full(distinct + 1, np.inf)
    best[distinct] = 0.0
    after = np.zeros(distinct + 1, np.int64)
    for u in range(distinct - 1, -1, -1):
        landed = ends[u - 1] if u > 0 else 0
        begin = steps[landed - 1] if landed > 0 else 0.0
        alive = n - landed
        per_step = step_cost + (size_of[alive] if alive < size_of.shape[0] else alive)
        for v in range(u, distinct):
            cost = segment_cost + (steps[ends[v] - 1] - begin) * per_step + best[v + 1]
            if cost < best[u]:
                best[u] = cost
                after[u] = v + 1
    count = 0
    u = 0
    while u < distinct:
        u = after[u]
        count += 1
    landed_after = np.empty(count, np.int64)
    end_step = np.empty(count, np.int64)
    u = 0
    for j in range(count):
        u = after[u]
        landed_after[j] = ends[u - 1]
        end_step[j] = int(steps[ends[u - 1] - 1])
    return landed_after, end_step, best[0]


def _stairs(steps: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The cheapest staircase for flights of ascending model steps (``_model_steps``).

    The whole batch starts in one model; each segment is one native rollout, after which the
    throws that have landed leave and the rest go on in a model of their size. A segment costs
    ``_SEGMENT_COST``, then per model step ``_STEP_COST`` plus one per projectile of its model
    (all in projectile-steps).

    Returns:
      ``(landed, end, cost)``: after segment j the first ``landed[j]`` throws have landed (by
      plan) and the flights stand at model step ``end[j]``; the last segment lands them all.
    """
    return _stairs_kernel(np.asarray(steps, dtype=np.float64), _SIZE_OF, _STEP_COST, _SEGMENT_COST)


@numba.njit(cache=True, nogil=True)
def _land_segment(rows, m, qvel, gravity, slots, scale, out, keep):
    """Landings of a segment's rows for model slots ``0..m-1`` (dofs 2i and 2i+1).

    A slot is landed if its height is at or below 0 in a row after the first; its landing is
    located inside that step (``_locate_one``), times its throw's ``scale``, into
    ``out[slots[i]]``. The slots still flying go to ``keep``; returns how many.
    """
    n_rows = rows.shape[0]
    flying = 0
    for i in range(m):
        x, z = 1 + 2 * i, 2 + 2 * i
        after = 1
        while after < n_rows and rows[after, z] > 0.0:
            after += 1
        if after == n_rows:
            keep[flying] = i
            flying += 1
            continue
        b = after - 1
        throw = slots[i]
        out[throw] = _locate_one(rows[b, z], rows[b, qvel + 2 * i + 1], rows[b, x], rows[b, qvel + 2 * i],
                                 rows[after, x], rows[after, qvel + 2 * i], gravity, SCALED_STEP) * scale[throw]
    return flying


@numba.njit(cache=True, nogil=True)
def _carry(last, qvel, keep, flying, start, start_qvel):
    """The next segment's first row: time, then the kept slots' positions and velocities in order."""
    start[:] = 0.0
    start[0] = last[0]
    for j in range(flying):
        i = keep[j]
        start[1 + 2 * j] = last[1 + 2 * i]
        start[2 + 2 * j] = last[2 + 2 * i]
        start[start_qvel + 2 * j] = last[qvel + 2 * i]
        start[start_qvel + 2 * j + 1] = last[qvel + 2 * i + 1]


def _fly_stairs(arrays, out: np.ndarray, G: float) -> None:
    """Land one group of sorted throws into ``out`` (same order), as the staircase ``_stairs`` plans.

    Args:
      arrays: ``ux, uy, k, W, scale`` (each throw's RK4 step) and ``steps`` (``_model_steps``).
      out: the landings, written here.

    Raises:
      RuntimeError: a throw is still in the air after the steps that cover its flight.
    """
    ux, uy, k, W, scale, steps = arrays
    n = len(ux)
    landed, ends, _ = _stairs(steps)
    rate = scale * k
    push = -rate * W
    slots = np.arange(n)
    batch = _batch_for_thread(_model_size(n), G)
    start = np.zeros(batch.n_state)
    start[batch.qvel:batch.qvel + 2 * n:2] = ux
    start[batch.qvel + 1:batch.qvel + 2 * n:2] = uy / scale
    keep = np.empty(n, np.int64)
    begin = 0
    for planned, end in zip(landed, ends, strict=True):
        rows = batch.roll(start, int(end) - begin, rate[slots], push[slots])
        flying = _land_segment(rows, len(slots), batch.qvel, G, slots, scale, out, keep)
        if flying > n - planned:
            raise RuntimeError(f"projectile(s) still flying after {int(end)} steps")
        if flying == 0:
            return
        nxt = _batch_for_thread(_model_size(flying), G)
        start = np.empty(nxt.n_state)
        _carry(rows[-1], batch.qvel, keep, flying, start, nxt.qvel)
        slots = slots[keep[:flying]]
        batch, begin = nxt, int(end)
    raise RuntimeError(f"projectile(s) still flying after {begin} steps")  # pragma: no cover - planned away


@numba.njit(cache=True)
def _cut(steps, size_of, cap, step_cost, chunk_cost):
    """Cheapest cut of ascending flights into chunks of at most ``cap`` (dynamic programming).

    A chunk ``[a, b)`` costs ``chunk_cost + steps[b - 1] * (step_cost + size_of[b - a])``: its
    set-up, then its longest flight's steps, each a fixed cost plus one per projectile of its
    model. Returns each prefix's best last-chunk start (``start[b]`` for the chunk ending at b).
    """
    n = steps.shape[0]
    best = np.empty(n + 1)
    best[0] = 0.0
    start = np.zeros(n + 1, np.int64)
    for b in range(1, n + 1):
        lowest = np.inf
        for a in range(max(0, b - cap), b):
            cost = best[a] + chunk_cost + steps[b - 1] * (step_cost + size_of[b - a])
            if cost < lowest:
                lowest = cost
                start[b] = a
        best[b] = lowest
    return start


def _chunks(steps: np.ndarray, cap: int, chunk_cost: float = _SEGMENT_COST) -> list[tuple[int, int]]:
    """Flights of ascending model steps cut into chunks ``(start, stop)`` of similar flights, at most
    ``cap`` each: the cheapest cut if every chunk flew side by side to its longest flight (``_cut``)."""
    start = _cut(np.asarray(steps, dtype=np.float64), _SIZE_OF, max(1, min(int(cap), _SIZES[-1])), _STEP_COST,
                 chunk_cost)
    chunks = []
    stop = len(steps)
    while stop > 0:
        chunks.append((int(start[stop]), stop))
        stop = chunks[-1][0]
    return chunks[::-1]


def _groups(steps: np.ndarray, cap: int, workers: int) -> tuple[list[list[tuple[int, int]]], float]:
    """Contiguous groups of the sorted flights, each a staircase, shared between up to ``workers`` threads.

    A batch of up to ``cap`` throws is one group; a larger one is cut into chunks of similar
    flights of at most ``cap`` (``_chunks``), each its own staircase. The groups are shared out
    longest first (by ``_stairs``' cost). With several threads a batch of up to ``cap`` is also
    tried split into one group per thread of about equal work (model steps), kept if it ends
    sooner by more than handing work to another thread costs (``_THREAD_COST``).

    Returns:
      The groups ``(start, stop)`` of each thread, and the longest thread's cost.
    """
    n = len(steps)
    candidates = [[(0, n)] if n <= cap else _chunks(steps, cap)]
    if workers > 1 and 1 < n <= cap:
        work = np.cumsum(steps)
        cuts = np.searchsorted(work, work[-1] * np.arange(1, workers) / workers, side="right")
        bounds = [0, *(int(c) for c in cuts), n]
        candidates.append([(a, b) for a, b in zip(bounds[:-1], bounds[1:], strict=True) if b > a])
    best: tuple[list[list[tuple[int, int]]], float] | None = None
    for groups in candidates:
        costs = [_stairs(steps[a:b])[2] for a, b in groups]
        shares: list[list[tuple[int, int]]] = [[] for _ in range(min(workers, len(groups)))]
        load = [0.0] * len(shares)
        for i in sorted(range(len(groups)), key=lambda i: -costs[i]):
            w = load.index(min(load))
            shares[w].append(groups[i])
            load[w] += costs[i]
        finish = max(load) + (_THREAD_COST if len(shares) > 1 else 0.0)
        if best is None or finish < best[1]:
            best = (shares, finish)
    return best


def _run_groups(groups: list[tuple[int, int]], arrays, out: np.ndarray, G: float) -> None:
    """Land the sorted throws ``[a, b)`` of each group into ``out`` (sorted order)."""
    for a, b in groups:
        _fly_stairs(tuple(x[a:b] for x in arrays), out[a:b], G)


def landing_x(ux, uy, *, G: float = 0.05, Fr=0.1, W=0.0, M=1.0, tolerance: float = DEFAULT_TOLERANCE,
              n_threads: int | None = None, cap: int = _CAP) -> np.ndarray:
    """Landing x of many throws simulated in MuJoCo (unchecked: the tasks validate first).

    Args:
      ux, uy: launch velocities, broadcast with the parameters to one shape ``(...)``.
      G: gravity (a scalar for the whole batch). Fr, W, M: drag, wind and mass, per throw or scalar.
      tolerance: landing error bound that picks each throw's step (``step_for``).
      n_threads: threads for large batches (default ``THREADS``).
      cap: most throws in one model (a larger batch flies as several staircases).

    Returns:
      Landing x of shape ``(...)``.
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (ux, uy, Fr, W, M)))
    shape = arrays[0].shape
    if arrays[0].size == 0:
        return np.empty(shape)
    workers = max(1, threads_here(THREADS) if n_threads is None else n_threads)
    plan = _plan(*(np.ascontiguousarray(a).ravel() for a in arrays), G=G, tolerance=tolerance, workers=workers,
                 cap=cap)
    landed = _fly(plan, G)
    out = np.empty(len(landed))
    out[plan.order] = landed
    return out.reshape(shape)


class _Plan(NamedTuple):
    """A batch ready to fly: its throws sorted by flight length, and how they are shared out."""

    order: np.ndarray  #: the sorting permutation of the batch
    flat: tuple  #: ux, uy, k, W, scale (each throw's RK4 step) and model steps, in flight order
    lengths: np.ndarray  #: flights in model steps, ascending
    shares: list  #: groups ``(start, stop)`` of the sorted throws per thread (``_groups``)


def _plan(ux, uy, Fr, W, M, *, G: float, tolerance: float, workers: int, cap: int = _CAP) -> _Plan:
    """Each throw's step, the flights sorted by length (every group then a slice, a view), and the
    groups shared out over ``workers`` threads (1-D arrays of one length)."""
    k = Fr / M
    scale = step_for(ux, uy, W, k, G=G, tolerance=tolerance)
    lengths = 2.0 * (uy / scale) / (G * SCALED_STEP)  # flight in model steps
    order = np.argsort(lengths, kind="stable")
    lengths = lengths[order]
    steps = _model_steps(lengths)
    shares, _ = _groups(steps, max(1, min(int(cap), _SIZES[-1])), workers)
    return _Plan(order, (*(a[order] for a in (ux, uy, k, W, scale)), steps), lengths, shares)


def _fly(plan: _Plan, G: float) -> np.ndarray:
    """Landing x of a planned batch, in flight order; the shares beyond the first on the shared pool."""
    landed = np.empty(len(plan.order))
    if len(plan.shares) == 1:
        _run_groups(plan.shares[0], plan.flat, landed, G)
    else:
        pool = shared_pool(len(plan.shares))
        futures = [pool.submit(_run_groups, share, plan.flat, landed, G) for share in plan.shares[1:]]
        _run_groups(plan.shares[0], plan.flat, landed, G)  # the calling thread takes a share too
        for future in futures:
            future.result()
    return landed
