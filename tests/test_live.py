"""`run --live` / `compare --live`: the log's topics served over the Foxglove WebSocket protocol
by foxglove-sdk's server, decoded with the schemas it advertises, and paced to real time.

A WebSocket client (the `websockets` package) connects to 127.0.0.1 offering the protocol's
subprotocols: `foxglove.websocket.v1` (the protocol's original name) and `foxglove.sdk.v1`
(what foxglove-sdk 0.30's server accepts: the same messages)."""

from __future__ import annotations

import asyncio
import base64
import json
import math
import socket
import struct
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

pytestmark = pytest.mark.closed_loop
websockets = pytest.importorskip("websockets")

LOCOPLAN = [sys.executable, "-m", "locoplan"]
SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
OP_MESSAGE_DATA = 0x01
OP_TIME = 0x02


def _stand(name: str, seconds: float) -> str:
    return (
        f"version: 1\nname: {name}\ntasks:\n"
        f"  - {{action: stand, start: 0.0, duration: {seconds}}}\nend: {seconds}\n"
    )


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _decoder(channel: dict[str, Any]) -> Any:
    """The protobuf message class of an advertised channel, from its FileDescriptorSet."""
    assert channel["schemaEncoding"] == "protobuf"
    fds = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))


@dataclass
class Session:
    """What one connection saw: the server's name, the channels by topic, and per subscribed
    topic (log time s, wall time s of arrival, decoded message)."""

    name: str = ""
    subprotocol: str | None = None
    channels: dict[str, dict[str, Any]] = field(default_factory=dict)
    messages: dict[str, list[tuple[float, float, Any]]] = field(default_factory=dict)
    server_times: list[float] = field(default_factory=list)


async def _session(port: int, topics: tuple[str, ...], seconds: float, connect_s: float) -> Session:
    """Connect (retrying for `connect_s`), subscribe to `topics` once advertised, and collect
    for `seconds` of wall time after the first message, or until the server closes."""
    deadline = time.monotonic() + connect_s
    while True:
        try:
            ws = await websockets.connect(
                f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS, max_size=None
            )
            break
        except OSError:
            if time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.05)
    session = Session(subprotocol=ws.subprotocol)
    subscribed: dict[int, str] = {}
    decoders: dict[str, Any] = {}
    first: float | None = None
    async with ws:
        while first is None or time.monotonic() - first < seconds:
            try:
                frame = await asyncio.wait_for(ws.recv(), timeout=30.0)
            except websockets.ConnectionClosed:
                break
            if isinstance(frame, str):
                op = json.loads(frame)
                if op["op"] == "serverInfo":
                    session.name = op["name"]
                elif op["op"] == "advertise":
                    subs = []
                    for ch in op["channels"]:
                        session.channels[ch["topic"]] = ch
                        if ch["topic"] in topics:
                            sid = len(subscribed) + 1
                            subscribed[sid] = ch["topic"]
                            decoders[ch["topic"]] = _decoder(ch)
                            subs.append({"id": sid, "channelId": ch["id"]})
                    if subs:
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                continue
            now = time.monotonic()
            if frame[0] == OP_TIME:
                session.server_times.append(struct.unpack_from("<Q", frame, 1)[0] / 1e9)
            elif frame[0] == OP_MESSAGE_DATA:
                sid, log_ns = struct.unpack_from("<IQ", frame, 1)
                topic = subscribed[sid]
                msg = decoders[topic].FromString(bytes(frame[13:]))
                session.messages.setdefault(topic, []).append((log_ns / 1e9, now, msg))
                first = now if first is None else first
    return session


