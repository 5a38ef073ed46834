"""Units of work on a Ray cluster: ``--engine ray`` of ``somarm compare`` and ``somarm reproduce``.

A unit is a module-level function and its arguments (a comparison's learner at one seed, an
experiment of the reproduction), with the CPUs it takes declared. Each runs as a Ray task; this
process, the driver, keeps at most as many in flight as the cluster has CPUs, so that what it
shows as running is running, and hands each result to the caller as it comes back: the caller alone
writes files (the seed records ``--resume`` reads, the report), so a driver killed and started again
with ``--resume`` keeps every unit that had come back. A worker process that dies mid-unit (a node
lost, a process killed) has its unit run again by Ray, up to ``RETRIES`` times; a unit that raises
is not run again, and counts as failed.

What crosses the wire: the unit's function (by reference: the workers import somarm), its arguments
(a config, a seed, the rungs) and its result (scores and settings; for an experiment its report
section and figures' bytes). Ray is the ``sweep`` extra, imported here only when a unit runs.
Without an address, a local Ray is started on this machine, with one CPU per core.
"""

from __future__ import annotations

import os
import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = ["ENGINES", "RETRIES", "Unit", "check_engine", "join", "leave", "run_units"]

ENGINES = ("local", "ray")
#: How many times Ray runs a unit again after its worker process died.
RETRIES = 3


@dataclass(frozen=True)
class Unit:
    """One piece of work for the cluster."""

    name: str
    """What the status line and the errors call it (``td3 seed 2``)."""
    function: Callable
    """A module-level function (the workers import it by its module and name)."""
    args: tuple
    """Its arguments (pickled to the worker)."""
    kind: str = ""
    """Units of one kind are expected to take alike: the mean of the finished ones estimates the rest."""
    cpus: float = 1.0
    """The CPUs it takes (Ray's ``num_cpus``)."""


def check_engine(engine: str, address: str | None) -> None:
    """Fail fast on an unknown engine, an address without Ray, or Ray missing.

    Raises:
      ValueError: one line naming what is wrong and what is allowed (a missing Ray: the install command).
    """
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}; allowed: {', '.join(ENGINES)}")
    if address is not None and engine != "ray":
        raise ValueError("--ray-address is for --engine ray: give both, or neither")
    if address is not None and not address.strip():
        raise ValueError("--ray-address needs an address (HOST:PORT, as `ray start --head` prints), got an empty one")
    if engine == "ray":
        import importlib.util

        if importlib.util.find_spec("ray") is None:
            from somarm.extras import missing

            raise missing("sweep", "--engine ray needs Ray")


def join(address: str | None) -> bool:
    """Join the cluster at ``address``, or start a local one, unless this process is on one already;
    True when this call started Ray (``leave`` it then).

    Raises:
      ValueError: the cluster at ``address`` cannot be joined (one line).
    """
    check_engine("ray", address)
    import ray

    if ray.is_initialized():
        return False
    if address:
        try:
            ray.init(address=address, log_to_driver=False)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            text = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
            raise ValueError(f"cannot join the Ray cluster at {address}: {text}") from None
    else:
        from somarm.sweep.ray_engine import start_local

        start_local(os.cpu_count() or 1)
    return True


def leave(started: bool) -> None:
    """Stop Ray if ``join`` started it."""
    if started:
        import ray

        ray.shutdown()


def _why(exc: BaseException) -> str:
    """One line saying why a unit failed: its own error's message, or what happened to its worker."""
    cause = getattr(exc, "cause", None)
    if isinstance(cause, BaseException):
        text = str(cause).strip().splitlines()
        return f"{type(cause).__name__}: {text[-1]}" if text else type(cause).__name__
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def run_units(units: Sequence[Unit], *, on_done: Callable[[Unit, Any], None], address: str | None = None,
              progress: bool = True, expected: dict[str, float] | None = None) -> list[tuple[Unit, str]]:
    """Run ``units`` on the Ray cluster at ``address`` (None: a local one, started and stopped here).

    ``on_done(unit, result)`` is called in this process as each unit comes back (what it prints goes
    above the status line). ``expected``: seconds each unit is expected to take, by name, until
    units of its kind have finished (then their mean). Ctrl-C cancels the units in flight and is
    raised again.

    Returns:
      The units that failed, each with one line saying why (the others were all handed to ``on_done``).

    Raises:
      ValueError: Ray is missing, or the cluster at ``address`` cannot be joined (one line).
    """
    from somarm.status import Status

    started = join(address)
    import ray

    remotes: dict[Callable, Any] = {}
    in_flight: dict[Any, Unit] = {}
    failed: list[tuple[Unit, str]] = []
    seconds: dict[str, list[float]] = {}
    try:
        capacity = max(1.0, float(ray.cluster_resources().get("CPU", 1.0)))
        status = Status([u.name for u in units], workers=int(capacity), expected=dict(expected or {}),
                        enabled=progress)
        waiting = list(units)
        try:
            while waiting or in_flight:
                while waiting and (not in_flight or sum(u.cpus for u in in_flight.values()) + waiting[0].cpus
                                   <= capacity):
                    unit = waiting.pop(0)
                    if unit.function not in remotes:
                        remotes[unit.function] = ray.remote(unit.function)
                    ref = remotes[unit.function].options(num_cpus=unit.cpus, max_retries=RETRIES,
                                                         retry_exceptions=False).remote(*unit.args)
                    in_flight[ref] = unit
                    status.started(unit.name, "on the cluster")
                ready, _ = ray.wait(list(in_flight), num_returns=1, timeout=0.5)
                for ref in ready:
                    unit = in_flight.pop(ref)
                    try:
                        result = ray.get(ref)
                    except ray.exceptions.RayError as exc:
                        status.failed(unit.name)
                        failed.append((unit, _why(exc)))
                        status.say(f"{unit.name}: failed: {failed[-1][1]}")
                        continue
                    seconds.setdefault(unit.kind, []).append(status.finished(unit.name))
                    typical = statistics.mean(seconds[unit.kind])
                    status.expected.update({u.name: typical for u in units if u.kind == unit.kind})
                    with status.above():
                        on_done(unit, result)
                status.draw()
        except KeyboardInterrupt:
            for ref in in_flight:
                ray.cancel(ref, force=True)
            raise
        finally:
            status.close()
    finally:
        leave(started)
    return failed
