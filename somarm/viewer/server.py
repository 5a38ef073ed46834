"""Start and stop a meshcat server bound to one host, and never leave it orphaned.

The server runs as a child process (``somarm.viewer._bridge``); its output goes to a log
file, never to a pipe someone must keep reading. It is stopped by ``stop()``, by the
context manager, at interpreter exit, on SIGTERM and Ctrl-C (``stop_on_signals``), and
by itself when its parent dies.
"""

from __future__ import annotations

import atexit
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from somarm.validation import check_int, check_number

__all__ = ["MeshcatServer", "stop_on_signals"]

_STOP_GRACE_S = 3.0
#: Each server's log and ready file live in ``<tmp>/somarm-meshcat-<owner pid>-<random>``.
_FOLDER_PREFIX = "somarm-meshcat-"


class MeshcatServer:
    """A meshcat server (web page + zmq command socket) in a child process.

    Args:
      host: address the web page listens on. 127.0.0.1 (this machine only) unless you
        mean to share the viewer; the zmq command socket is always on 127.0.0.1.
      port: web port; None lets the system pick a free one.
      start_timeout_s: how long to wait for the server to come up.
      title: the page's title (the task's name).
      live_task: if given, the server draws this task itself from snapshots pushed to ``feed_url``
        (what ``LiveView`` uses); ``task_params`` are the task's parameters.
      live_model: instead of a task, any compiled MuJoCo model, drawn from snapshots of its states.

    Attributes (after ``start``):
      web_url: the page to open, e.g. ``http://127.0.0.1:7001/static/``.
      zmq_url: where commands go.
      port: the web port actually bound.
      feed_url: where ``LiveView`` pushes frames (only with ``live_task``).
    """

    def __init__(self, *, host: str = "127.0.0.1", port: int | None = None, start_timeout_s: float = 30.0,
                 title: str = "somarm", live_task: str | None = None, task_params: dict | None = None,
                 live_model=None):
        if not isinstance(host, str) or not host:
            raise ValueError(f"host must be a non-empty address string, got {host!r}")
        self.host = host
        self.requested_port = 0 if port is None else check_int("port", port, minimum=0)
        if self.requested_port > 65535:
            raise ValueError(f"port must be in 0..65535, got {port!r}")
        self.start_timeout_s = check_number("start_timeout_s", start_timeout_s, minimum=0, strict_minimum=True)
        if not isinstance(title, str):
            raise ValueError(f"title must be a string, got {title!r}")
        self.title = title
        self.live_task = live_task
        self.live_model = live_model
        self.task_params = dict(task_params or {})
        self.feed_url: str | None = None
        self.web_url: str | None = None
        self.zmq_url: str | None = None
        self.port: int | None = None
        self.process: subprocess.Popen | None = None
        self._folder: tempfile.TemporaryDirectory | None = None
        self._lock = threading.Lock()

    @property
    def log_path(self) -> Path | None:
        """The server's stdout/stderr log (kept until ``stop``)."""
        return None if self._folder is None else Path(self._folder.name) / "server.log"

    def start(self) -> MeshcatServer:
        """Start the child process and wait until it reports its addresses.

        Raises:
          RuntimeError: the server exited early (e.g. port taken) or did not come up in time;
            the message is one line: the error the server's log ends with.
        """
        if self.process is not None:
            return self
        _remove_stale_folders()
        self._folder = tempfile.TemporaryDirectory(prefix=f"{_FOLDER_PREFIX}{os.getpid()}-")
        ready_file = Path(self._folder.name) / "ready.json"
        log = open(self.log_path, "wb")  # the child owns it from here
        command = [
            sys.executable, "-m", "somarm.viewer._bridge", "--host", self.host,
            "--port", str(self.requested_port), "--ready-file", str(ready_file),
            "--parent-pid", str(os.getpid()), "--title", self.title,
        ]
        if self.live_task is not None:
            command += ["--live-task", self.live_task, "--task-params", json.dumps(self.task_params)]
        elif self.live_model is not None:
            import mujoco

            model_file = Path(self._folder.name) / "model.mjb"
            mujoco.mj_saveModel(self.live_model, str(model_file), None)
            command += ["--live-model", str(model_file)]
        # Own session: a Ctrl-C in the terminal reaches us, and we stop the server in order.
        self.process = subprocess.Popen(
            command, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
        )
        log.close()
        atexit.register(self.stop)
        deadline = time.monotonic() + self.start_timeout_s
        while not ready_file.exists():
            if self.process.poll() is not None or time.monotonic() > deadline:
                reason = _last_error(self.log_path.read_text(errors="replace"))
                self.stop()
                raise RuntimeError(f"meshcat server on {self.host}:{self.requested_port} did not start: {reason}")
            time.sleep(0.02)
        ready = json.loads(ready_file.read_text())
        self.web_url, self.zmq_url, self.port = ready["web_url"], ready["zmq_url"], int(ready["port"])
        self.feed_url = ready.get("feed_url")
        return self

    def alive(self) -> bool:
        """True while the child process runs."""
        return self.process is not None and self.process.poll() is None

    def stop(self) -> None:
        """Terminate the server (kill it if it does not go within a few seconds). Idempotent."""
        with self._lock:
            process, self.process = self.process, None
            if process is not None and process.poll() is None:
                process.terminate()
                try:
                    process.wait(timeout=_STOP_GRACE_S)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait(timeout=_STOP_GRACE_S)
            if self._folder is not None:
                self._folder.cleanup()
                self._folder = None
        atexit.unregister(self.stop)

    def __enter__(self) -> MeshcatServer:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def __repr__(self) -> str:
        state = "running" if self.alive() else "stopped"
        return f"MeshcatServer(host={self.host!r}, port={self.port}, {state})"


def _remove_stale_folders() -> None:
    """Remove the folders of servers whose owner died without stopping them (SIGKILL, power loss).

    The bridge removes its own folder when its owner dies; this catches the case where both died.
    """
    for folder in Path(tempfile.gettempdir()).glob(f"{_FOLDER_PREFIX}*-*"):
        owner = folder.name[len(_FOLDER_PREFIX):].split("-", 1)[0]
        if owner.isdigit() and not _pid_alive(int(owner)):
            shutil.rmtree(folder, ignore_errors=True)


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, someone else's
        return True
    return True


def _last_error(log: str) -> str:
    """The line of a child's log that says what went wrong (a traceback's last line), without its type.

    ``OSError: [Errno 98] Address already in use`` -> ``[Errno 98] Address already in use``.
    """
    lines = [line.strip() for line in log.splitlines() if line.strip()]
    if not lines:
        return "it exited without a word (or took too long)"
    kind, sep, text = lines[-1].partition(": ")
    return text if sep and kind.replace(".", "").replace("_", "").isalnum() and " " not in kind else lines[-1]


def stop_on_signals(server: MeshcatServer) -> None:
    """On SIGTERM stop ``server`` and exit with status 143, after any earlier handler.

    Ctrl-C raises KeyboardInterrupt as usual; callers stop the server in ``finally`` (and
    ``atexit`` does it otherwise). Only the main thread may install handlers, so from any
    other thread this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        return
    previous = signal.getsignal(signal.SIGTERM)

    def handle(signum, frame):
        server.stop()
        if callable(previous):
            previous(signum, frame)
        raise SystemExit(128 + signum)

    signal.signal(signal.SIGTERM, handle)
