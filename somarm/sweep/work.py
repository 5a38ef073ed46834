"""The unit of sweep work both engines share: a group of points trained in lockstep.

Points that share a task (task parameters and seed) train together through ``train_group``: one
physics call per step for the whole group, and each point's numbers equal a run of it alone. A
group too big for memory is cut into chunks. ``run_chunk`` turns a chunk into result rows; a point
that fails gives a row holding its error, and the other points of its chunk still finish.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

from somarm import learners, run, tasks
from somarm.run.config import RunConfig
from somarm.sweep.spec import SweepSpec, config_key

__all__ = ["Chunk", "plan_chunks", "validate_points", "run_chunk", "point_label", "failed_row", "METRICS",
           "greedy_name"]

#: The numbers of a result row; an error is minus the reward (the distance to the goal for the
#: arms, the miss for throws). ``greedy`` is the policy on fresh observations (``run.greedy_cost``:
#: of an episodic task, minus the return of whole greedy episodes, so a sweep ranks it by return),
#: ``final`` training's last window; ``_sd`` is the spread over the seed's trials.
METRICS = ("greedy_error", "greedy_error_sd", "final_error", "final_error_sd")



def greedy_name(task: str) -> str:
    """What a row's ``greedy_error`` is for ``task``, in words (the summary line's and the figure's)."""
    return "greedy cost (minus the episode return)" if tasks.record(task).episodic else "greedy error"


#: The evaluation that ``somarm train`` writes into summary.json, so a sweep row equals a run.
GREEDY_OBSERVATIONS = 1000


@dataclass(frozen=True)
class Chunk:
    """Points trained in one ``train_group`` call: ``items`` are ``(point index, seed, config)``."""

    items: tuple[tuple[int, int, RunConfig], ...]

    def to_dict(self) -> dict:
        return {"items": [[i, s, c.to_dict()] for i, s, c in self.items]}

    @classmethod
    def from_dict(cls, data: dict) -> Chunk:
        return cls(tuple((i, s, RunConfig.from_dict(c)) for i, s, c in data["items"]))


def point_label(point: dict[str, str]) -> str:
    """``alpha=0.5 task.radius=0.2``: a point as the sweep's keys and values."""
    return " ".join(f"{k}={v}" for k, v in point.items())


def validate_points(spec: SweepSpec, points: list[dict[str, str]]) -> None:
    """Check every point's learner settings and task parameters, and that its run fits in memory
    (``run.check_memory_needs``: a point trains alone when it is too big for a group), before any
    training and before the sweep's folder is made.

    Raises:
      ValueError: the first bad point, in one line naming it and what is allowed.
    """
    tasks_checked: set[str] = set()
    for point in points:
        try:
            config = spec.config(point, spec.seed)  # reads and checks its learner settings and task parameters
            run.check_memory_needs([config])  # the same at every seed
            task_key = json.dumps(config.task_params, sort_keys=True)
            if task_key not in tasks_checked:
                run.make_task(config)
                tasks_checked.add(task_key)
        except ValueError as exc:
            label = point_label(point)
            label = label if len(label) <= 120 else label[:117] + "..."
            raise ValueError(f"sweep point {label}: {exc}") from None


def _bytes_per_point(config: RunConfig) -> float:
    """Rough memory of one point's learner: its kind's own estimate (``learners.memory_needed``, the
    lower bound ``run.check_memory_needs`` uses), three times over for the working arrays."""
    return 3.0 * learners.memory_needed(config.learner, config.learner_config, n_trials=config.n_trials,
                                        obs_dim=1, action_dim=1)[1]


def plan_chunks(
    todo: list[tuple[int, int, RunConfig]], *, max_bytes: float = 2e9, max_points: int | None = None
) -> list[Chunk]:
    """Group ``(point index, seed, config)`` items that can share physics, then cut by memory.

    Args:
      todo: the items still to run.
      max_bytes: estimated learner memory allowed per chunk.
      max_points: at most this many points per chunk (None: no limit).

    Returns:
      Chunks in order of first appearance; the items of each share task parameters and seed.
    """
    groups: dict[tuple[str, int], list[tuple[int, int, RunConfig]]] = {}
    for item in todo:
        config = item[2]
        groups.setdefault((json.dumps(config.task_params, sort_keys=True), config.seed), []).append(item)
    chunks = []
    for items in groups.values():
        current: list[tuple[int, int, RunConfig]] = []
        used = 0.0
        for item in items:
            size = _bytes_per_point(item[2])
            if current and (used + size > max_bytes or (max_points and len(current) >= max_points)):
                chunks.append(Chunk(tuple(current)))
                current, used = [], 0.0
            current.append(item)
            used += size
        chunks.append(Chunk(tuple(current)))
    return chunks


def _number(value: float | None) -> float:
    """summary.json writes a mean over nothing (no complete block) as null."""
    return float("nan") if value is None else float(value)


def _row(index: int, seed: int, result: run.RunResult) -> dict:
    """Result row of one trained point: the errors its run folder's summary.json would hold."""
    greedy = run.greedy_summary(result, GREEDY_OBSERVATIONS, shortest=False)  # ranked by the return
    if not greedy or "greedy_error" in greedy:
        raise ValueError(greedy.get("greedy_error", "no step was trained"))
    greedy_error, greedy_error_sd = run.greedy_cost(greedy)
    if not math.isfinite(greedy_error):
        raise FloatingPointError(f"the greedy error is {greedy_error} (the learner diverged)")
    summary = run.summary(result)
    return {
        "point": index,
        "seed": seed,
        "key": config_key(result.config),
        "greedy_error": greedy_error,
        "greedy_error_sd": greedy_error_sd,
        "final_error": -_number(summary["final_mean_reward"]),
        "final_error_sd": _number(summary["final_sd_reward"]),
        "steps": result.steps_done,
        "group_wall_time_s": summary["wall_time_s"],
        "error": "",
    }


def failed_row(index: int, seed: int, config: RunConfig, exc: BaseException) -> dict:
    """The row of a point that failed: its error as ``Type: last line of the message``."""
    message = (str(exc).strip().splitlines() or [""])[-1]
    return {"point": index, "seed": seed, "key": config_key(config), "error": f"{type(exc).__name__}: {message}"}


def run_chunk(chunk: Chunk, *, progress: bool = False) -> tuple[list[dict], bool]:
    """Train a chunk's points in lockstep and evaluate each.

    A failure in the group retrains its points one by one, so only the failing point is lost.

    Returns:
      ``(rows, interrupted)``: one row per finished or failed point; ``interrupted`` when Ctrl-C
      or SIGTERM stopped training (the unfinished points then have no row).
    """
    configs = [config for _, _, config in chunk.items]
    label = f"sweep {chunk.items[0][2].task} seed {chunk.items[0][1]} ({len(configs)} points)"
    try:
        results = run.train_group(configs, progress=progress, label=label)
    except Exception as exc:  # any failure of one point; the others are retried alone
        if len(configs) == 1:
            index, seed, config = chunk.items[0]
            return [failed_row(index, seed, config, exc)], False
        rows: list[dict] = []
        for item in chunk.items:
            part, interrupted = run_chunk(Chunk((item,)), progress=progress)
            rows += part
            if interrupted:
                return rows, True
        return rows, False
    if results[0].interrupted:
        return [], True
    rows = []
    for (index, seed, config), result in zip(chunk.items, results, strict=True):
        try:
            rows.append(_row(index, seed, result))
        except Exception as exc:  # recorded in the row; the sweep goes on
            rows.append(failed_row(index, seed, config, exc))
    return rows, False

