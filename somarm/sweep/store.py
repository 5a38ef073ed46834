"""The sweep folder: one file per finished row, and the tables drawn from them.

``points/KEY.json`` holds the row of one point at one seed, named by a hash of its whole run
configuration; a rerun finds the rows already there and runs only the rest, even when the sweep
was widened (more values, more seeds). Every file is written atomically, so a sweep stopped at any
moment leaves complete rows and tables that describe exactly them.
"""

from __future__ import annotations

import csv
import io
import math
import shlex
from pathlib import Path
from typing import Any

import numpy as np

from somarm.io import atomic_write_json, atomic_write_text, make_folder, read_json
from somarm.sweep.spec import TASK_PREFIX, SweepSpec, config_key, preset_value, same_value
from somarm.sweep.work import METRICS, greedy_name, point_label

__all__ = ["Table", "save_row", "load_rows", "write_outputs", "summary_line"]


def save_row(out: Path, row: dict[str, Any]) -> None:
    """Keep one finished (or failed) row on disk; the point index is the sweep's, not stored."""
    folder = make_folder(out / "points", within=out)
    atomic_write_json(folder / f"{row['key']}.json", {k: v for k, v in row.items() if k != "point"}, within=out)


#: A row holds a few numbers and settings: a file far larger is not one.
_MAX_ROW_BYTES = 2**20


def load_rows(out: Path) -> dict[str, dict[str, Any]]:
    """Rows on disk by key; an unreadable or incomplete file counts as missing (that point runs again)."""
    rows = {}
    for path in sorted((out / "points").glob("*.json")):
        try:
            row = read_json(path, max_bytes=_MAX_ROW_BYTES)
        except ValueError:
            continue
        complete = isinstance(row, dict) and row.get("key") == path.stem and "error" in row
        finished = complete and all(isinstance(row.get(m), float) for m in METRICS) and \
            math.isfinite(row["greedy_error"])  # a damaged file's NaN is no result: the point runs again
        if complete and (row["error"] or finished):
            rows[path.stem] = row
    return rows


class Table:
    """The current sweep's rows: one per point and seed that finished or failed.

    Args:
      spec: the checked sweep.
      points: its points (``spec.points()``).
      rows: rows by key (``load_rows``).
    """

    def __init__(self, spec: SweepSpec, points: list[dict[str, str]], rows: dict[str, dict[str, Any]]):
        self.spec, self.points = spec, points
        self.keys = [a.key for a in spec.axes]
        self.rows = []
        self.missing = 0
        for index, point in enumerate(points):
            for seed in spec.seeds():
                row = rows.get(config_key(spec.config(point, seed)))
                if row is None:
                    self.missing += 1
                else:
                    self.rows.append({"point": index, **row})

    def columns(self) -> list[str]:
        fixed = list(self.spec.fixed_texts())
        return ["point", "seed", *self.keys, *fixed, "task", "learner", "preset", "trials", "steps_requested",
                *METRICS, "steps", "group_wall_time_s", "error"]

    def csv_text(self) -> str:
        """``results.csv``: one row per point and seed, every parameter a column, floats exact."""
        buffer = io.StringIO()
        writer = csv.DictWriter(buffer, fieldnames=self.columns(), lineterminator="\n", extrasaction="ignore")
        writer.writeheader()
        spec = self.spec
        for row in self.rows:
            base = spec.fixed_texts()
            writer.writerow({
                **base, **self.points[row["point"]], **{k: row.get(k, "") for k in row if k != "key"},
                "task": spec.task, "learner": spec.learner, "preset": spec.preset,
                "trials": spec.n_trials, "steps_requested": spec.n_steps,
            })
        return buffer.getvalue()

    def per_point(self) -> list[dict[str, Any]]:
        """Each point with every seed finished and none failed: mean and sd over seeds of each metric."""
        out = []
        for index, point in enumerate(self.points):
            rows = [r for r in self.rows if r["point"] == index]
            if len(rows) < self.spec.n_seeds or any(r.get("error") for r in rows):
                continue
            stats = {"point": index, "values": point, "seeds": len(rows)}
            for name in ("greedy_error", "final_error"):
                values = np.array([r[name] for r in rows])
                stats[name] = float(values.mean())
                stats[f"{name}_seed_sd"] = float(values.std())
            out.append(stats)
        return out

    def best(self) -> dict[str, Any] | None:
        """The point with the lowest mean greedy error over seeds (None if no point finished)."""
        done = self.per_point()
        return min(done, key=lambda s: s["greedy_error"]) if done else None

    def preset_point(self) -> dict[str, Any] | None:
        """The finished point whose swept values are the preset's own, if the sweep holds one."""
        own = {k: preset_value(self.spec, k) for k in self.keys}
        for stats in self.per_point():
            if all(own[k] is not None and same_value(stats["values"][k], own[k]) for k in self.keys):
                return stats
        return None


