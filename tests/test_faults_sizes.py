"""Sizes checked by arithmetic before memory is spent: huge sweeps and comparisons are refused at once in
one line, on real processes under a small address space, and leave no folder."""

from __future__ import annotations

import subprocess
import time

import pytest
from processes import checkout_env, one_error_line, somarm_command

SHORT_GRID = ",".join(f"{i / 10000:g}" for i in range(1, 2001))


def _limited(kib: int = 1_500_000):
    """A ``preexec_fn`` giving the child ``ulimit -v kib``, the same on every machine."""
    import resource

    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (kib * 1024, resource.RLIM_INFINITY))

    return limited


def _refused_at_once(tmp_path, *argv: str) -> str:
    out = tmp_path / "out"
    began = time.monotonic()
    done = subprocess.run(somarm_command(*argv, "--out", str(out)), capture_output=True, text=True,
                          env=checkout_env(), timeout=120, preexec_fn=_limited())
    line = one_error_line(done)
    assert time.monotonic() - began < 60 and not out.exists()
    return line


@pytest.mark.parametrize("argv, needles", [
    (("sweep", "reach2", "--grid", f"alpha={SHORT_GRID}", "--grid", f"epsilon={SHORT_GRID}"),
     ("4000000 runs", "give fewer values, --samples or --seeds")),
    (("sweep", "reach2", "--grid", "alpha=0.1,0.2", "--seeds", "100000000"), ("200000000 runs",)),
    (("sweep", "reach2", "--random", "alpha=0.1:1", "--samples", "1000000000"), ("1000000000 runs",)),
    (("compare", "reach2", "--learners", "tabular", "--seeds", "100000000"), ("100000000 units", "fewer --seeds")),
    (("compare", "reach2", "--learners", "tabular", "--observations", "1000000000"),
     ("--observations 1000000000 needs about", "give fewer --observations")),
])
def test_a_huge_sweep_or_comparison_is_refused_at_once_in_one_line(tmp_path, argv, needles):
    line = _refused_at_once(tmp_path, *argv)
    for needle in needles:
        assert needle in line, line
