"""Tests of locoplan.log.protoenc: the hand-laid protobuf messages decode to exactly what the
Foxglove SDK's own encoding of the same message decodes to.

Both sides are parsed with the message classes built from the SDK's schema (the descriptor
set a reader such as Foxglove or mcap-protobuf uses) and compared with protobuf equality, so
doubles must match bit for bit (no tolerance: both carry the same IEEE doubles).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import pytest
from foxglove import messages as fm
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from locoplan.log.protoenc import (
    FrameTransformsEncoder,
    JointStatesEncoder,
    SceneUpdateEncoder,
    length_field,
    timestamp,
    varint,
)
from locoplan.log.scene import (
    box,
    entity_body,
    force_arrow,
    line_strip,
    prepare_scene,
    sphere,
    to_scene_entity,
)

# Log times covering 1- to 5-byte varints of seconds and nanoseconds, and zero parts.
TIMES_NS = [0, 1, 999, 1_000_000_000, 5_432_100_000, 127_999_999_999, 12_345_678_901_234]


@functools.cache
def _message_class(message_type: Any) -> Any:
    schema = message_type.get_schema()
    pool = descriptor_pool.DescriptorPool()
    for file in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def _parse(message_type: Any, data: bytes) -> Any:
    msg = _message_class(message_type)()
    msg.ParseFromString(data)
    return msg


def _stamp(ns: int) -> fm.Timestamp:
    return fm.Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)


def test_varint_and_timestamp_wire_format() -> None:
    assert varint(0) == b"\x00"
    assert varint(1) == b"\x01"
    assert varint(300) == b"\xac\x02"  # the protobuf documentation's example
    assert length_field(2, b"ab") == b"\x12\x02ab"
    # An SDK deletion of type ALL at 3 s 5 ns: timestamp field 1 {08 03 10 05}, type 2 = 1.
    sdk = fm.SceneEntityDeletion(timestamp=fm.Timestamp(3, 5), type=fm.SceneEntityDeletionType.All)
    assert length_field(1, timestamp(3_000_000_005)) + b"\x10\x01" == sdk.encode()


@pytest.mark.parametrize("ns", TIMES_NS)
def test_frame_transforms_match_the_sdk(ns: int) -> None:
    rng = np.random.default_rng(ns % 1000)
    parents = ["world", "world", "trunk"]
    children = ["trunk", "box", "L_foot_with_a_long_name"]
    pos = rng.normal(size=(3, 3))
    pos[0, 1] = 0.0  # a zero the SDK omits and the template writes
    quat = rng.normal(size=(3, 4))
    quat[1] = [0.0, 0.0, 0.0, 1.0]
    encoder = FrameTransformsEncoder(parents, children)
    mine = encoder.encode(ns, pos, quat)
    sdk = fm.FrameTransforms(
        transforms=[
            fm.FrameTransform(
                timestamp=_stamp(ns),
                parent_frame_id=p,
                child_frame_id=c,
                translation=fm.Vector3(x=x, y=y, z=z),
                rotation=fm.Quaternion(x=qx, y=qy, z=qz, w=qw),
            )
            for p, c, (x, y, z), (qx, qy, qz, qw) in zip(
                parents, children, pos.tolist(), quat.tolist(), strict=True
            )
        ]
    ).encode()
    assert _parse(fm.FrameTransforms, mine) == _parse(fm.FrameTransforms, sdk)
    # Strided inputs (MuJoCo's xquat reordered) give the same message.
    assert encoder.encode(ns, np.asfortranarray(pos), quat[:, [0, 1, 2, 3]]) == mine


@pytest.mark.parametrize("ns", TIMES_NS)
def test_joint_states_match_the_sdk(ns: int) -> None:
    rng = np.random.default_rng(7)
    names = ["L_hip_yaw", "L_knee", "R_ankle"]
    q, v, tau = rng.normal(size=(3, 3))
    v[1] = 0.0
    tau[2] = np.nan  # NaN passes through as a double on both sides
    mine = JointStatesEncoder(names).encode(ns, q, v, tau)
    sdk = fm.JointStates(
        timestamp=_stamp(ns),
        joints=[
            fm.JointState(name=n, position=a, velocity=b, effort=c)
            for n, a, b, c in zip(names, q.tolist(), v.tolist(), tau.tolist(), strict=True)
        ],
    ).encode()
    a, b = _parse(fm.JointStates, mine), _parse(fm.JointStates, sdk)
    assert a.timestamp == b.timestamp
    assert [j.name for j in a.joints] == names
    for ja, jb in zip(a.joints, b.joints, strict=True):
        for field in ("position", "velocity", "effort"):
            assert ja.HasField(field) and jb.HasField(field)
            assert np.array_equal(getattr(ja, field), getattr(jb, field), equal_nan=True)


@pytest.mark.parametrize("ns", TIMES_NS)
@pytest.mark.parametrize("delete_all", [True, False])
def test_scene_updates_match_the_sdk(ns: int, delete_all: bool) -> None:
    items = [
        box("b", [0.1, 0.2, 0.3], [0.2, 0.1, 0.05], orientation=[0.0, 0.0, 0.6, 0.8]),
        sphere("s", [0.0, 0.0, 1.0], 0.1, frame_id="trunk"),
        force_arrow("f", [0.0, 0.0, 0.0], [10.0, 0.0, 80.0]),
        line_strip("l", [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.5]]),
    ]
    stamp = _stamp(ns)
    deletions = (
        [fm.SceneEntityDeletion(timestamp=stamp, type=fm.SceneEntityDeletionType.All)]
        if delete_all
        else None
    )
    sdk = fm.SceneUpdate(
        deletions=deletions, entities=[to_scene_entity(e, stamp) for e in items]
    ).encode()
    expected = _parse(fm.SceneUpdate, sdk)
    encoder = SceneUpdateEncoder([entity_body(e) for e in items])
    assert _parse(fm.SceneUpdate, encoder.encode(ns, delete_all=delete_all)) == expected
    # Prepared once, stamped twice (the cached pieces for this timestamp length are reused).
    prepared = prepare_scene(items)
    for _ in range(2):
        got = prepared.encoder.encode(ns, delete_all=delete_all)
        assert _parse(fm.SceneUpdate, got) == expected


def test_empty_scene_update_is_only_the_deletion() -> None:
    encoder = SceneUpdateEncoder([])
    msg = _parse(fm.SceneUpdate, encoder.encode(2_000_000_000, delete_all=True))
    assert len(msg.entities) == 0 and len(msg.deletions) == 1
    assert encoder.encode(2_000_000_000, delete_all=False) == b""
