"""Shared by the real-process tests (not collected): whether a process still runs, and waiting for that to end."""

import time


def alive(pid: int) -> bool:
    """Whether process ``pid`` exists and has not ended (a zombie has ended; its parent may be gone)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def still_running(pids, seconds: float) -> list[int]:
    """The processes of ``pids`` still running after waiting up to ``seconds`` for all to end."""
    deadline = time.monotonic() + seconds
    while (left := [pid for pid in pids if alive(pid)]) and time.monotonic() < deadline:
        time.sleep(0.2)
    return left


def survivors_of_a_killed_parent(parent, pids, seconds: float) -> list[int]:
    """SIGKILL the ``subprocess.Popen`` ``parent``, then those of ``pids`` still running after up to ``seconds``."""
    parent.kill()
    parent.wait(timeout=30)
    return still_running(pids, seconds)


def somarm_command(*argv: str) -> list[str]:
    """The command line of ``somarm ARGV`` run from this checkout (``python -m somarm.cli``)."""
    import sys

    return [sys.executable, "-m", "somarm.cli", *argv]


def checkout_env() -> dict[str, str]:
    """The environment of a process started on this checkout: no OpenGL, this checkout first on the path."""
    import os
    from pathlib import Path

    return dict(os.environ, MUJOCO_GL="disable", PYTHONPATH=str(Path(__file__).resolve().parents[1]))


def one_error_line(done, *needles: str) -> str:
    """The ``subprocess.CompletedProcess`` ``done`` failed with exit code 2 and one ``somarm: error:`` line
    holding every needle; that line."""
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith("somarm: error: "), lines[0]
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


def train_into_an_endless_evaluation(out, env):
    """``somarm train gym:Pendulum-v1`` (300 steps, 2 trials) into ``out`` with greedy episodes 10^8 steps long
    (without a cut the evaluation would run for days), returned once its last training step is shown."""
    import subprocess

    proc = subprocess.Popen(somarm_command("train", "gym:Pendulum-v1", "--steps", "300", "--trials", "2",
                                           "--task-set", "max_episode_steps=100000000", "--task-set",
                                           "evaluation_steps=100000000", "--no-figures", "--out", str(out)),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    lines = []
    while not any("300/300" in line for line in lines):  # the progress line of the last step
        lines.append(proc.stderr.readline())
        if not lines[-1] and proc.poll() is not None:
            proc.kill()
            raise AssertionError("".join(lines))
    return proc
