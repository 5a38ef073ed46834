"""Where meshcat commands go: a zmq client that never hangs, and an in-memory recorder.

meshcat's own client waits forever for a reply, so one dead server hangs the caller. Ours
sets send/receive timeouts and ``LINGER=0``; after the first timeout it warns once, marks
itself dead and drops every later command, so a training run carries on without a viewer.
"""

from __future__ import annotations

import warnings
from typing import Protocol

import umsgpack
import zmq

from somarm.viewer.text import TEXT_COMMAND

__all__ = ["CommandSink", "MeshcatClient", "Recorder", "ViewerUnavailableWarning"]


class ViewerUnavailableWarning(RuntimeWarning):
    """The meshcat server stopped answering; the viewer is switched off for this run."""


class CommandSink(Protocol):
    """Anything that accepts lowered meshcat commands (live server or recorder)."""

    def send(self, command: dict) -> bool:
        """Deliver one command; False when it was dropped."""

    def send_batch(self, commands: list[dict]) -> bool:
        """Deliver commands in order; False when they were dropped."""


class MeshcatClient:
    """Sends lowered meshcat commands to a meshcat zmq server, with timeouts.

    Args:
      zmq_url: the server's zmq address, e.g. ``"tcp://127.0.0.1:6001"``.
      timeout_s: longest wait for one send or one reply before the server counts as dead.
        Rule of thumb: a live local server answers in well under 10 ms; 2 s leaves room for
        a busy machine without letting a dead server stall anyone for long.
    """

    def __init__(self, zmq_url: str, *, timeout_s: float = 2.0) -> None:
        if not isinstance(zmq_url, str) or not zmq_url.startswith(("tcp://", "ipc://")):
            raise ValueError(f"zmq_url must be a tcp:// or ipc:// address, got {zmq_url!r}")
        if not timeout_s > 0:
            raise ValueError(f"timeout_s must be > 0, got {timeout_s!r}")
        self.zmq_url = zmq_url
        self.timeout_ms = max(1, int(timeout_s * 1000))
        self.dead = False
        self._context = zmq.Context.instance()
        self._socket = self._connect()

    def _connect(self) -> zmq.Socket:
        socket = self._context.socket(zmq.REQ)
        socket.setsockopt(zmq.SNDTIMEO, self.timeout_ms)
        socket.setsockopt(zmq.RCVTIMEO, self.timeout_ms)
        socket.setsockopt(zmq.LINGER, 0)  # closing never waits for a dead peer
        socket.connect(self.zmq_url)
        return socket

    def _die(self, reason: str) -> None:
        if not self.dead:
            self.dead = True
            warnings.warn(
                f"meshcat server at {self.zmq_url} {reason}; viewing is off from now on, the run carries on",
                ViewerUnavailableWarning,
                stacklevel=3,
            )
        self._socket.close(linger=0)

    def request(self, frames: list[bytes]) -> bytes | None:
        """Send ``frames`` and return the reply, or None (and go dead) on a timeout."""
        if self.dead:
            return None
        try:
            self._socket.send_multipart(frames)
            return self._socket.recv()
        except zmq.Again:
            self._die(f"did not answer within {self.timeout_ms} ms")
        except zmq.ZMQError as exc:
            self._die(f"failed ({exc})")
        return None

    def send(self, command: dict) -> bool:
        """Send one lowered command (``SetObject(...).lower()`` etc.); False if dropped."""
        frames = [command["type"].encode(), command.get("path", "").encode(), umsgpack.packb(command)]
        return self.request(frames) is not None

    def send_batch(self, commands: list[dict]) -> bool:
        """Send many lowered commands in one round trip (needs somarm's server); False if dropped."""
        if not commands:
            return True
        frames = [b"batch"]
        for command in commands:
            frames += [command["type"].encode(), command.get("path", "").encode(), umsgpack.packb(command)]
        return self.request(frames) is not None

    def web_url(self) -> str | None:
        """The page the server serves, as the server reports it."""
        reply = self.request([b"url"])
        return None if reply is None else reply.decode()

    def close(self) -> None:
        """Close the socket without waiting for anything."""
        if not self._socket.closed:
            self._socket.close(linger=0)


class Recorder:
    """Keeps the last state of every path, like meshcat's server tree, for the static HTML export.

    The overlay's ``somarm_text`` commands are merged into one (each sets only its fields).
    """

    def __init__(self) -> None:
        self.objects: dict[str, dict] = {}
        self.properties: dict[str, list[dict]] = {}
        self.transforms: dict[str, dict] = {}
        self.animation: dict | None = None
        self.text: dict | None = None

    def send(self, command: dict) -> bool:
        """Record one lowered command; always True."""
        kind, path = command["type"], command.get("path", "")
        if kind == "set_object":
            self.objects[path] = command
            self.properties[path] = []
        elif kind == "set_property":
            self.properties.setdefault(path, []).append(command)
        elif kind == "set_transform":
            self.transforms[path] = command
        elif kind == "set_animation":
            self.animation = command
        elif kind == TEXT_COMMAND:
            self.text = {**(self.text or {}), **command}
        elif kind == "delete":
            for store in (self.objects, self.properties, self.transforms):
                for key in [k for k in store if k == path or k.startswith(path + "/")]:
                    del store[key]
        else:
            raise ValueError(f"unknown meshcat command type {kind!r}")
        return True

    def send_batch(self, commands: list[dict]) -> bool:
        """Record commands in order; always True."""
        for command in commands:
            self.send(command)
        return True

    def commands(self) -> list[dict]:
        """All recorded commands in replay order: objects, properties, transforms, text, animation."""
        ordered = list(self.objects.values())
        ordered += [p for props in self.properties.values() for p in props]
        ordered += list(self.transforms.values())
        if self.text is not None:
            ordered.append(self.text)
        if self.animation is not None:
            ordered.append(self.animation)
        return ordered
