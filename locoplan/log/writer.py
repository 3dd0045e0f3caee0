"""`RunLogWriter`: one MCAP file per closed-loop run, written through the Foxglove SDK.

Layout of a file (topics in `locoplan.log.topics`):
- metadata ``locoplan`` (scenario name, locoplan version, start wall time, caller's keys) and
  attachment ``scenario.yaml``, both written when the writer opens;
- ``/tf`` (foxglove.FrameTransforms), ``/joint_states`` (foxglove.JointStates), scene topics
  (foxglove.SceneUpdate), ``/robot/joint_limits`` and any other topic as JSON with a JSON
  Schema inferred from its first payload, ``/events`` (JSON: kind + fields);
- metadata ``metrics`` and attachment ``metrics.json`` from `finish`, and metadata
  ``run_end`` (status, end wall time) when the file closes.

Every message's log time is the simulation time in nanoseconds (t = 0 at the start of the
run). On the first write after `flush_interval_s` of wall time since the last flush, the
writer finishes its chunk and hands it to the OS, so a process killed with SIGKILL leaves a
file that `locoplan.log.reader.read_log` reads up to at most that long before the last write
(measured: 0.5 s median, 0.95 s max over 8 kills at the 1 s default). A flush costs 0.2-1 ms
and does not measurably grow the file. Not thread-safe: one writer per thread.

Live view: `serve(port)` starts foxglove-sdk's WebSocket server on the writer's own
`foxglove.Context`, so every channel that goes to the MCAP file is also served to Foxglove
clients (Foxglove WebSocket protocol, loopback only), with the simulation time as the server's
time; `publish(t)` hands the queued messages to both sinks at once. Without `serve` nothing
changes.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import functools
import json
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

import foxglove
import numpy as np
import numpy.typing as npt
from foxglove import messages as fm
from foxglove.mcap import MCAPCompression, MCAPWriteOptions

from locoplan import __version__
from locoplan.log import topics
from locoplan.log.jsonenc import infer_schema, make_json_encoder, to_jsonable
from locoplan.log.protoenc import FrameTransformsEncoder, JointStatesEncoder, scene_update
from locoplan.log.scene import PreparedScene, SceneItem, entity_body
from locoplan.log.transform import Transform

FloatArray = npt.NDArray[np.floating]

# Chunks are compressed with zstd at level 1: 3.2 us of CPU per message of the closed loop
# instead of 5-7 us at the SDK's default level, and a slightly smaller file (3.30 MB instead of
# 3.48 MB for the same messages). The compressor keeps the SDK's default threading, which
# buffers a chunk until it is finished (compression_threads=0 would stream half-written chunks
# into the file, so a killed run's file would end in a chunk no reader can use).
ZSTD_LEVEL = 1

RESERVED_METADATA_KEYS = frozenset(
    {"scenario", "locoplan_version", "start_wall_time", "start_wall_time_ns"}
)

_FramePairs = tuple[tuple[str, ...], tuple[str, ...]]  # parent frames, child frames
# A queued message, encoded when the queue is drained: a function returning its bytes, or a
# JSON payload (a dict of copied values), encoded with the other queued payloads in one batch.
_Encode = Callable[[], bytes] | dict[str, Any]

# Queued messages are encoded in batches of this many (see `RunLogWriter._emit`).
PENDING_LIMIT = 256

# Values a JSON payload may hold to be queued unencoded (immutable, or copied when queued).
_SCALARS = frozenset({type(None), bool, int, float, str, np.float64, np.bool_, np.int64})

_EVENT_SCHEMA: dict[str, Any] = {
    "title": "locoplan.event",
    "type": "object",
    "properties": {"kind": {"type": "string"}},
    "required": ["kind"],
    "additionalProperties": True,
}


class RunLogWriter:
    """Writes one run's MCAP log. Use as a context manager; see the module docstring.

    `path` is created (with its parent directories) at construction; an existing file is
    replaced unless `overwrite` is False (then FileExistsError). `metadata` adds string
    key/values to the ``locoplan`` metadata record (keys may not shadow the reserved ones).
    `flush_interval_s` (> 0, wall-clock seconds) bounds what a SIGKILL can lose.
    `json_decimals` rounds float numpy arrays in JSON payloads to that many decimal places
    (None: full precision; 6 keeps micrometres and micronewtons and saves about a quarter of
    the encoding time and a fifth of the size of float-heavy payloads).
    """

    def __init__(
        self,
        path: str | Path,
        *,
        scenario_name: str,
        scenario_text: str,
        metadata: Mapping[str, str] | None = None,
        flush_interval_s: float = 1.0,
        json_decimals: int | None = None,
        overwrite: bool = True,
    ) -> None:
        if not flush_interval_s > 0.0:
            raise ValueError(f"flush_interval_s must be positive, got {flush_interval_s}")
        extra = dict(metadata or {})
        for key, value in extra.items():
            if key in RESERVED_METADATA_KEYS:
                raise ValueError(f"metadata key {key!r} is reserved by the log writer")
            if not isinstance(key, str) or not isinstance(value, str):
                raise TypeError(f"metadata must map str to str, got {key!r}: {value!r}")
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        # One context per file: channels of another writer (another run in the same process)
        # never reach this file.
        self._context = foxglove.Context()
        self._writer = foxglove.open_mcap(
            self.path,
            allow_overwrite=overwrite,
            context=self._context,
            writer_options=MCAPWriteOptions(
                compression=MCAPCompression.Zstd, compression_level=ZSTD_LEVEL
            ),
        )
        self._closed = False
        self._flush_interval_s = float(flush_interval_s)
        self._encode_json = make_json_encoder(json_decimals)
        self._flush_due = time.monotonic() + self._flush_interval_s
        self._pending: list[tuple[Any, int, bytes | _Encode]] = []
        self._last_ns = 0
        self._message_count = 0
        self._topic_kinds: dict[str, str] = {}
        self._json_channels: dict[str, foxglove.Channel] = {}
        # Foxglove-schema topics are written as bytes encoded here (`locoplan.log.protoenc`)
        # on channels with the SDK's schemas; the encoders are per-run constants.
        self._scene_channels: dict[str, foxglove.Channel] = {}
        self._tf_channel: foxglove.Channel | None = None
        self._tf_encoders: dict[_FramePairs, FrameTransformsEncoder] = {}
        self._joint_channel: foxglove.Channel | None = None
        self._joint_encoders: dict[tuple[str, ...], JointStatesEncoder] = {}
        self._server: Any = None  # foxglove.websocket.WebSocketServer, with `serve`
        self._subscribed = threading.Event()  # set by the server's thread on a subscribe

        start_ns = time.time_ns()
        record = {
            "scenario": scenario_name,
            "locoplan_version": __version__,
            "start_wall_time": _iso(start_ns),
            "start_wall_time_ns": str(start_ns),
            **extra,
        }
        self._writer.write_metadata(topics.METADATA_RUN, record)
        self._writer.attach(
            log_time=0,
            create_time=start_ns,
            name=topics.ATTACHMENT_SCENARIO,
            media_type="application/yaml",
            data=scenario_text.encode("utf-8"),
        )
        self._writer.flush()

    # -- context manager ---------------------------------------------------------------

    def __enter__(self) -> RunLogWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self._closed:
            return
        if exc_type is None:
            self._close("closed")
            return
        try:
            # Recording the abort must not mask the exception that caused it.
            with contextlib.suppress(Exception):
                self.event(
                    self._last_ns / 1e9, "aborted", exception=exc_type.__name__, message=str(exc)
                )
        finally:
            self._close("aborted")

    @property
    def closed(self) -> bool:
        """True once `close`, `finish` or the context exit has finished the file."""
        return self._closed

    @property
    def message_count(self) -> int:
        """Messages written so far (all topics)."""
        return self._message_count

    # -- messages ----------------------------------------------------------------------

    def frame_transforms(self, t: float, transforms: Sequence[Transform]) -> None:
        """Log link poses at simulation time `t` (s) on ``/tf`` as foxglove.FrameTransforms."""
        self.frame_transforms_arrays(
            t,
            [tr.parent_frame for tr in transforms],
            [tr.child_frame for tr in transforms],
            np.array([tr.translation for tr in transforms], dtype=float).reshape(-1, 3),
            np.array([tr.rotation for tr in transforms], dtype=float).reshape(-1, 4),
        )

    def frame_transforms_arrays(
        self,
        t: float,
        parent_frames: str | Sequence[str],
        child_frames: Sequence[str],
        translations: FloatArray,
        rotations_xyzw: FloatArray,
    ) -> None:
        """`frame_transforms` from arrays, without building `Transform` values (the closed
        loop's way: about 10 us for 20 links).

        Row i is the pose of `child_frames[i]` in `parent_frames[i]` (or in `parent_frames`
        when it is one string): `translations` (n, 3) in m, `rotations_xyzw` (n, 4) unit
        quaternions (x, y, z, w). From MuJoCo: ``d.xpos[ids]``, ``d.xquat[ids][:, [1, 2, 3, 0]]``.
        """
        n = len(child_frames)
        parents = (parent_frames,) * n if isinstance(parent_frames, str) else tuple(parent_frames)
        p = np.asarray(translations, dtype=float)
        r = np.asarray(rotations_xyzw, dtype=float)
        if p.shape != (n, 3) or r.shape != (n, 4) or len(parents) != n:
            raise ValueError(
                f"{n} child frames need {n} parents, translations (n, 3) and rotations (n, 4);"
                f" got {len(parents)}, {p.shape}, {r.shape}"
            )
        ns = self._log_time(t, topics.TF, "tf")
        key = (parents, tuple(child_frames))
        encoder = self._tf_encoders.get(key)
        if encoder is None:
            encoder = self._tf_encoders[key] = FrameTransformsEncoder(*key)
        # Copies: the caller may pass live buffers (MuJoCo's) that change before encoding.
        self._emit(
            self._tf_frames_channel(), ns, functools.partial(encoder.encode, ns, p.copy(), r.copy())
        )

    def joint_states(
        self,
        t: float,
        names: Sequence[str],
        position: FloatArray | Sequence[float],
        velocity: FloatArray | Sequence[float] | None = None,
        effort: FloatArray | Sequence[float] | None = None,
    ) -> None:
        """Log joint positions (rad), velocities (rad/s) and efforts (N m), each shape (n,),
        at `t` (s) on ``/joint_states`` as foxglove.JointStates. ValueError on length mismatch.
        """
        ns = self._log_time(t, topics.JOINT_STATES, "joint_states")
        n = len(names)
        if velocity is not None and effort is not None:
            # All three given (the closed loop's case): the encoded template.
            arrays = (
                _float_array(position, n, "position"),
                _float_array(velocity, n, "velocity"),
                _float_array(effort, n, "effort"),
            )
            key = tuple(names)
            encoder = self._joint_encoders.get(key)
            if encoder is None:
                encoder = self._joint_encoders[key] = JointStatesEncoder(key)
            self._emit(
                self._joint_states_channel(), ns, functools.partial(encoder.encode, ns, *arrays)
            )
            return
        q = _floats(position, n, "position")
        v = _floats(velocity, n, "velocity") if velocity is not None else [None] * n
        tau = _floats(effort, n, "effort") if effort is not None else [None] * n
        msg = fm.JointStates(
            timestamp=_timestamp(ns),
            joints=[
                fm.JointState(name=name, position=qi, velocity=vi, effort=ei)
                for name, qi, vi, ei in zip(names, q, v, tau, strict=True)
            ],
        )
        self._emit(self._joint_states_channel(), ns, msg.encode())

    def _tf_frames_channel(self) -> foxglove.Channel:
        if self._tf_channel is None:
            self._tf_channel = self._proto_channel(topics.TF, fm.FrameTransforms)
        return self._tf_channel

    def _joint_states_channel(self) -> foxglove.Channel:
        if self._joint_channel is None:
            self._joint_channel = self._proto_channel(topics.JOINT_STATES, fm.JointStates)
        return self._joint_channel

    def joint_limits(
        self,
        names: Sequence[str],
        torque_limits: FloatArray | Sequence[float],
        q_lower: FloatArray | Sequence[float],
        q_upper: FloatArray | Sequence[float],
    ) -> None:
        """Log the joints' torque limits (N m) and position limits (rad), each (n,), once, on
        ``/robot/joint_limits`` (JSON) at log time 0."""
        n = len(names)
        payload = {
            "names": list(names),
            "torque_limit": _floats(torque_limits, n, "torque_limits"),
            "q_lower": _floats(q_lower, n, "q_lower"),
            "q_upper": _floats(q_upper, n, "q_upper"),
        }
        self.json(topics.JOINT_LIMITS, 0.0, payload)

    def scene(
        self,
        topic: str,
        t: float,
        entities: Sequence[SceneItem] | PreparedScene,
        *,
        replace: bool = True,
    ) -> None:
        """Log scene items (see `locoplan.log.scene`) at `t` (s) on `topic` as a
        foxglove.SceneUpdate. With `replace` the update first deletes every entity earlier
        updates put on this topic (a contact that ended loses its arrow); without it, entities
        replace only those with the same id. Items re-published unchanged (only re-stamped)
        are best passed as one `PreparedScene` (`locoplan.log.scene.prepare_scene`)."""
        ns = self._log_time(t, topic, "scene")
        channel = self._scene_channels.get(topic)
        if channel is None:
            channel = self._proto_channel(topic, fm.SceneUpdate)
            self._scene_channels[topic] = channel
        if isinstance(entities, PreparedScene):
            message = functools.partial(entities.encoder.encode, ns, delete_all=replace)
        else:
            message = functools.partial(_scene_update, ns, tuple(entities), replace)
        self._emit(channel, ns, message)

    def json(self, topic: str, t: float, payload: Mapping[str, Any]) -> None:
        """Log `payload` at `t` (s) on `topic` as JSON.

        The channel is created on the first call for `topic`, with a JSON Schema inferred from
        that payload (`locoplan.log.jsonenc.infer_schema`) and named ``locoplan`` + the topic
        with dots (``/mpc/solve`` -> ``locoplan.mpc.solve``). numpy arrays become lists and
        non-finite floats null.
        """
        ns = self._log_time(t, topic, "json")
        channel = self._json_channels.get(topic)
        if channel is None:
            schema = infer_schema(payload, "locoplan" + topic.replace("/", "."))
            channel = self._new_json_channel(topic, schema)
        self._emit(channel, ns, self._json_message(payload))

    def event(self, t: float, kind: str, **fields: Any) -> None:
        """Log a discrete event (task started/finished, grasp, release, fall, solver
        fallback, aborted) at `t` (s) on ``/events``: ``{"kind": kind, **fields}``."""
        if not kind:
            raise ValueError("event kind must be a non-empty string")
        ns = self._log_time(t, topics.EVENTS, "json")
        channel = self._json_channels.get(topics.EVENTS)
        if channel is None:
            channel = self._new_json_channel(topics.EVENTS, _EVENT_SCHEMA)
        self._emit(channel, ns, self._encode_json({"kind": kind, **fields}))

    # -- live view -------------------------------------------------------------------

    def serve(self, port: int = 8765, host: str = "127.0.0.1", bind_wait_s: float = 2.0) -> int:
        """Serve this file's channels live over the Foxglove WebSocket protocol (foxglove-sdk's
        server on the writer's context) until the file closes; returns the port (0 picks a
        free one). Retries for `bind_wait_s` while the port is still held (a previous run's
        server closing); then OSError."""
        from foxglove.websocket import Capability, ServerListener

        subscribed = self._subscribed

        class _Listener(ServerListener):
            def on_subscribe(self, client: Any, channel: Any) -> None:
                subscribed.set()

        self._check_open()
        if self._server is not None:
            raise ValueError(f"RunLogWriter for {self.path} already serves on {self._server.port}")
        # The robot's topics exist before the first tick, so a client can subscribe to them
        # while the run waits for it (`wait_for_subscriber`); the rest appear as they log.
        self._tf_frames_channel()
        self._joint_states_channel()
        deadline = time.monotonic() + bind_wait_s
        while True:
            try:
                self._server = foxglove.start_server(
                    name=f"locoplan {self.path.stem}",
                    host=host,
                    port=port,
                    capabilities=[Capability.Time],
                    server_listener=_Listener(),
                    context=self._context,
                )
                break
            except RuntimeError as exc:
                if time.monotonic() >= deadline:
                    raise OSError(f"cannot serve on {host}:{port}: {exc}") from None
                time.sleep(0.05)
        self._server.broadcast_time(self._last_ns)
        return int(self._server.port)

    def wait_for_subscriber(self, timeout_s: float) -> bool:
        """Block until a client of `serve` has subscribed to a channel, at most `timeout_s`
        (s); True if one has. A live view starts its run on this, so a viewer that connects
        after the server is up (Foxglove reconnecting between `compare`'s two runs) sees the
        run from its first tick instead of a part of it, or none."""
        if self._server is None:
            raise ValueError(f"RunLogWriter for {self.path} is not serving")
        deadline = time.monotonic() + timeout_s
        while not self._subscribed.is_set():
            left = deadline - time.monotonic()
            if left <= 0.0:
                return False
            # Short slices: a signal handler (Ctrl-C) runs between them.
            self._subscribed.wait(min(left, 0.1))
        return True

    @property
    def serving(self) -> bool:
        """True while `serve` has a server running."""
        return self._server is not None

    def publish(self, t: float) -> None:
        """Hand the queued messages to the sinks now (the live view sees them without
        waiting for a batch) and broadcast `t` (s, simulation time) as the server's time."""
        self._check_open()
        self._drain()
        if self._server is not None:
            self._server.broadcast_time(max(0, round(t * 1e9)))

    # -- end of run --------------------------------------------------------------------

    def finish(self, metrics: Mapping[str, Any]) -> None:
        """Store the run's metrics and close the file.

        Writes metadata record ``metrics`` (each value a string: strings as they are, anything
        else as compact JSON) and attachment ``metrics.json`` (the whole object, indented).
        """
        self._check_open()
        self._drain()
        clean = to_jsonable(dict(metrics))
        record = {
            key: value if isinstance(value, str) else json.dumps(value, separators=(",", ":"))
            for key, value in clean.items()
        }
        self._writer.write_metadata(topics.METADATA_METRICS, record)
        self._writer.attach(
            log_time=self._last_ns,
            create_time=time.time_ns(),
            name=topics.ATTACHMENT_METRICS,
            media_type="application/json",
            data=json.dumps(clean, indent=2).encode("utf-8"),
        )
        self._close("finished")

    def flush(self) -> None:
        """Finish the current chunk and push it to the OS now (survives a SIGKILL)."""
        self._check_open()
        self._drain()
        self._writer.flush()
        self._flush_due = time.monotonic() + self._flush_interval_s

    def close(self) -> None:
        """Finish the file (summary, indexes, footer). Idempotent."""
        self._close("closed")

    # -- internals ---------------------------------------------------------------------

    def _close(self, status: str) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            try:
                self._drain()
            finally:
                end_ns = time.time_ns()
                self._writer.write_metadata(
                    topics.METADATA_RUN_END,
                    {
                        "status": status,
                        "end_wall_time": _iso(end_ns),
                        "end_wall_time_ns": str(end_ns),
                        "last_log_time_ns": str(self._last_ns),
                        "message_count": str(self._message_count),
                    },
                )
        finally:
            try:
                self._writer.close()
            finally:
                if self._server is not None:
                    server, self._server = self._server, None
                    server.stop()

    def _check_open(self) -> None:
        if self._closed:
            raise ValueError(f"RunLogWriter for {self.path} is closed")

    def _log_time(self, t: float, topic: str, kind: str) -> int:
        """Nanoseconds of `t`; checks the writer is open and `topic` keeps one kind."""
        if self._closed:
            raise ValueError(f"RunLogWriter for {self.path} is closed")
        known = self._topic_kinds.get(topic)
        if known is None:
            if not topic.startswith("/"):
                raise ValueError(f"topic {topic!r} must start with '/'")
            self._topic_kinds[topic] = kind
        elif known != kind:
            raise ValueError(f"topic {topic} already carries {known} messages, not {kind}")
        ns = round(t * 1e9)
        if ns < 0:
            raise ValueError(f"log time must be >= 0 s, got {t}")
        if ns > self._last_ns:
            self._last_ns = ns
        return ns

    def _emit(self, channel: foxglove.Channel, ns: int, message: bytes | _Encode) -> None:
        """Queue one message (bytes, a function encoding it from copies of its values, or a
        copied JSON payload).

        Messages are encoded and handed to the SDK in batches, in call order: every
        `PENDING_LIMIT` messages and before each flush, `finish` and close. Between control
        ticks the encoders' code and data are out of the CPU caches and each message costs
        about three times what it costs in a batch. The flush policy is unchanged: what a
        SIGKILL loses is what was written since the last flush, as before (the SDK keeps the
        unfinished chunk in memory too)."""
        self._pending.append((channel.base, ns, message))
        self._message_count += 1
        if len(self._pending) >= PENDING_LIMIT:
            self._drain()
        now = time.monotonic()
        if now >= self._flush_due:
            self._drain()
            self._writer.flush()
            self._flush_due = now + self._flush_interval_s

    def _drain(self) -> None:
        """Encode the queued messages and hand them to the SDK, in order (the JSON payloads
        first, all together: `JsonEncoder.many` prints their arrays in one compiled call)."""
        pending, self._pending = self._pending, []
        payloads = [message for _, _, message in pending if isinstance(message, dict)]
        texts = iter(self._encode_json.many(payloads))
        for base, ns, message in pending:
            if isinstance(message, dict):
                data = next(texts)
            elif isinstance(message, bytes):
                data = message
            else:
                data = message()
            base.log(data, ns)

    def _json_message(self, payload: Mapping[str, Any]) -> bytes | _Encode:
        """What `_emit` queues for a JSON payload: a copy, encoded when the queue is drained,
        when the payload holds only scalars, strings, numpy arrays and flat lists of scalars
        (what the closed loop writes); its bytes now otherwise (nested containers, objects: an
        unsupported value raises here, at the caller)."""
        copy: dict[str, Any] = {}
        for key, value in payload.items():
            kind = type(value)
            if kind is np.ndarray:
                if value.dtype.kind not in "biuf":
                    return self._encode_json(payload)  # raises TypeError here, not later
                value = value.copy()
            elif kind is list or kind is tuple:
                if not all(type(v) in _SCALARS for v in value):
                    return self._encode_json(payload)
                value = list(value)
            elif kind not in _SCALARS or type(key) is not str:
                return self._encode_json(payload)
            copy[key] = value
        return copy

    def _proto_channel(self, topic: str, message_type: Any) -> foxglove.Channel:
        """A channel for the protobuf encoding of a Foxglove message type (its schema record
        is the one the SDK's typed channel writes)."""
        return foxglove.Channel(
            topic,
            schema=message_type.get_schema(),
            message_encoding="protobuf",
            context=self._context,
        )

    def _new_json_channel(self, topic: str, schema: dict[str, Any]) -> foxglove.Channel:
        channel = foxglove.Channel(
            topic, schema=schema, message_encoding="json", context=self._context
        )
        self._json_channels[topic] = channel
        return channel


def _scene_update(ns: int, items: tuple[SceneItem, ...], replace: bool) -> bytes:
    return scene_update(ns, [entity_body(e) for e in items], delete_all=replace)


def _timestamp(ns: int) -> fm.Timestamp:
    return fm.Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)


def _iso(ns: int) -> str:
    return dt.datetime.fromtimestamp(ns / 1e9, tz=dt.UTC).isoformat(timespec="milliseconds")


def _float_array(values: FloatArray | Sequence[float], n: int, what: str) -> FloatArray:
    """`values` as a new float64 array of shape (n,) (a copy: the caller may pass live
    buffers); ValueError otherwise."""
    out = np.array(values, dtype=np.float64)
    if out.shape != (n,):
        raise ValueError(f"{what} needs shape ({n},), got {out.shape}")
    return out


def _floats(values: FloatArray | Sequence[float], n: int, what: str) -> list[float]:
    """`values` as a list of `n` floats (a numpy array is converted in one call)."""
    out = (
        values.tolist()
        if isinstance(values, np.ndarray) and values.dtype.kind == "f"
        else [float(v) for v in values]
    )
    if len(out) != n or (out and isinstance(out[0], list)):
        raise ValueError(f"{what} needs shape ({n},), got {np.shape(values)}")
    return out