def _start(args: list[str], cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [*LOCOPLAN, *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_run_live_serves_tf_and_joint_states_paced_to_real_time(tmp_path: Path) -> None:
    (tmp_path / "stand.yaml").write_text(_stand("live-stand", 6.0))
    port = _free_port()
    proc = _start(
        ["run", "stand.yaml", "--live", "--port", str(port), "--quiet", "--out", "runs",
         "--metrics-json", "m.json"],
        tmp_path,
    )  # fmt: skip
    try:
        session = asyncio.run(_session(port, ("/tf", "/joint_states"), 4.0, 60.0))
    finally:
        _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 0, stderr
    assert session.subprotocol in SUBPROTOCOLS
    assert session.name == "locoplan live-stand"
    # The same topics as the MCAP, Foxglove's schemas for the well-known ones.
    assert session.channels["/tf"]["schemaName"] == "foxglove.FrameTransforms"
    assert session.channels["/joint_states"]["schemaName"] == "foxglove.JointStates"
    assert {"/events", "/scene/robot", "/mpc/solution"} <= set(session.channels)
    tf = session.messages["/tf"]
    joints = session.messages["/joint_states"]
    assert len(tf) > 100 and len(joints) > 100
    _, _, first_tf = tf[0]
    frames = {t.child_frame_id for t in first_tf.transforms}
    assert "trunk" in frames and all(t.parent_frame_id == "world" for t in first_tf.transforms)
    names = [j.name for j in joints[-1][2].joints]
    assert names[0] == "L_hip_yaw" and len(names) == 16
    trunk = next(t for t in first_tf.transforms if t.child_frame_id == "trunk")
    assert math.isfinite(trunk.translation.z) and 0.3 < trunk.translation.z < 1.0
    assert session.server_times and session.server_times[-1] > 1.0  # simulation time
    # Paced at 1x: simulated time advances with wall time within 5 % over the session.
    t_first, wall_first, _ = tf[0]
    t_last, wall_last, _ = tf[-1]
    assert wall_last - wall_first > 3.0
    rate = (t_last - t_first) / (wall_last - wall_first)
    assert abs(rate - 1.0) < 0.05, rate
    metrics = json.loads((tmp_path / "m.json").read_text())
    assert abs(metrics["real_time_factor"] - 1.0) < 0.05, metrics["real_time_factor"]
    assert (tmp_path / "runs" / "live-stand.mcap").stat().st_size > 0


def test_compare_live_serves_both_runs_one_after_the_other(tmp_path: Path) -> None:
    (tmp_path / "stand.yaml").write_text(_stand("two", 2.0))
    port = _free_port()
    proc = _start(
        ["compare", "stand.yaml", "--live", "--port", str(port), "--pace", "2", "--quiet",
         "--no-plots", "--out", "cmp"],
        tmp_path,
    )  # fmt: skip
    sessions: list[Session] = []
    try:
        for _ in range(2):
            sessions.append(asyncio.run(_session(port, ("/tf",), 30.0, 60.0)))
    finally:
        _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 0, stderr
    assert [s.name for s in sessions] == ["locoplan two-quasi-static", "locoplan two-dynamic"]
    for s in sessions:
        assert s.messages["/tf"], s.name
        assert s.messages["/tf"][-1][0] > 0.5  # each run's own simulation time
    assert (tmp_path / "cmp" / "two-dynamic.mcap").exists()


def test_live_port_in_use_is_bad_input(tmp_path: Path) -> None:
    (tmp_path / "stand.yaml").write_text(_stand("busy", 1.0))
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        res = subprocess.run(
            [*LOCOPLAN, "run", "stand.yaml", "--live", "--port", str(port), "--quiet"],
            cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False,
        )  # fmt: skip
    assert res.returncode == 2, res.stderr
    assert "--live: cannot serve on 127.0.0.1" in res.stderr
    assert "Traceback" not in res.stderr


@pytest.mark.parametrize("flag", ["--pace", "--wait"])
def test_live_options_need_live(tmp_path: Path, flag: str) -> None:
    (tmp_path / "stand.yaml").write_text(_stand("nolive", 1.0))
    res = subprocess.run(
        [*LOCOPLAN, "run", "stand.yaml", flag, "1"],
        cwd=tmp_path, capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert res.returncode == 2 and f"{flag} applies with --live only" in res.stderr


def test_live_run_without_a_client_starts_after_wait(tmp_path: Path) -> None:
    """Nobody connects: the run starts after --wait s and completes; the MCAP is whole."""
    (tmp_path / "stand.yaml").write_text(_stand("alone", 0.5))
    start = time.monotonic()
    res = subprocess.run(
        [*LOCOPLAN, "run", "stand.yaml", "--live", "--port", "0", "--wait", "1.5", "--pace", "0",
         "--quiet", "--out", "runs"],
        cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert time.monotonic() - start > 1.5
    assert "at most 1.5 s" in res.stderr
    assert (tmp_path / "runs" / "alone.mcap").stat().st_size > 0


def test_wait_for_subscriber_sees_a_subscription(tmp_path: Path) -> None:
    """The writer's own wait: False after the timeout with no client; True once a client
    subscribes to /tf, which exists before the first tick."""
    from locoplan.log.writer import RunLogWriter

    async def subscribe(port: int) -> None:
        async with await websockets.connect(
            f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS
        ) as ws:
            while True:
                op = json.loads(await asyncio.wait_for(ws.recv(), 5.0))
                if op["op"] == "advertise":
                    ids = [c["id"] for c in op["channels"] if c["topic"] == "/tf"]
                    if ids:
                        sub = {"op": "subscribe", "subscriptions": [{"id": 1, "channelId": ids[0]}]}
                        await ws.send(json.dumps(sub))
                        await asyncio.sleep(0.3)
                        return

    with RunLogWriter(tmp_path / "w.mcap", scenario_name="w", scenario_text="") as writer:
        port = writer.serve(0)
        t0 = time.monotonic()
        assert not writer.wait_for_subscriber(0.3)
        assert time.monotonic() - t0 >= 0.3
        asyncio.run(subscribe(port))
        assert writer.wait_for_subscriber(2.0)


def test_pacer_keeps_pace_and_publishes() -> None:
    from locoplan.sim.live import Pacer

    published: list[float] = []

    class FakeWriter:
        def publish(self, t: float) -> None:
            published.append(t)

    pacer = Pacer(FakeWriter(), 4.0)  # type: ignore[arg-type]
    start = time.perf_counter()
    for k in range(41):
        pacer(k * 0.01)  # 0.4 s simulated at 4x: 0.1 s of wall time
    elapsed = time.perf_counter() - start
    assert len(published) == 41
    assert 0.095 < elapsed < 0.2
    with pytest.raises(ValueError):
        Pacer(FakeWriter(), -1.0)  # type: ignore[arg-type]
