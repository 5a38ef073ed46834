"""The meshcat server process: meshcat's zmq-to-websocket bridge, bound where we say.

Run as ``python -m somarm.viewer._bridge --host H --port P --ready-file F --parent-pid N``
by ``somarm.viewer.server``. It differs from ``meshcat-server`` where that one has defects:

- the web server listens on ``--host`` only (meshcat's listens on every interface), and the
  zmq socket on 127.0.0.1 only;
- the port may be 0 (the system picks a free one), reported through ``--ready-file``
  instead of stdout, so the parent never has to keep reading a pipe;
- nothing is printed per browser connection (meshcat's prints two lines each, which froze
  it once an unread pipe filled up);
- its page (``/static/``) is somarm's: the task as the title, a favicon, the text overlay
  (``html.live_page``), and it forwards and remembers the overlay's ``somarm_text`` commands;
- the bare address ``/`` sends a browser to the page (meshcat answers it with
  ``Can "Upgrade" only to "WebSocket"``: the websocket lives there too);
- with ``--live-task`` or ``--live-model`` it draws what training sends it (``feed.py``);
- a ``batch`` request carries many commands in one round trip (a live frame of the
  20-link arm is about 25 commands);
- ``wait`` is answered through the zmq stream (meshcat answers on the bare socket, after
  which the stream misses the next request and the caller hangs);
- it exits by itself when its parent dies, so a killed training run leaves no orphan.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys

import tornado.httpserver
import tornado.ioloop
import tornado.netutil
import tornado.web
import umsgpack
import zmq
from meshcat.servers.tree import SceneTree, find_node
from meshcat.servers.zmqserver import (
    MESHCAT_COMMANDS,
    VIEWER_HTML,
    VIEWER_ROOT,
    StaticFileHandlerNoCache,
    WebSocketHandler,
    ZMQWebSocketBridge,
)

from somarm.validation import whole_number
from somarm.viewer.html import FAVICON_SVG, live_page
from somarm.viewer.text import TEXT_COMMAND

__all__ = ["LoopbackBridge", "main"]

_PARENT_CHECK_MS = 500


class _QuietWebSocketHandler(WebSocketHandler):
    """meshcat's websocket handler without the per-connection prints; a plain GET goes to the page."""

    async def get(self, *args, **kwargs):
        if self.request.headers.get("Upgrade", "").lower() != "websocket":
            self.redirect("/static/")
            return
        await super().get(*args, **kwargs)

    def open(self):
        self.bridge.websocket_pool.add(self)
        self.bridge.send_scene(self)
        if self.bridge.text:
            self.write_message(umsgpack.packb(self.bridge.text), binary=True)

    def on_close(self):
        self.bridge.websocket_pool.discard(self)


class _PageHandler(tornado.web.RequestHandler):
    """somarm's viewer page (never cached: the title and the overlay are this server's)."""

    def initialize(self, page: str) -> None:
        self.page = page

    def get(self, *args):
        self.set_header("Cache-Control", "no-store")
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.write(self.page)


class _IconHandler(tornado.web.RequestHandler):
    def get(self):
        self.set_header("Content-Type", "image/svg+xml")
        self.set_header("Cache-Control", "max-age=86400")
        self.write(FAVICON_SVG)


