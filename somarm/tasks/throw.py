"""Throw a projectile at a target (Smith 2002, sections 5.3 to 5.5, Tables 3 and 6).

``throw`` has a single state (target X = 4, the environment of Table 3); ``throw_distance``,
``throw_wind``, ``throw_friction`` and ``throw_mass`` are experiments A to D of Table 6, whose
observation is the varied parameters (in the order X, W, Fr, M) drawn uniformly. The action is
the launch velocity (u_x, u_y) in [0, 1]^2; the reward is ``-|X - landing x|``, minus 2 more
for throws below 45 degrees (u_y < u_x) when ``punish_low`` is set (the footnote of Fig. 25).

Table 6 asks that every target be reachable from the velocity square, but its box is not:
with no wind and Fr = 0.2, M = 1 the longest throw lands near 5.0, short of X = 9 (0.18% of
experiment C's box and 0.035% of D's are out of reach). So each observation is drawn uniformly
from the reachable part of the box: 16 candidate points per row of uniforms, the first
reachable one kept (this project's choice; see ``_pick``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from somarm.tasks import ballistics, flight, launcher
from somarm.tasks.base import OneStepEnvTask, OneStepTask, check_actions
from somarm.tasks.record import TaskRecord

__all__ = ["RANGES", "VARIED", "TABLE3", "ThrowParams", "Throw", "ThrowEnvTask", "RECORDS", "landing_x",
           "simulate_trajectory", "throw_rewards"]

#: Table 6's ranges of the varied parameters.
RANGES: dict[str, tuple[float, float]] = {"X": (0.0, 9.0), "W": (-3.0, 0.0), "Fr": (0.0, 0.2), "M": (1.0, 2.0)}
#: The varied parameters of each throw task, in observation order.
VARIED: dict[str, tuple[str, ...]] = {
    "throw": (),
    "throw_distance": ("X",),
    "throw_wind": ("X", "W"),
    "throw_friction": ("X", "W", "Fr"),
    "throw_mass": ("X", "W", "Fr", "M"),
}
_CANDIDATES = 16
_PUNISHMENT = 2.0


@dataclasses.dataclass(frozen=True)
class ThrowParams:
    """The environment of Table 3; a throw_* task draws its varied fields instead."""

    M: float = 1.0  #: mass of the projectile (> 0)
    G: float = 0.05  #: gravity (> 0)
    Fr: float = 0.1  #: coefficient of air resistance (>= 0), horizontal only
    W: float = 0.0  #: horizontal wind speed against the thrower
    X: float = 4.0  #: horizontal position of the target
    punish_low: bool = False  #: add -2 to throws below 45 degrees (Fig. 25)
    tolerance: float = flight.DEFAULT_TOLERANCE  #: landing error bound picking the MuJoCo step

    def __post_init__(self):
        for name, low, strict in (("M", 0.0, True), ("G", 0.0, True), ("Fr", 0.0, False),
                                  ("W", None, False), ("X", None, False), ("tolerance", 0.0, True)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{name} must be a finite number, got {value!r}")
            if low is not None and (value <= low if strict else value < low):
                raise ValueError(f"{name} must be {'>' if strict else '>='} {low}, got {value!r}")
        if not isinstance(self.punish_low, bool):
            raise ValueError(f"punish_low must be true or false, got {self.punish_low!r}")


#: The environment of Table 3 (the defaults of ``ThrowParams``).
TABLE3 = ThrowParams()


def _check_velocities(ux, uy) -> tuple[np.ndarray, np.ndarray]:
    velocities = check_actions("velocities", np.stack(np.broadcast_arrays(
        np.asarray(ux, dtype=np.float64), np.asarray(uy, dtype=np.float64)), axis=-1),
        np.zeros(2), np.ones(2))
    return velocities[..., 0], velocities[..., 1]


def _check_condition(name: str, values, ok, allowed: str) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if not (np.isfinite(array) & ok(array)).all():
        raise ValueError(f"{name} must be finite and {allowed}, got values from {array.min():g} to {array.max():g}")
    return array


def landing_x(ux, uy, *, params: ThrowParams = TABLE3, Fr=None, W=None, M=None,
              backend: str = "mujoco") -> np.ndarray:
    """Landing x of throws, simulated in MuJoCo (default) or from Eq. 7.

    Args:
      ux, uy: launch velocities in [0, 1] (out-of-range values are rejected, not clipped).
      params: G, the tolerance, and the defaults of Fr, W and M.
      Fr, W, M: optional per-throw arrays overriding ``params``; everything broadcasts.
      backend: "mujoco" or "analytic".

    Returns:
      Landing x of the broadcast shape.

    Raises:
      ValueError: velocities outside [0, 1], NaN or inf, Fr < 0, M <= 0, or an unknown backend.
    """
    ux, uy = _check_velocities(ux, uy)
    return _landing(ux, uy, params=params, Fr=Fr, W=W, M=M, backend=backend)


def _landing(ux: np.ndarray, uy: np.ndarray, *, params: ThrowParams, Fr, W, M, backend: str) -> np.ndarray:
    """``landing_x`` for velocities already checked (the task's step checks its actions once)."""
    Fr = params.Fr if Fr is None else _check_condition("Fr", Fr, lambda v: v >= 0, ">= 0")
    W = params.W if W is None else _check_condition("W", W, lambda v: np.isfinite(v), "finite")
    M = params.M if M is None else _check_condition("M", M, lambda v: v > 0, "> 0")
    if backend == "analytic":
        return ballistics.landing_x(ux, uy, G=params.G, Fr=Fr, W=W, M=M)
    if backend != "mujoco":
        raise ValueError(f"unknown backend {backend!r}; backends: mujoco, analytic")
    return flight.landing_x(ux, uy, G=params.G, Fr=Fr, W=W, M=M, tolerance=params.tolerance)


def simulate_trajectory(ux: float, uy: float, params: ThrowParams | None = None, *,
                        dt: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One throw simulated in MuJoCo, for animation: every step, ending at the landing point.

    Args:
      ux, uy: launch velocity in [0, 1].
      params: the environment (G, Fr, W, M, X; the tolerance picks the step when ``dt`` is None);
        None means Table 3.
      dt: RK4 step; default: the step the tasks use for this throw (``flight.step_for``).

    Returns:
      ``(times (T,), xy (T, 2))``: time and (x, height) at launch, after every step, and at the
      located landing point (the last row, height 0).

    Raises:
      ValueError: velocities outside [0, 1] or a step that is not > 0.
    """
    params = TABLE3 if params is None else params
    ux_a, uy_a = _check_velocities(ux, uy)
    if ux_a.shape != ():
        raise ValueError(f"ux and uy must be single numbers, got shape {ux_a.shape}")
    step = float(flight.step_for(float(ux_a), float(uy_a), float(params.W), float(params.Fr / params.M), G=float(params.G),
                                 tolerance=params.tolerance))
    if dt is not None:
        if not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a number > 0, got {dt!r}")
        step = float(dt)
    return launcher.trajectory(float(ux_a), float(uy_a), G=params.G, Fr=params.Fr, W=params.W, M=params.M,
                               X=params.X, step=step)


def throw_rewards(landing: np.ndarray, X, ux, uy, *, punish_low: bool) -> np.ndarray:
    """``-|X - landing|``, minus 2 for throws below 45 degrees when ``punish_low``."""
    rewards = -np.abs(np.asarray(X) - landing)
    if punish_low:
        rewards = rewards - _PUNISHMENT * (np.asarray(uy) < np.asarray(ux))
    return rewards


class Throw(OneStepTask):
    """Batched throw task; ``varied`` names the parameters drawn per episode (Table 6)."""

    def __init__(self, params: ThrowParams, *, name: str, **kwargs):
        self.name = name
        self.varied = VARIED[name]
        # When no condition but the target varies, the velocity square's reach is one range for
        # every episode: computed here once, not at every reset.
        fixed = not {"Fr", "W", "M"} & set(self.varied)
        self._fixed_range = (ballistics.landing_range(G=params.G, Fr=params.Fr, W=params.W, M=params.M)
                             if fixed else None)
        if self.varied:
            low = np.array([RANGES[v][0] for v in self.varied])
            high = np.array([RANGES[v][1] for v in self.varied])
        else:
            lowest, highest = self._fixed_range
            if not lowest <= params.X <= highest:
                raise ValueError(f"target X = {params.X:g} is out of reach: throws from the velocity "
                                 f"square land between {float(lowest):.4g} and {float(highest):.4g}")
            low, high = np.array([min(0.0, params.X)]), np.array([max(RANGES["X"][1], params.X)])
        self.observation_low, self.observation_high = low, high
        # The box's corner and sides repeated for the 16 candidates of a row of uniforms, so the
        # candidates come from one flat multiply-add (a trailing axis of d <= 4 would make NumPy
        # loop over the row 2 to 4 numbers at a time).
        self._candidate_low = np.tile(low, _CANDIDATES)
        self._candidate_width = np.tile(high - low, _CANDIDATES)
        self.action_low, self.action_high = np.zeros(2), np.ones(2)
        self.uniform_width = max(1, _CANDIDATES * len(self.varied))
        super().__init__(params, **kwargs)

    def conditions(self, observations: np.ndarray) -> dict[str, np.ndarray | float]:
        """X, W, Fr and M of each observation ``(..., obs_dim)``: drawn fields or the params'."""
        values: dict[str, np.ndarray | float] = {k: getattr(self.params, k) for k in ("X", "W", "Fr", "M")}
        for i, key in enumerate(self.varied):
            values[key] = observations[..., i]
        return values

    def reachable(self, observations: np.ndarray) -> np.ndarray:
        """Whether each observation's target lies within reach of the velocity square."""
        c = self.conditions(observations)
        if self._fixed_range is None:
            # The compiled check: the same answers as comparing with landing_range, far cheaper.
            return ballistics.within_reach(c["X"], G=self.params.G, Fr=c["Fr"], W=c["W"], M=c["M"])
        lowest, highest = self._fixed_range
        return (lowest <= c["X"]) & (c["X"] <= highest)

    def observations_from(self, uniforms: np.ndarray) -> np.ndarray:
        if not self.varied:
            return np.full((len(uniforms), 1), self.params.X)
        candidates = self._candidate_low + self._candidate_width * uniforms
        return self._pick(candidates.reshape(len(uniforms), _CANDIDATES, len(self.varied)))

    def _pick(self, candidates: np.ndarray) -> np.ndarray:
        """The first reachable of each row's candidates ``(n, 16, d)``.

        Rejection keeps the draw uniform over the reachable part of the box. A row whose 16
        candidates all miss (probability about 1e-44 for Table 6) keeps its first candidate
        with X pulled back to the farthest reachable landing.
        """
        chosen = candidates[:, 0].copy()
        pending = np.flatnonzero(~self.reachable(chosen))
        # Column by column, only for the rows still without a reachable candidate: nearly every
        # row is settled by its first candidate, so the reach is rarely computed more than once.
        for column in range(1, candidates.shape[1]):
            if pending.size == 0:
                return chosen
            trial = candidates[pending, column]
            ok = self.reachable(trial)
            chosen[pending[ok]] = trial[ok]
            pending = pending[~ok]
        if pending.size:  # every candidate missed: the first, with X pulled back
            c = self.conditions(chosen[pending])
            _, highest = ballistics.landing_range(G=self.params.G, Fr=c["Fr"], W=c["W"], M=c["M"])
            chosen[pending, 0] = np.minimum(chosen[pending, 0], highest)
        return chosen

    @classmethod
    def rewards_together(cls, tasks: list[Throw], steps: list[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
        """Rewards of several throw tasks from one batch of flights (one gravity, tolerance and backend)."""
        first = tasks[0]
        if any((t.backend, t.params.G, t.params.tolerance) != (first.backend, first.params.G, first.params.tolerance)
               for t in tasks):
            return super().rewards_together(tasks, steps)
        conditions = [t.conditions(o) for t, (o, _) in zip(tasks, steps, strict=True)]
        shapes = [a.shape[:-1] for _, a in steps]
        flat = {key: np.concatenate([np.broadcast_to(c[key], shape).ravel() for c, shape in zip(conditions, shapes,
                                                                                                 strict=True)])
                for key in ("Fr", "W", "M")}
        ux = np.concatenate([a[..., 0].ravel() for _, a in steps])
        uy = np.concatenate([a[..., 1].ravel() for _, a in steps])
        landing = landing_x(ux, uy, params=first.params, backend=first.backend, **flat)
        rewards, start = [], 0
        for task, c, (_, a), shape in zip(tasks, conditions, steps, shapes, strict=True):
            size = int(np.prod(shape))
            rewards.append(throw_rewards(landing[start:start + size].reshape(shape), c["X"], a[..., 0], a[..., 1],
                                         punish_low=task.params.punish_low))
            start += size
        return rewards

    def rewards(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        c = self.conditions(observations)
        ux, uy = actions[..., 0], actions[..., 1]
        landing = _landing(ux, uy, params=self.params, Fr=c["Fr"], W=c["W"], M=c["M"], backend=self.backend)
        return throw_rewards(landing, c["X"], ux, uy, punish_low=self.params.punish_low)


class ThrowEnvTask(OneStepEnvTask):
    """dm_env side of the throw tasks: launch, fly in MuJoCo until the landing, reward."""

    def __init__(self, batched: Throw):
        super().__init__(batched, observation_key="conditions")
        self._conditions: dict = {}

    def apply_observation(self, physics: launcher.LauncherPhysics, observation: np.ndarray) -> None:
        c = self.batched.conditions(observation)
        self._conditions = {k: float(v) for k, v in c.items()}
        physics.set_conditions(Fr=self._conditions["Fr"], W=self._conditions["W"], M=self._conditions["M"])
        physics.set_target(self._conditions["X"])

    def apply_action(self, physics: launcher.LauncherPhysics, action: np.ndarray) -> None:
        c = self._conditions
        self._velocity = (float(action[0]), float(action[1]))
        step = float(flight.step_for(*self._velocity, c["W"], c["Fr"] / c["M"], G=float(self.batched.params.G),
                                     tolerance=self.batched.params.tolerance))
        self._launch = physics.launch(*self._velocity, step=step)

    def reward_from_physics(self, physics: launcher.LauncherPhysics, observation: np.ndarray) -> float:
        # physics.step took the first step of the flight; fly on from there until the landing.
        landing = float(physics.fly(previous=self._launch)[0])
        ux, uy = self._velocity
        return float(throw_rewards(landing, self._conditions["X"], ux, uy,
                                   punish_low=self.batched.params.punish_low))


#: Axis labels of the varied parameters and of the launch velocity in the run figures.
_LABELS = {"X": "target X", "W": "wind W", "Fr": "friction Fr", "M": "mass M"}
_ACTION_LABELS = ("u_x (horizontal speed)", "u_y (vertical speed)")
_SUMMARIES = {
    "throw": "throw at target X = 4, a single state (Table 3); action (ux, uy) in [0, 1]^2",
    "throw_distance": "Table 6 A: target X in [0, 9] observed; action (ux, uy)",
    "throw_wind": "Table 6 B: X in [0, 9], wind W in [-3, 0] observed; action (ux, uy)",
    "throw_friction": "Table 6 C: X, W, friction Fr in [0, 0.2] observed; action (ux, uy)",
    "throw_mass": "Table 6 D: X, W, Fr, mass M in [1, 2] observed; action (ux, uy)",
}
_RUNS = {"throw": ("table4", 4_000), "throw_distance": ("table5", 10_000), "throw_wind": ("table7", 20_000),
         "throw_friction": ("table7", 20_000), "throw_mass": ("table7", 20_000)}


def _record(name: str) -> TaskRecord:
    varied = VARIED[name]
    return TaskRecord(
        name=name,
        summary=_SUMMARIES[name],
        params=ThrowParams,
        settable=tuple(f.name for f in dataclasses.fields(ThrowParams) if f.name not in varied),
        make=lambda params, **kwargs: Throw(params, name=name, **kwargs),
        environment=lambda batched: (launcher.load_physics(batched.params.G), ThrowEnvTask(batched)),
        preset=_RUNS[name][0],
        n_steps=_RUNS[name][1],
        model="launcher",
        observation_labels=tuple(_LABELS[v] for v in varied) or (_LABELS["X"],),
        action_labels=_ACTION_LABELS,
        view="fan" if name == "throw" else "goals",
    )


RECORDS = tuple(_record(name) for name in VARIED)
