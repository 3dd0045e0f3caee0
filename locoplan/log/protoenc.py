"""Protobuf wire encoding of the Foxglove messages a run writes over and over.

The SDK's typed channels want a Python message object per message, and building those (20
`FrameTransform`s with their `Vector3`, `Quaternion` and `Timestamp` every 10 ms, 70 scene
entities every 33 ms) costs far more than the encoding itself. The messages a run repeats keep
their layout: only the timestamp and the numbers change. So each is laid out once as a byte
template and filled per message (the numbers scattered in as little-endian doubles), and
`RunLogWriter` logs the bytes on a channel with the same Foxglove schema (same schema record,
same decoded messages, as the tests check against the SDK's own encoding).

Wire format (https://protobuf.dev/programming-guides/encoding/): a field is a varint tag
``number << 3 | wire_type`` followed by a varint (type 0), 8 bytes (type 1, double) or a
varint length and that many bytes (type 2: strings, sub-messages, repeated sub-messages one
field each). Zero numbers are written rather than omitted (decoders read them the same).
Field numbers are those of the Foxglove schemas (foxglove/*.proto):

- Timestamp: seconds 1, nanos 2;
- FrameTransforms: transforms 1; FrameTransform: timestamp 1, parent_frame_id 2,
  child_frame_id 3, translation 4 (Vector3: x 1, y 2, z 3), rotation 5 (Quaternion: x 1,
  y 2, z 3, w 4);
- JointStates: timestamp 1, joints 2; JointState: name 1, position 2, velocity 3, effort 5;
- SceneUpdate: deletions 1, entities 2; SceneEntityDeletion: timestamp 1, type 2 (ALL = 1);
  SceneEntity: timestamp 1, then the rest as the SDK encodes it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from numba import njit

FloatArray = npt.NDArray[np.floating]

_LEN = 2  # wire type of length-delimited fields
_I64 = 1  # wire type of doubles
_DELETE_ALL = 1  # foxglove.SceneEntityDeletion.Type.ALL


def varint(value: int) -> bytes:
    """Base-128 varint of `value` (>= 0)."""
    out = bytearray()
    while value >= 0x80:
        out.append((value & 0x7F) | 0x80)
        value >>= 7
    out.append(value)
    return bytes(out)


def tag(number: int, wire_type: int) -> bytes:
    """The key of field `number`."""
    return varint(number << 3 | wire_type)


def length_field(number: int, payload: bytes) -> bytes:
    """Field `number` holding `payload` (a string or an encoded sub-message)."""
    return tag(number, _LEN) + varint(len(payload)) + payload


def timestamp(ns: int) -> bytes:
    """An encoded google.protobuf.Timestamp of `ns` (>= 0) nanoseconds."""
    seconds, nanos = divmod(ns, 1_000_000_000)
    out = b""
    if seconds:
        out += b"\x08" + varint(seconds)
    if nanos:
        out += b"\x10" + varint(nanos)
    return out


@njit(
    "uint8[::1](uint8[::1], uint8[::1], int64[::1], int64[:, ::1],"
    " float64[:, ::1], float64[:, ::1], float64[:, ::1])",
    cache=True,
)
def _fill(
    template: npt.NDArray[np.uint8],
    ts: npt.NDArray[np.uint8],
    ts_at: npt.NDArray[np.int64],
    doubles_at: npt.NDArray[np.int64],
    a: npt.NDArray[np.float64],
    b: npt.NDArray[np.float64],
    c: npt.NDArray[np.float64],
) -> npt.NDArray[np.uint8]:
    """A copy of `template` with `ts` written at each offset of `ts_at`, and row i of the
    doubles (a[i], then b[i], then c[i]) as little-endian bytes at offsets `doubles_at[i]`."""
    out = template.copy()
    for start in ts_at:
        for j in range(ts.size):
            out[start + j] = ts[j]
    one = np.empty(1, dtype=np.float64)
    one_bytes = one.view(np.uint8)
    for i in range(doubles_at.shape[0]):
        k = 0
        for arr in (a, b, c):
            for j in range(arr.shape[1]):
                one[0] = arr[i, j]
                start = doubles_at[i, k]
                for byte in range(8):
                    out[start + byte] = one_bytes[byte]
                k += 1
    return out


_ROW = -1  # starts a row of doubles in a template's parts
_NO_BYTES = np.zeros(0, dtype=np.uint8)
_EMPTY_ROWS = np.zeros((1 << 16, 0))  # (n, 0) slices: no third group of doubles


class _Template:
    """A message laid out once: the bytes, where the timestamps go and where each row's
    doubles go.

    Built from parts: bytes (copied), None (the timestamp, the same in every place), `_ROW`
    (starts a row of doubles) or an int k > 0 (k doubles of the current row).
    """

    def __init__(self, parts: Sequence[bytes | int | None], ts_len: int) -> None:
        buf = bytearray()
        ts_at: list[int] = []
        rows: list[list[int]] = []
        for part in parts:
            if part is None:
                ts_at.append(len(buf))
                buf += bytes(ts_len)
            elif part == _ROW:
                rows.append([])
            elif isinstance(part, int):
                rows[-1].extend(range(len(buf), len(buf) + 8 * part, 8))
                buf += bytes(8 * part)
            else:
                buf += part
        self.buf = np.frombuffer(bytes(buf), dtype=np.uint8).copy()
        self.ts_at = np.asarray(ts_at, dtype=np.int64)
        self.doubles_at = np.asarray(rows, dtype=np.int64).reshape(len(rows), -1)

    def fill(
        self,
        ts: bytes,
        a: npt.NDArray[np.float64],
        b: npt.NDArray[np.float64],
        c: npt.NDArray[np.float64],
    ) -> bytes:
        """The message with timestamp `ts` and the rows of `a`, `b`, `c` ((n, k) each, C order,
        float64; together as many columns as a row has doubles)."""
        ts_arr = np.frombuffer(ts, dtype=np.uint8).copy() if ts else _NO_BYTES
        return _fill(self.buf, ts_arr, self.ts_at, self.doubles_at, a, b, c).tobytes()


def _rows(values: FloatArray, n: int, k: int) -> npt.NDArray[np.float64]:
    """`values` as a C-ordered float64 (n, k) array (a view when it already is one)."""
    return np.ascontiguousarray(values, dtype=np.float64).reshape(n, k)


class FrameTransformsEncoder:
    """foxglove.FrameTransforms of a fixed list of (parent, child) frame pairs."""

    def __init__(self, parent_frames: Sequence[str], child_frames: Sequence[str]) -> None:
        if len(parent_frames) != len(child_frames):
            raise ValueError("one parent frame per child frame")
        self.n = len(child_frames)
        self._names = [
            length_field(2, p.encode()) + length_field(3, c.encode())
            for p, c in zip(parent_frames, child_frames, strict=True)
        ]
        self._templates: dict[int, _Template] = {}

    def _template(self, ts_len: int) -> _Template:
        template = self._templates.get(ts_len)
        if template is None:
            ts_field = tag(1, _LEN) + varint(ts_len)
            translation = tag(4, _LEN) + varint(3 * 9)
            rotation = tag(5, _LEN) + varint(4 * 9)
            parts: list[bytes | int | None] = []
            for names in self._names:
                size = len(ts_field) + ts_len + len(names) + len(translation) + 27
                size += len(rotation) + 36
                parts += [tag(1, _LEN) + varint(size), ts_field, None, names, _ROW, translation]
                for k in range(3):
                    parts += [tag(k + 1, _I64), 1]
                parts.append(rotation)
                for k in range(4):
                    parts += [tag(k + 1, _I64), 1]
            template = self._templates[ts_len] = _Template(parts, ts_len)
        return template

    def encode(self, ns: int, translations: FloatArray, rotations_xyzw: FloatArray) -> bytes:
        """The message at `ns`: `translations` (n, 3) m, `rotations_xyzw` (n, 4)."""
        ts = timestamp(ns)
        n = self.n
        return self._template(len(ts)).fill(
            ts, _rows(translations, n, 3), _rows(rotations_xyzw, n, 4), _EMPTY_ROWS[:n]
        )


class JointStatesEncoder:
    """foxglove.JointStates of a fixed list of joints, each with position, velocity, effort."""

    def __init__(self, names: Sequence[str]) -> None:
        self.n = len(names)
        parts: list[bytes | int | None] = []
        for name in names:
            name_field = length_field(1, name.encode())
            parts += [_ROW, tag(2, _LEN) + varint(len(name_field) + 27), name_field]
            for number in (2, 3, 5):  # position, velocity, effort
                parts += [tag(number, _I64), 1]
        self._body = _Template(parts, 0)

    def encode(
        self, ns: int, position: FloatArray, velocity: FloatArray, effort: FloatArray
    ) -> bytes:
        """The message at `ns`: joint positions (rad), velocities (rad/s), efforts (N m), (n,)."""
        n = self.n
        body = self._body.fill(
            b"", _rows(position, n, 1), _rows(velocity, n, 1), _rows(effort, n, 1)
        )
        return length_field(1, timestamp(ns)) + body


class SceneUpdateEncoder:
    """foxglove.SceneUpdate messages of a fixed list of entities, each given as its encoding
    without timestamp (the SDK's ``SceneEntity(...).encode()``), stamped per message.

    Entity i is ``field-2 header_i + timestamp field + body_i``, and the header's length
    prefix depends only on the timestamp's length; so for each timestamp length the message
    is one ``bytes.join`` of constant pieces with the timestamp field as separator.
    """

    def __init__(self, entity_bodies: Sequence[bytes]) -> None:
        self.bodies = tuple(entity_bodies)
        self._pieces: dict[int, list[bytes]] = {}

    def _pieces_for(self, ts_field_len: int) -> list[bytes]:
        pieces = self._pieces.get(ts_field_len)
        if pieces is None:
            heads = [b"\x12" + varint(ts_field_len + len(body)) for body in self.bodies]
            # header 0 | body 0 + header 1 | ... | body n-2 + header n-1 | body n-1
            pieces = [heads[0]]
            pieces += [body + head for body, head in zip(self.bodies, heads[1:], strict=False)]
            pieces.append(self.bodies[-1])
            self._pieces[ts_field_len] = pieces
        return pieces

    def encode(self, ns: int, *, delete_all: bool) -> bytes:
        """The update at `ns`: first (with `delete_all`) a deletion of every entity on the
        topic, then the entities."""
        ts_field = length_field(1, timestamp(ns))
        head = length_field(1, ts_field + b"\x10" + varint(_DELETE_ALL)) if delete_all else b""
        if not self.bodies:
            return head
        return head + ts_field.join(self._pieces_for(len(ts_field)))


def scene_update(ns: int, entity_bodies: Sequence[bytes], *, delete_all: bool) -> bytes:
    """foxglove.SceneUpdate at `ns` of entities given as their encodings without timestamp
    (see `SceneUpdateEncoder`; this builds one for a single message)."""
    return SceneUpdateEncoder(entity_bodies).encode(ns, delete_all=delete_all)
