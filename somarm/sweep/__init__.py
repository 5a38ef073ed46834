"""Parameter sweeps: every point a full run, in lockstep on one machine or as Ray Tune trials.

``SweepSpec`` says what is searched (``spec``), ``run_sweep`` runs it (``driver``) on the local
engine (``local``) or on Ray (``ray_engine``, the ``sweep`` extra), both through the same lockstep
unit of work (``work``); ``store`` keeps the sweep folder and ``figure`` draws ``sweep.png``.
"""

from somarm.sweep.driver import ENGINES, SweepOutcome, run_sweep
from somarm.sweep.spec import Axis, SweepSpec, parse_grid, parse_random

__all__ = ["ENGINES", "Axis", "SweepSpec", "SweepOutcome", "parse_grid", "parse_random", "run_sweep"]
