"""The viewer's server process survives malformed messages on its ports: each dropped, one line in its log."""

import socket
import time

import pytest
import umsgpack
import zmq

from somarm.viewer.server import MeshcatServer

JUNK = {
    "bytes that are no command": [b"\xff\xfe"],
    "an unknown command": [b"capture_image"],
    "a command with two frames": [b"set_transform", b"/a"],
    "a batch of junk": [b"batch", b"\xff", b"x", b"y"],
    "a batch that is not triples": [b"batch", b"set_transform", b"/a"],
    "data that is not msgpack": [b"set_object", b"/a", b"junk"],
    "an overlay that is not a map": [b"somarm_text", b"", umsgpack.packb(7)],
    "an empty overlay": [b"somarm_text", b"", b""],
}


def _request(url: str, frames: list[bytes]) -> bytes:
    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.RCVTIMEO, 10_000)
    sock.connect(url)
    try:
        sock.send_multipart(frames)
        return sock.recv()
    finally:
        sock.close()


@pytest.fixture(scope="module")
def server():
    with MeshcatServer(live_task="reach2") as started:
        yield started


def test_malformed_requests_are_answered_as_errors_dropped_and_logged_in_one_line_each(server):
    for name, frames in JUNK.items():
        assert _request(server.zmq_url, frames).startswith(b"error: "), name
        assert _request(server.zmq_url, [b"n_clients"]) == b"0", name  # the next request is answered
    for port in (server.zmq_url, server.feed_url):  # raw bytes that are no zmq at all
        with socket.create_connection(("127.0.0.1", int(port.rsplit(":", 1)[1]))) as raw:
            raw.sendall(b"\xff" * 64 + b"GET / HTTP/1.0\r\n\r\n")
            time.sleep(0.2)
    push = zmq.Context.instance().socket(zmq.PUSH)
    push.setsockopt(zmq.LINGER, 1000)
    push.connect(server.feed_url)
    push.send_multipart([b"\xff", b"not a snapshot"])
    push.close()
    time.sleep(0.5)
    assert server.alive()
    assert _request(server.zmq_url, [b"set_transform", b"/a", umsgpack.packb({"type": "set_transform"})]) == b"ok"
    log = server.log_path.read_text().splitlines()
    dropped = [line for line in log if line.startswith("bridge: request dropped")]
    assert len(dropped) == len(JUNK) and "Traceback" not in "\n".join(log), log


def test_a_dead_server_is_one_warning_line_with_no_source_beneath_it(tmp_path):
    import subprocess
    import sys

    from processes import checkout_env

    script = (
        "import time\nimport numpy as np\nfrom somarm.viewer.live import LiveView\n"
        "view = LiveView('reach2', policy=lambda x: np.full((len(x), 2), 0.3), hold_s=0.05)\n"
        "view._server.process.kill()\nstart = time.monotonic()\n"
        "while time.monotonic() - start < 2.0:\n"
        "    view.update(1, np.full((1, 2), 0.5), np.full((1, 2), 0.3), np.zeros(1))\n"
        "view.close()\nprint('trained on', view.alive)\n")
    (tmp_path / "train.py").write_text(script)  # a file: a warning would show its line
    done = subprocess.run([sys.executable, str(tmp_path / "train.py")], capture_output=True, text=True,
                          env=checkout_env(), timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "trained on False", done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "ViewerUnavailableWarning: the meshcat viewer's server stopped" in lines[0], lines
