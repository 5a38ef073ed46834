"""Smoke test of ``somarm bench tasks`` (figures are printed, never asserted as timings)."""

from __future__ import annotations

import pytest

from somarm.benchmarks import tasks as bench


def test_quick_benchmark_prints_a_row_per_task(capsys):
    assert bench.main(["--quick", "--only", "reach2", "throw"]) == 0
    lines = capsys.readouterr().out.splitlines()
    rows = {line.split()[0]: line.split() for line in lines[1:3]}
    assert set(rows) == {"reach2", "throw"}
    assert float(rows["throw"][4]) <= 1e-6  # the landing error column
    assert float(rows["reach2"][4]) <= 1e-9  # the fingertip error column


def test_unknown_task_fails_in_one_line():
    with pytest.raises(ValueError, match="unknown task 'reach3'; tasks: reach2"):
        bench.main(["--quick", "--only", "reach3"])