def _split(texts: dict[str, str]) -> tuple[dict[str, str], dict[str, str]]:
    """Text settings by sweep key as ``(--set, --task-set)`` settings."""
    return ({k: v for k, v in texts.items() if not k.startswith(TASK_PREFIX)},
            {k[len(TASK_PREFIX):]: v for k, v in texts.items() if k.startswith(TASK_PREFIX)})


def _train_command(spec: SweepSpec, values: dict[str, str]) -> list[str]:
    (fixed_learner, fixed_task), (learner, task) = _split(spec.fixed_texts()), _split(values)
    learner, task = {**fixed_learner, **learner}, {**fixed_task, **task}
    argv = ["somarm", "train", spec.task, "--learner", spec.learner, "--preset", str(spec.preset)]
    for key, value in learner.items():
        argv += ["--set", f"{key}={value}"]
    for key, value in task.items():
        argv += ["--task-set", f"{key}={value}"]
    argv += ["--trials", str(spec.n_trials), "--steps", str(spec.n_steps), "--seed", str(spec.seed)]
    if spec.backend != "mujoco":
        argv += ["--backend", spec.backend]
    if spec.block != 100:
        argv += ["--block", str(spec.block)]
    return argv


def summary_line(table: Table) -> str:
    """One line: the best point, its error, and how far it lies from the preset's values and error.

    E.g. ``summary: best decay=inv:250 alpha=0.5, greedy error 0.117 (sd 0.005 over 2 seeds);
    preset table1 has decay=inv:1000 alpha=1 (best x0.5), greedy error 0.135 there (best -13.3%)``.
    """
    best = table.best()
    done = f"{len(table.rows)} of {len(table.rows) + table.missing} runs done"
    if best is None:
        return f"summary: no point finished every seed ({done})"
    name = greedy_name(table.spec.task)
    text = (f"summary: best {point_label(best['values'])}, {name} {best['greedy_error']:.4g} "
            f"(sd {best['greedy_error_seed_sd']:.2g} over {best['seeds']} seed(s))")
    own_values = []
    for key in table.keys:
        own, value = preset_value(table.spec, key), best["values"][key]
        if own is None:
            own_values.append(f"{key} unset")
            continue
        own_values.append(f"{key}={own}")
        try:
            if not same_value(value, own) and float(own) != 0:
                own_values[-1] += f" (best x{float(value) / float(own):.3g})"
        except ValueError:
            pass
    text += f"; preset {table.spec.preset} has {' '.join(own_values)}"
    own_point = table.preset_point()
    if own_point is None:
        text += " (a point this sweep did not run)"
    elif own_point["point"] == best["point"]:
        text += " (the best)"
    else:
        change = best["greedy_error"] / own_point["greedy_error"] - 1.0 if own_point["greedy_error"] else math.nan
        text += f", {name} {own_point['greedy_error']:.4g} there (best {change:+.1%})"
    return f"{text}; {done}"


def write_outputs(out: Path, table: Table, *, figure: bool = True) -> str:
    """Write results.csv, best.json and sweep.png for the rows so far; return the summary line."""
    atomic_write_text(out / "results.csv", table.csv_text(), within=out)
    best = table.best()
    line = summary_line(table)
    if best is not None:
        argv = _train_command(table.spec, best["values"])
        (fixed_learner, fixed_task), (learner, task) = _split(table.spec.fixed_texts()), _split(best["values"])
        atomic_write_json(out / "best.json", {
            **best,
            "set": [f"{k}={v}" for k, v in {**fixed_learner, **learner}.items()],
            "task_set": [f"{k}={v}" for k, v in task.items()] + [f"{k}={v}" for k, v in fixed_task.items()],
            "command": shlex.join(argv),
            "summary": line,
        }, within=out)
    else:  # a best.json left from an earlier, narrower sweep would no longer be true
        (out / "best.json").unlink(missing_ok=True)
    if figure and table.rows:
        from somarm.sweep import plot as sweep_plot

        sweep_plot.draw(table, out / "sweep.png")
    return line
