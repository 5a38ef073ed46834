"""The shape every experiment of the reproduction fills in: what it trains, how, and what it reports.

An experiment module declares its lockstep groups (``groups``: what it trains at a seed, read by
``sizes`` before anything is written), its training (``train``: the runs and whatever it measures on
them that needs the trained learners) and its report (``report``: the claims, notes, choices and
figures of its section), and binds them in one ``Experiment``, which ``runner.EXPERIMENTS`` names. An
experiment that trains no lockstep group (the peers' comparisons, through ``somarm.peers.compare``)
declares ``groups`` None.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from somarm.reproduce.common import Context
from somarm.reproduce.report import Section
from somarm.run import RunConfig

__all__ = ["Experiment"]


@dataclass(frozen=True)
class Experiment:
    """One experiment: ``report(ctx, train(ctx))`` at ``ctx.seed``, its runs declared by ``groups``.

    ``backend`` is the backend it always computes its rewards in, whatever the run's ``--backend``
    (None: the run's): an experiment whose point is the simulated dynamics (the servo-driven arm) has
    no closed form to run in.
    """

    groups: Callable[[Context], dict[str, list[RunConfig]]] | None
    """What it trains at a seed; None for an experiment without lockstep groups (the peers' comparisons)."""
    train: Callable[[Context], Any]
    report: Callable[[Context, Any], Section]
    backend: str | None = None

    def context(self, ctx: Context) -> Context:
        """``ctx`` as this experiment runs in it (its own ``backend`` where it has one)."""
        return ctx if self.backend is None else dataclasses.replace(ctx, backend=self.backend)

    def __call__(self, ctx: Context) -> Section:
        """Train, measure and report at ``ctx.seed``.

        Args:
          ctx: where and how the experiment runs (``ctx.quick``: reduced trial counts and run lengths).

        Returns:
          The report's section: claims with their verdicts, notes, this project's choices, the figures.

        Raises:
          KeyboardInterrupt: the training was stopped (see ``common.run_group``).
          ValueError: a figure cannot be written (a full disk), in one line naming it.
        """
        ctx = self.context(ctx)
        return self.report(ctx, self.train(ctx))
