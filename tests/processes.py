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
