"""Worker processes: a stop that comes while a worker's work is over ends it quietly (real processes)."""

from __future__ import annotations

import atexit
import os
import subprocess
import sys
import textwrap
import time

from somarm.run.stopping import sigterm_as_interrupt


def _work_then_linger(connection) -> None:
    """Work done; the interpreter's teardown then takes a while (as numba's and the thread pools' do)."""
    sigterm_as_interrupt()
    atexit.register(time.sleep, 3)
    connection.send("done")


def test_a_stop_during_a_workers_teardown_prints_no_traceback(tmp_path):
    script = tmp_path / "parent.py"
    script.write_text(textwrap.dedent(f"""
        import multiprocessing, os, signal, sys, time
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from somarm.run.workers import start
        from test_workers import _work_then_linger
        if __name__ == "__main__":
            connection, process = start(multiprocessing.get_context("spawn"), _work_then_linger, (),
                                        name="w", duplex=False)
            assert connection.recv() == "done"
            time.sleep(1.5)  # the worker is in its teardown now
            os.kill(process.pid, signal.SIGTERM)  # as its parent's death would
            process.join(30)
            print("exit", process.exitcode)
    """))
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=60,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert "exit" in done.stdout, done.stderr
    assert "Traceback" not in done.stderr and "KeyboardInterrupt" not in done.stderr, done.stderr

