"""The meshcat server we start: loopback only, timeouts, no orphans, no frozen pipe, live hook."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path

import meshcat.geometry as mg
import mujoco
import numpy as np
import pytest
import umsgpack
from meshcat.commands import SetObject

from somarm.viewer.client import MeshcatClient, ViewerUnavailableWarning
from somarm.viewer.scene import path_of
from somarm.viewer.server import MeshcatServer


@pytest.fixture
def server():
    running = MeshcatServer().start()
    yield running
    running.stop()


def box_command(name="box"):
    return SetObject(mg.Box([0.1, 0.2, 0.3]), path=path_of(f"/meshcat/{name}")).lower()


def listening_addresses(port: int) -> set[str]:
    """Local addresses with a socket LISTENing on ``port``, read from /proc (no traffic)."""
    found = set()
    for table, width in (("/proc/net/tcp", 8), ("/proc/net/tcp6", 32)):
        if not os.path.exists(table):
            continue
        with open(table) as handle:
            next(handle)
            for line in handle:
                fields = line.split()
                address, port_hex = fields[1].split(":")
                if fields[3] == "0A" and int(port_hex, 16) == port:  # 0A = LISTEN
                    if width == 8:
                        found.add(".".join(str(b) for b in reversed(bytes.fromhex(address))))
                    else:
                        found.add(address)
    return found


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # A zombie (exited, not yet reaped by its parent) counts as gone.
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def wait_until(condition, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


def test_listens_on_loopback_only_by_default(server):
    assert server.web_url.startswith("http://127.0.0.1:")
    assert listening_addresses(server.port) == {"127.0.0.1"}
    zmq_port = int(server.zmq_url.rsplit(":", 1)[1])
    assert listening_addresses(zmq_port) == {"127.0.0.1"}


def test_the_host_argument_is_honoured():
    # Another loopback address: shows the bind follows --host without exposing anything.
    with MeshcatServer(host="127.0.0.2") as other:
        assert other.web_url.startswith("http://127.0.0.2:")
        assert listening_addresses(other.port) == {"127.0.0.2"}
    with pytest.raises(ValueError, match="host"):
        MeshcatServer(host="")


def test_commands_round_trip_and_the_url_is_reported(server):
    client = MeshcatClient(server.zmq_url, timeout_s=5.0)
    assert client.web_url() == server.web_url
    assert client.send(box_command())
    assert client.send_batch([box_command("a"), box_command("b")])
    assert client.request([b"n_clients"]) == b"0"
    client.close()


def test_a_killed_server_times_out_warns_once_and_never_hangs(server):
    client = MeshcatClient(server.zmq_url, timeout_s=0.3)
    assert client.send(box_command())
    server.process.kill()
    server.process.wait(timeout=5)
    start = time.monotonic()
    with pytest.warns(ViewerUnavailableWarning, match="did not answer"):
        assert client.send(box_command()) is False
    assert time.monotonic() - start < 3.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a second warning would fail here
        assert client.send(box_command()) is False
        assert client.send_batch([box_command()]) is False
    assert client.dead


def test_port_in_use_fails_with_the_servers_reason(server):
    with pytest.raises(RuntimeError, match="did not start"):
        MeshcatServer(port=server.port, start_timeout_s=20).start()
    with pytest.raises(ValueError, match="port must be"):
        MeshcatServer(port=70000)


async def _connect_many(url: str, n: int) -> int:
    import tornado.websocket

    opened = 0
    for _ in range(n):
        connection = await asyncio.wait_for(tornado.websocket.websocket_connect(url), timeout=5)
        opened += 1
        connection.close()
    return opened


def test_hundreds_of_browser_connections_do_not_freeze_the_server(server):
    client = MeshcatClient(server.zmq_url, timeout_s=5.0)
    client.send(box_command())  # each connection is sent the scene, as a browser would be
    ws_url = f"ws://127.0.0.1:{server.port}/"
    assert asyncio.run(_connect_many(ws_url, 400)) == 400
    assert client.send(box_command("after"))
    assert server.log_path.stat().st_size < 4096  # nothing printed per connection
    client.close()


async def _wait_then_send(server: MeshcatServer) -> tuple[bytes | None, bool]:
    import tornado.websocket

    connection = await asyncio.wait_for(
        tornado.websocket.websocket_connect(f"ws://127.0.0.1:{server.port}/"), timeout=5
    )
    client = MeshcatClient(server.zmq_url, timeout_s=5.0)
    loop = asyncio.get_running_loop()
    reply = await loop.run_in_executor(None, client.request, [b"wait"])
    sent = await loop.run_in_executor(None, client.send, box_command())
    connection.close()
    client.close()
    return reply, sent


def test_wait_then_send_does_not_hang(server):
    reply, sent = asyncio.run(_wait_then_send(server))
    assert reply == b"ok" and sent


_PARENT = textwrap.dedent(
    """
    import sys, time
    from somarm.viewer.server import MeshcatServer, stop_on_signals
    server = MeshcatServer().start()
    stop_on_signals(server)
    print(server.process.pid, server.log_path.parent, flush=True)
    try:
        time.sleep(60)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    """
)


@pytest.mark.parametrize("how", [signal.SIGTERM, signal.SIGINT, signal.SIGKILL])
def test_the_server_is_not_orphaned(how):
    parent = subprocess.Popen([sys.executable, "-c", _PARENT], stdout=subprocess.PIPE, text=True)
    try:
        pid, folder = parent.stdout.readline().split()
        server_pid, folder = int(pid), Path(folder)
        assert pid_alive(server_pid) and folder.is_dir()
        parent.send_signal(how)
        parent.wait(timeout=10)
        assert wait_until(lambda: not pid_alive(server_pid), timeout_s=10), f"server {server_pid} orphaned"
        assert not folder.exists(), f"{folder} left behind"
        if how == signal.SIGTERM:
            assert parent.returncode == 128 + signal.SIGTERM
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()


def test_a_server_start_removes_folders_of_dead_owners(tmp_path):
    import tempfile

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True, check=True)
    stale = Path(tempfile.gettempdir()) / f"somarm-meshcat-{int(dead.stdout)}-test"
    stale.mkdir()
    (stale / "server.log").write_text("left by a SIGKILL")
    ours = Path(tempfile.gettempdir()) / f"somarm-meshcat-{os.getpid()}-test"
    ours.mkdir()
    try:
        with MeshcatServer():
            assert not stale.exists() and ours.is_dir()  # a live owner's folder stays
    finally:
        ours.rmdir()


async def _scene_messages(port: int, n_wait_s: float = 1.0) -> list[dict]:
    """Every command a newly connected browser is sent, decoded."""
    import tornado.websocket

    connection = await asyncio.wait_for(tornado.websocket.websocket_connect(f"ws://127.0.0.1:{port}/"), 5)
    messages = []
    deadline = time.monotonic() + n_wait_s
    while time.monotonic() < deadline:
        try:
            message = await asyncio.wait_for(connection.read_message(), timeout=0.2)
        except asyncio.TimeoutError:
            continue
        if message is None:
            break
        messages.append(umsgpack.unpackb(message))
    connection.close()
    return messages


def _fixed_policy(angles):
    return lambda observations: np.tile(angles, (len(observations), 1))


def test_live_view_snapshots_reach_the_scene_at_mujocos_pose():
    from somarm.viewer.live import LiveView
    from somarm.viewer.shows import load_model

    action = np.array([0.4, 1.9])
    with LiveView("reach2", policy=_fixed_policy(action), trial=0, hold_s=0.2) as view:
        view.update(5, np.array([[0.55, 0.6], [0.1, 0.1]]), np.zeros((2, 2)), np.array([-0.1, -0.2]))
        port = int(view.url.split(":")[2].split("/")[0])

        def link2_position():
            found = [m for m in asyncio.run(_scene_messages(port, 0.5))
                     if m["type"] == "set_transform" and m["path"] == "/meshcat/reach2/link2"]
            return np.array(found[-1]["matrix"]).reshape(4, 4).T[:3, 3] if found else None

        expected_data = mujoco.MjData(model := load_model("arm2"))
        expected_data.qpos[:] = action
        mujoco.mj_forward(model, expected_data)
        expected = expected_data.xpos[model.body("link2").id]
        assert wait_until(lambda: (m := link2_position()) is not None and np.allclose(m, expected, atol=1e-9),
                          timeout_s=10)
        assert view.frames_sent == 1


def _overlay(port: int) -> dict:
    """The overlay text a browser connecting now is sent (merged)."""
    texts = [m for m in asyncio.run(_scene_messages(port, 0.3)) if m["type"] == "somarm_text"]
    merged = {}
    for text in texts:
        merged.update(text)
    return merged


def test_the_live_page_says_the_step_the_goal_and_when_training_finished():
    from somarm.viewer.live import LiveView

    with LiveView("reach2", policy=_fixed_policy([0.4, 1.9]), hold_s=0.2, n_steps=900, n_goals=3,
                  lines=["somq learner, trial 0"]) as view:
        port = int(view.url.split(":")[2].split("/")[0])
        for step in (10, 500):
            view.update(step, np.full((1, 2), 0.5), np.zeros((1, 2)), np.array([-0.25]))
            assert wait_until(lambda step=step: f"training: step {step:,} of 900" in _overlay(port).get("status", ""),
                              timeout_s=10)
            view._next_time = view._next_send = 0.0  # the next update samples and sends at once
        text = _overlay(port)
        assert text["title"] == "reach2: greedy pose, a cycle of 3" and text["lines"] == ["somq learner, trial 0"]
        assert any(line.startswith("running mean reward -0.250") for line in text["caption"])
        assert any(line.startswith("greedy error over the 3 goals: mean") for line in text["caption"])
        assert text["caption"][0].split(" at ")[0] in {"goal 1 of 3", "goal 2 of 3", "goal 3 of 3"}
        view.finish(900)
        assert wait_until(lambda: _overlay(port).get("status", "").startswith("training finished after 900 steps"),
                          timeout_s=10)
        assert view.serving()


def test_the_server_page_has_the_task_as_title_a_favicon_and_the_bare_address_leads_to_it():
    import urllib.error
    import urllib.request

    with MeshcatServer(title="reach2") as server:
        base = f"http://127.0.0.1:{server.port}"
        page = urllib.request.urlopen(f"{base}/static/").read().decode()
        assert "<title>reach2</title>" in page and "SomarmOverlay.install(viewer)" in page
        assert 'src="main.min.js"' in page and "viewer.connect()" in page
        assert urllib.request.urlopen(f"{base}/static/index.html").read().decode() == page
        assert urllib.request.urlopen(f"{base}/static/main.min.js").status == 200
        icon = urllib.request.urlopen(f"{base}/favicon.ico")
        assert icon.status == 200 and icon.headers["Content-Type"] == "image/svg+xml"
        assert icon.read().startswith(b"<svg")
        bare = urllib.request.urlopen(f"{base}/")  # follows the redirect
        assert bare.url == f"{base}/static/" and "<title>reach2</title>" in bare.read().decode()


def test_live_view_is_throttled_and_survives_a_stopped_or_killed_server():
    from somarm.viewer.live import LiveView

    observations, actions, rewards = np.full((3, 2), 0.5), np.full((3, 2), 0.3), np.zeros(3)
    with LiveView("reach2", policy=_fixed_policy([0.3, 0.3]), max_rate_hz=200.0, hold_s=0.05) as view:
        assert view.url.startswith("http://127.0.0.1:")
        start = time.monotonic()
        n_calls = 0
        while time.monotonic() - start < 0.5:
            view.update(n_calls, observations, actions, rewards)
            n_calls += 1
        elapsed = time.monotonic() - start
        assert 2 <= view.frames_sent <= elapsed / 0.05 + 2  # throttled: one snapshot per hold at most
        assert n_calls > 100 * view.frames_sent and view._n_rewards <= 200.0 * elapsed + 2
        # A frozen server (SIGSTOP) never blocks update: snapshots are simply not taken.
        os.kill(view._server.process.pid, signal.SIGSTOP)
        start, steps = time.monotonic(), 0
        while time.monotonic() - start < 0.5:
            view.update(steps, observations, actions, rewards)
            steps += 1
        assert steps > 1000 and view.alive
        os.kill(view._server.process.pid, signal.SIGCONT)
        view._server.process.kill()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            start, steps = time.monotonic(), 0
            while time.monotonic() - start < 2.0:  # "training" keeps going
                view.update(steps, observations, actions, rewards)
                steps += 1
        assert not view.alive and not view.serving() and steps > 1000
        assert sum(issubclass(w.category, ViewerUnavailableWarning) for w in caught) == 1
        view.finish(steps)  # nothing to send to: returns quietly


def test_a_bad_snapshot_is_logged_and_the_feed_carries_on():
    import zmq

    from somarm.viewer.feed import unpack_snapshot
    from somarm.viewer.live import pack_snapshot

    snapshot = unpack_snapshot(pack_snapshot({"kind": "goals", "step": 7, "items": {"actions": np.eye(2)}}))
    assert snapshot["step"] == 7 and snapshot["items"]["actions"] == [[1.0, 0.0], [0.0, 1.0]]
    with pytest.raises(ValueError, match="msgpack"):
        unpack_snapshot(b"\xc1 not msgpack")
    with pytest.raises(ValueError, match="a dict with a kind"):
        unpack_snapshot(pack_snapshot({"kind": "juggling", "items": {}}))
    with MeshcatServer(live_task="reach2") as live:
        push = zmq.Context.instance().socket(zmq.PUSH)
        push.setsockopt(zmq.LINGER, 0)
        push.connect(live.feed_url)
        push.send(b"not a snapshot at all!")
        assert wait_until(lambda: "snapshot dropped" in live.log_path.read_text(), timeout_s=10)
        push.send(pack_snapshot({"kind": "goals", "step": 1, "finished": False, "items": {
            "observations": [[0.5, 0.5]], "actions": [[0.1, 0.2]], "greedy": True}}))
        client = MeshcatClient(live.zmq_url, timeout_s=5)
        assert client.web_url() == live.web_url  # still serving
        client.close()
        push.close()


def test_live_view_rejects_bad_arguments():
    from somarm.viewer.live import LiveView

    with pytest.raises(ValueError, match="max_rate_hz"):
        LiveView("reach2", max_rate_hz=0)
    with pytest.raises(ValueError, match="hold_s"):
        LiveView("reach2", hold_s=0)
    with pytest.raises(ValueError, match="unknown task"):
        LiveView("juggle")
    with pytest.raises(ValueError, match="a task name or an env"):
        LiveView()
    with LiveView("reach2", trial=3) as view, pytest.raises(ValueError, match="trial=3 is not in this batch of 2"):
        view.update(1, np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2))


def test_cli_rejects_bad_input_in_one_line(capsys):
    from somarm.viewer.cli import main

    assert main(["juggle"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown task 'juggle'" in err[0] and "reach2" in err[0]
    assert main(["reach2", "--goals", "0"]) == 2
    assert "--goals" in capsys.readouterr().err
    assert main(["reach2", "--port", "70000"]) == 2


@pytest.mark.parametrize("task", ["reach2", "four_goals", "reach20", "throw"])
def test_cli_writes_an_offline_animation(task, tmp_path, capsys):
    from somarm.viewer.cli import main

    out = tmp_path / f"{task}.html"
    assert main([task, "--html", str(out), "--goals", "3"]) == 0
    text = out.read_text()
    assert "MeshCat.Viewer" in text and len(text) > 500_000  # the viewer script is inlined
    assert f"<title>{task}</title>" in text and "SomarmOverlay" in text
    assert "mean error" in capsys.readouterr().out


def test_cli_serves_until_ctrl_c_and_leaves_no_server():
    command = [sys.executable, "-m", "somarm.viewer.cli", "reach2", "--goals", "2", "--interval", "0.2"]
    env = dict(os.environ, MUJOCO_GL="disable")
    viewer = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = viewer.stdout.readline()
        assert "open http://127.0.0.1:" in line, line + viewer.stderr.read()
        port = int(line.split("http://127.0.0.1:")[1].split("/")[0])
        assert listening_addresses(port) == {"127.0.0.1"}
        assert "error" in viewer.stdout.readline()  # one line per goal shown
        import urllib.request

        assert "<title>reach2</title>" in urllib.request.urlopen(f"http://127.0.0.1:{port}/").read().decode()
        text = _overlay(port)
        assert text["title"] == "reach2: greedy answer for each goal" and text["caption"][0].startswith("goal ")
        viewer.send_signal(signal.SIGINT)
        assert viewer.wait(timeout=15) == 130
        assert wait_until(lambda: not listening_addresses(port), timeout_s=10)
    finally:
        if viewer.poll() is None:
            viewer.kill()
            viewer.wait()


def test_train_view_keeps_showing_the_final_policy_until_ctrl_c(tmp_path):
    out = tmp_path / "run"
    command = [sys.executable, "-m", "somarm.cli", "train", "reach2", "--steps", "2000", "--view", "--out", str(out),
               "--no-progress", "--no-figures"]
    env = dict(os.environ, MUJOCO_GL="disable")
    training = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        first = training.stdout.readline()
        assert first.startswith("viewer: http://127.0.0.1:"), first + training.stderr.read()
        port = int(first.split("http://127.0.0.1:")[1].split("/")[0])
        assert training.stdout.readline().startswith("done: 2000 steps")
        assert "the viewer keeps showing the final policy" in training.stdout.readline()
        assert (out / "learner.npz").is_file()  # the run is written before the viewer waits
        assert wait_until(lambda: _overlay(port).get("status", "").startswith("training finished after 2,000"),
                          timeout_s=10)
        training.send_signal(signal.SIGINT)
        assert training.wait(timeout=15) == 0
        assert wait_until(lambda: not listening_addresses(port), timeout_s=10)
    finally:
        if training.poll() is None:
            training.kill()
            training.wait()
