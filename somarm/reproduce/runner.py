"""``somarm reproduce``: run the experiments, time them, and write REPORT.md atomically."""

from __future__ import annotations

import json
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

from somarm import __version__
from somarm.compare import peers_missing
from somarm.io import atomic_write_json, atomic_write_text
from somarm.reproduce import arms, beyond, delayed, peers, throws
from somarm.reproduce.common import Context
from somarm.reproduce.report import Section, render

__all__ = ["EXPERIMENTS", "OPTIONAL", "check_names", "reproduce", "load_claims"]

#: Every experiment of the paper, in the paper's order, then what goes beyond it.
EXPERIMENTS: dict[str, Callable[[Context], Section]] = {
    "reach2": arms.reach2,
    "reach20": arms.reach20,
    "four_goals": arms.four_goals,
    "throw": throws.throw,
    "throw_maps": throws.throw_maps,
    "neighbourhood_q": throws.neighbourhood_q,
    "more_inputs": throws.more_inputs,
    "delayed_reward": delayed.delayed_reward,
    # Not the paper's: its suggested continuous response (issue 11), apart from the paper's claims.
    "beyond": beyond.beyond,
}

#: Parts run only when named with ``--only`` (they take far longer than the paper's experiments).
OPTIONAL: dict[str, Callable[[Context], Section]] = {"peers": peers.peers}


def check_names(only: list[str] | None) -> list[str]:
    """The experiments to run, in the paper's order; ValueError listing the names for an unknown one."""
    names = list(only or EXPERIMENTS)
    unknown = [n for n in names if n not in EXPERIMENTS and n not in OPTIONAL]
    if unknown:
        raise ValueError(f"unknown experiment(s) {', '.join(unknown)}; allowed: {', '.join([*EXPERIMENTS, *OPTIONAL])}")
    if "peers" in names and (reason := peers_missing()):
        raise ValueError(reason)
    return names


def reproduce(
    out: Path, *, quick: bool = False, only: list[str] | None = None, seed: int = 0, progress: bool = True
) -> int:
    """Run the chosen experiments and write ``out/REPORT.md``, ``out/claims.json`` and the figures.

    Returns:
      0 when every experiment ran (whatever the verdicts), 130 when interrupted (the report then
      holds the experiments that finished).

    Raises:
      ValueError: an unknown experiment name (the message lists the names).
    """
    names = check_names(only)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    ctx = Context(out_dir=out, quick=quick, seed=seed, progress=progress)
    sections: list[Section] = []
    start = time.perf_counter()
    status = 0
    for name in names:
        began = time.perf_counter()
        try:
            section = {**EXPERIMENTS, **OPTIONAL}[name](ctx)
        except KeyboardInterrupt:
            print(
                f"\ninterrupted during {name}; the report holds the experiments that finished",
                file=sys.stderr,
            )
            status = 130
            break
        except ValueError as exc:  # a figure that cannot be written (a full disk): keep the report so far
            _keep_report(out, sections, quick=quick, seed=seed, total=time.perf_counter() - start)
            raise ValueError(f"{exc}; {name} stopped, the report keeps the {len(sections)} "
                             "experiment(s) that finished") from None
        section.wall_time_s = time.perf_counter() - began
        sections.append(section)
        print(f"{name}: {section.wall_time_s:.1f} s", file=sys.stderr, flush=True)
        _write(out, sections, quick=quick, seed=seed, total=time.perf_counter() - start, complete=False)
    total = time.perf_counter() - start
    _write(out, sections, quick=quick, seed=seed, total=total, complete=status == 0)
    held = sum(c.holds is True for s in sections for c in s.claims)
    claims = sum(len(s.claims) for s in sections)
    print(f"report: {out / 'REPORT.md'} ({held} of {claims} claims hold; {total:.1f} s)")
    return status


def _keep_report(out: Path, sections: list[Section], **kwargs) -> None:
    """Write the report of the finished experiments, if there is room for it (best effort)."""
    try:
        _write(out, sections, complete=False, **kwargs)
    except ValueError:
        pass  # the report of the previous experiment stays as it was


def _write(
    out: Path, sections: list[Section], *, quick: bool, seed: int, total: float, complete: bool
) -> None:
    slowest = max(sections, key=lambda s: s.wall_time_s, default=None)
    header = [
        f"Mode: **{'quick (reduced trial counts: verdicts are indicative only)' if quick else 'full'}**; "
        f"seed {seed}; every reward evaluated in MuJoCo (the tasks' default backend); somarm {__version__}, "
        f"Python {platform.python_version()}, {platform.machine()}.",
        "",
        f"Total wall time {total:.1f} s"
        + (f"; slowest experiment `{slowest.name}` ({slowest.wall_time_s:.1f} s)." if slowest else ".")
        + ("" if complete else " **Incomplete: not every experiment has run.**"),
        "",
        "Arm lengths, the goal circle, the four goals, the reading of epsilon in Tables 1 and 2 (a fraction of "
        "the angle range), the Motoric Map's rules, run lengths and the levels and bounds used in the verdicts "
        "are this project's choices, stated in each part; the paper publishes none of them.",
    ]
    atomic_write_text(out / "REPORT.md", render(sections, header=header, out_dir=out))
    atomic_write_json(
        out / "claims.json",
        {
            "quick": quick,
            "seed": seed,
            "complete": complete,
            "wall_time_s": round(total, 2),
            "experiments": {
                s.name: {
                    "wall_time_s": round(s.wall_time_s, 2),
                    "claims": [
                        {"claim": c.claim, "measured": c.measured, "test": c.test, "holds": c.holds}
                        for c in s.claims
                    ],
                }
                for s in sections
            },
        },
    )


def load_claims(out: Path) -> dict:
    """The machine-readable verdicts of a report folder (for tests and tools)."""
    return json.loads((out / "claims.json").read_text())