class LoopbackBridge(ZMQWebSocketBridge):
    """meshcat's bridge with the web server bound to ``host`` and zmq bound to 127.0.0.1."""

    def __init__(self, host: str, port: int, *, title: str = "somarm") -> None:  # meshcat's binds everywhere
        self.host = host
        self.title = title
        self.text: dict = {}  # the overlay's merged state, sent to each browser that connects
        self.websocket_pool = set()
        self.app = self.make_app()
        self.ioloop = tornado.ioloop.IOLoop.current()
        self.zmq_socket, self.zmq_stream, _ = self.setup_zmq("tcp://127.0.0.1:*")
        self.zmq_url = self.zmq_socket.getsockopt(zmq.LAST_ENDPOINT).decode()
        sockets = tornado.netutil.bind_sockets(port, address=host)
        server = tornado.httpserver.HTTPServer(self.app)
        server.add_sockets(sockets)
        self.fileserver_port = sockets[0].getsockname()[1]
        url_host = f"[{host}]" if ":" in host else host
        self.web_url = f"http://{url_host}:{self.fileserver_port}/static/"
        self.tree = SceneTree()

    def make_app(self):
        return tornado.web.Application([
            (r"/static/(?:index\.html)?", _PageHandler, {"page": live_page(self.title)}),
            (r"/static/(.*)", StaticFileHandlerNoCache, {"path": VIEWER_ROOT, "default_filename": VIEWER_HTML}),
            (r"/favicon\.ico", _IconHandler),
            (r"/", _QuietWebSocketHandler, {"bridge": self}),
        ])

    def handle_zmq(self, frames):
        """Answer one request on the command socket. A malformed one (bytes that are no command, a
        wrong number of frames, data that is not msgpack) is answered ``error: ...`` and dropped, with
        one line in the log: the socket must answer every request to take the next one."""
        try:
            reply = self._answer(frames)
        except Exception as exc:
            reply = f"error: {type(exc).__name__}: {exc}".splitlines()[0].encode()
        if reply is None:  # answered later (``wait``)
            return
        if reply.startswith(b"error: "):
            print(f"bridge: request dropped ({len(frames)} frame(s), {sum(map(len, frames))} bytes): "
                  f"{reply[7:].decode(errors='replace')}", file=sys.stderr, flush=True)
        self.zmq_stream.send(reply)

    def _answer(self, frames) -> bytes | None:
        """The reply to a request (None: ``wait``, answered once a browser is connected)."""
        command = frames[0].decode("ascii")
        if command == "batch":
            return self._apply_batch(frames[1:])
        if command == "n_clients":
            return str(len(self.websocket_pool)).encode()
        if command == "wait":
            self._reply_when_connected()
            return None
        if command == "url":
            return self.web_url.encode()
        if command in (*MESHCAT_COMMANDS, TEXT_COMMAND):
            if len(frames) != 3:
                return f"error: {command} takes 3 frames (command, path, data), got {len(frames)}".encode()
            return self._apply_batch(frames)
        return f"error: unknown command {command[:40]!r}; commands: batch, n_clients, wait, url, " \
               f"{', '.join(MESHCAT_COMMANDS)}, {TEXT_COMMAND}".encode()

    def _apply_batch(self, frames) -> bytes:
        """Apply (type, path, data) triples as one request: one round trip per frame, not per command.
        Every command is checked (a known one, its data a msgpack map by its first byte; the overlay's
        read whole) before any is applied."""
        if len(frames) % 3:
            return b"error: a batch is (type, path, data) triples"
        commands = []
        for k in range(0, len(frames), 3):
            kind, path, data = frames[k].decode("ascii"), frames[k + 1].decode("utf-8"), frames[k + 2]
            if kind not in MESHCAT_COMMANDS and kind != TEXT_COMMAND:
                return f"error: unknown command {kind[:40]!r} in a batch".encode()
            if not data or not (0x80 <= data[0] <= 0x8F or data[0] in (0xDE, 0xDF)):  # a msgpack map's first byte
                return f"error: the data of {kind} is a msgpack map, got {bytes(data[:8])!r}".encode()
            if kind == TEXT_COMMAND and not isinstance(umsgpack.unpackb(data), dict):
                return f"error: the data of {TEXT_COMMAND} is not a msgpack map".encode()
            commands.append((kind, path, data))
        for kind, path, data in commands:
            self.apply_command(kind, path, data)
        return b"ok"

    def apply_command(self, kind: str, path: str, data: bytes) -> None:
        """Forward one packed command to every browser and remember it for later ones."""
        if kind not in MESHCAT_COMMANDS and kind != TEXT_COMMAND:
            return
        for websocket in self.websocket_pool:
            websocket.write_message(data, binary=True)
        if kind == TEXT_COMMAND:
            self.text = {**self.text, **umsgpack.unpackb(data)}
        else:
            self._remember(kind, [p for p in path.split("/") if p], data)

    def _remember(self, kind, path, data):
        """Keep the scene tree current, as meshcat's server does, for browsers that connect later."""
        node = find_node(self.tree, path)
        if kind == "set_transform":
            node.transform = data
        elif kind == "set_object":
            node.object = data
            node.properties = []
        elif kind == "set_property":
            node.properties.append(data)
        elif kind == "set_animation":
            node.animation = data
        elif kind == "delete":
            if path:
                parent = find_node(self.tree, path[:-1])
                if path[-1] in parent:
                    del parent[path[-1]]
            else:
                self.tree = SceneTree()

    def _reply_when_connected(self):
        if self.websocket_pool:
            self.zmq_stream.send(b"ok")
        else:
            self.ioloop.call_later(0.1, self._reply_when_connected)

    def watch_parent(self, parent_pid: int) -> None:
        """Stop the loop once ``parent_pid`` is gone (we were re-parented)."""

        def check():
            if os.getppid() != parent_pid:
                self.ioloop.stop()

        tornado.ioloop.PeriodicCallback(check, _PARENT_CHECK_MS).start()


def main(argv: list[str] | None = None) -> int:
    """Start the bridge, write its addresses to the ready file, serve until stopped."""
    parser = argparse.ArgumentParser(prog="somarm.viewer._bridge", allow_abbrev=False)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=whole_number, default=0)
    parser.add_argument("--ready-file", required=True)
    parser.add_argument("--parent-pid", type=whole_number, default=None)
    parser.add_argument("--title", default="somarm", help="the page's title (the task)")
    parser.add_argument("--live-task", default=None, help="draw this task and take LiveView snapshots")
    parser.add_argument("--live-model", default=None, help="draw this MuJoCo model (.mjb) and take snapshots")
    parser.add_argument("--task-params", default="{}", help="the task's parameters as JSON")
    args = parser.parse_args(argv)
    bridge = LoopbackBridge(args.host, args.port, title=args.title)
    if args.parent_pid is not None:
        bridge.watch_parent(args.parent_pid)
    ready = {"zmq_url": bridge.zmq_url, "web_url": bridge.web_url, "port": bridge.fileserver_port}
    if args.live_task is not None or args.live_model is not None:
        from somarm.viewer.feed import attach_feed

        ready["feed_url"] = attach_feed(bridge, task_name=args.live_task, model_path=args.live_model,
                                        task_params=json.loads(args.task_params))
    tmp = args.ready_file + ".tmp"
    with open(tmp, "w", encoding="utf-8") as handle:
        json.dump(ready, handle)
    os.replace(tmp, args.ready_file)  # the parent sees the whole file or none
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass
    if args.parent_pid is not None and os.getppid() != args.parent_pid:
        # Our owner died without stopping us (SIGKILL): nobody else will remove its folder.
        shutil.rmtree(os.path.dirname(os.path.abspath(args.ready_file)), ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
