"""Tests of locoplan.log.writer: write a log with every method and read it back.

Values are compared exactly where they pass through protobuf doubles or JSON floats unchanged
(both round-trip an IEEE double exactly); log times are compared in integer nanoseconds.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from locoplan import __version__
from locoplan.log import (
    RunLogWriter,
    Transform,
    box,
    force_arrow,
    line_strip,
    read_log,
    sphere,
)
from locoplan.log.scene import RED, prepare_scene

SCENARIO = "name: demo\ntasks:\n  - pick: {object: package}\n"
JOINTS = ["L_hip", "L_knee", "R_hip", "R_knee"]


def _write_full_log(path: Path) -> None:
    with RunLogWriter(
        path, scenario_name="demo", scenario_text=SCENARIO, metadata={"strategy": "dynamic"}
    ) as w:
        w.joint_limits(JOINTS, np.array([30.0, 40.0, 30.0, 40.0]), [-1.0] * 4, [1.0] * 4)
        for k in range(10):
            t = 0.01 * k
            w.frame_transforms(
                t,
                [
                    Transform("world", "base", np.array([0.0, 0.0, 0.5 + k]), [0, 0, 0, 1.0]),
                    Transform("base", "L_foot", [0.1, 0.05, -0.5], [0.0, 0.0, 0.6, 0.8]),
                ],
            )
            w.joint_states(t, JOINTS, np.arange(4.0) + k, np.ones(4), np.full(4, -2.5))
            w.json(
                "/mpc/plan",
                t,
                {
                    "forces_world": np.arange(6.0).reshape(2, 3) * k,
                    "solve_ms": 1.25,
                    "status": "solved",
                    "ok": True,
                    "count": np.int64(k),
                    "bad": math.nan,
                    "stance": [True, False],
                    "nested": {"yaw": np.float32(0.5)},
                },
            )
            w.scene(
                "/scene/contacts",
                t,
                [
                    force_arrow("f_L", [0.1, 0.0, 0.0], [0.0, 0.0, 100.0], scale_m_per_N=0.01),
                    box("package", [0.5, 0.0, 0.6], [0.2, 0.3, 0.4], color=RED),
                    sphere("com", [0.0, 0.0, 0.55], 0.05),
                    line_strip("path", [[0, 0, 0], [1, 0, 0], [1, 1, 0]]),
                ],
            )
        w.frame_transforms_arrays(
            0.1, "world", ["base", "torso"], np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]),
            np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 0.0]]),
        )  # fmt: skip
        w.event(0.05, "grasp", object="package", hand="left")
        w.finish(
            {
                "scenario": "demo",
                "completed": True,
                "sim_time": 0.09,
                "peak_torque": {"L_knee": 27.1},
                "yaw_difference_deg": None,
                "peak": np.float64(0.81),
            }
        )


@pytest.fixture(scope="module")
def full_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("log") / "demo.mcap"
    _write_full_log(path)
    return path


def test_metadata_and_attachments_round_trip(full_log: Path) -> None:
    log = read_log(full_log)
    assert log.complete
    run = log.metadata["locoplan"]
    assert run["scenario"] == "demo"
    assert run["locoplan_version"] == __version__
    assert run["strategy"] == "dynamic"
    assert run["start_wall_time"].endswith("+00:00")
    assert log.scenario_text == SCENARIO
    assert log.scenario_name == "demo"
    assert log.metrics == {
        "scenario": "demo",
        "completed": True,
        "sim_time": 0.09,
        "peak_torque": {"L_knee": 27.1},
        "yaw_difference_deg": None,
        "peak": 0.81,
    }
    assert log.metadata["metrics"] == {
        "scenario": "demo",
        "completed": "true",
        "sim_time": "0.09",
        "peak_torque": '{"L_knee":27.1}',
        "yaw_difference_deg": "null",
        "peak": "0.81",
    }
    assert log.metadata["run_end"]["status"] == "finished"
    assert log.metadata["run_end"]["message_count"] == str(1 + 10 * 4 + 1 + 1)


def test_topics_counts_and_times(full_log: Path) -> None:
    log = read_log(full_log)
    counts = {name: info.message_count for name, info in log.topics.items()}
    assert counts == {
        "/robot/joint_limits": 1,
        "/tf": 11,
        "/joint_states": 10,
        "/mpc/plan": 10,
        "/scene/contacts": 10,
        "/events": 1,
    }
    schemas = {name: info.schema_name for name, info in log.topics.items()}
    assert schemas["/tf"] == "foxglove.FrameTransforms"
    assert schemas["/joint_states"] == "foxglove.JointStates"
    assert schemas["/scene/contacts"] == "foxglove.SceneUpdate"
    assert schemas["/mpc/plan"] == "locoplan.mpc.plan"
    assert schemas["/events"] == "locoplan.event"
    assert log.start_time == 0.0  # joint limits are logged at t = 0
    assert log.end_time == 0.1


def test_transforms_round_trip(full_log: Path) -> None:
    msgs = list(read_log(full_log).messages("/tf"))
    assert [round(t * 1e9) for t, _ in msgs] == [round(k * 0.01 * 1e9) for k in range(11)]
    t3, m3 = msgs[3]
    base, foot = m3.transforms
    assert (base.parent_frame_id, base.child_frame_id) == ("world", "base")
    assert (base.translation.x, base.translation.y, base.translation.z) == (0.0, 0.0, 3.5)
    assert (base.rotation.x, base.rotation.y, base.rotation.z, base.rotation.w) == (0, 0, 0, 1)
    assert (foot.rotation.z, foot.rotation.w) == (0.6, 0.8)
    # The header stamp equals the log time, so Foxglove animates by either.
    assert base.timestamp.seconds * 10**9 + base.timestamp.nanos == round(t3 * 1e9)
    _, last = msgs[-1]
    torso = last.transforms[1]
    assert torso.child_frame_id == "torso"
    assert (torso.translation.x, torso.translation.z, torso.rotation.y) == (4.0, 6.0, 1.0)


def test_joint_states_and_limits_round_trip(full_log: Path) -> None:
    log = read_log(full_log)
    msgs = list(log.messages("/joint_states"))
    _, m5 = msgs[5]
    assert [j.name for j in m5.joints] == JOINTS
    assert [j.position for j in m5.joints] == [5.0, 6.0, 7.0, 8.0]
    assert [j.velocity for j in m5.joints] == [1.0] * 4
    assert [j.effort for j in m5.joints] == [-2.5] * 4
    ((t, limits),) = list(log.messages("/robot/joint_limits"))
    assert t == 0.0
    assert limits == {
        "names": JOINTS,
        "torque_limit": [30.0, 40.0, 30.0, 40.0],
        "q_lower": [-1.0] * 4,
        "q_upper": [1.0] * 4,
    }


def test_json_round_trip_and_schema(full_log: Path) -> None:
    msgs = list(read_log(full_log).messages("/mpc/plan"))
    t, m = msgs[2]
    assert t == 0.02
    assert m == {
        "forces_world": [[0.0, 2.0, 4.0], [6.0, 8.0, 10.0]],
        "solve_ms": 1.25,
        "status": "solved",
        "ok": True,
        "count": 2,
        "bad": None,  # NaN is written as null (strict JSON)
        "stance": [True, False],
        "nested": {"yaw": 0.5},
    }
    with open(full_log, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    (schema,) = [s for s in summary.schemas.values() if s.name == "locoplan.mpc.plan"]
    assert schema.encoding == "jsonschema"
    props = json.loads(schema.data)["properties"]
    assert props["forces_world"] == {
        "type": "array",
        "items": {"type": "array", "items": {"type": "number"}},
    }
    assert props["status"] == {"type": "string"}
    assert props["ok"] == {"type": "boolean"}
    assert props["nested"]["properties"]["yaw"] == {"type": "number"}


def test_events_and_scene_round_trip(full_log: Path) -> None:
    log = read_log(full_log)
    ((t, event),) = list(log.messages("/events"))
    assert t == 0.05
    assert event == {"kind": "grasp", "object": "package", "hand": "left"}
    _, update = next(iter(log.messages("/scene/contacts")))
    assert [d.type for d in update.deletions] == [1]  # ALL: the update replaces the scene
    arrow_entity, box_entity, sphere_entity, line_entity = update.entities
    arrow = arrow_entity.arrows[0]
    assert arrow_entity.id == "f_L" and arrow_entity.frame_id == "world"
    # 100 N at 0.01 m/N is 1 m long; the head takes a quarter of it.
    assert arrow.shaft_length + arrow.head_length == pytest.approx(1.0, abs=1e-15)
    assert arrow.pose.position.x == 0.1
    cube = box_entity.cubes[0]
    assert (cube.size.x, cube.size.y, cube.size.z) == (0.2, 0.3, 0.4)
    assert (cube.color.r, cube.color.a) == (RED.r, 1.0)
    assert sphere_entity.spheres[0].size.x == 0.05
    assert [(p.x, p.y) for p in line_entity.lines[0].points] == [(0, 0), (1, 0), (1, 1)]


def test_mcap_reader_summary_lists_every_channel(full_log: Path) -> None:
    with open(full_log, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None
        assert summary.statistics is not None
        topics = {c.topic for c in summary.channels.values()}
        assert topics == {
            "/robot/joint_limits",
            "/tf",
            "/joint_states",
            "/mpc/plan",
            "/scene/contacts",
            "/events",
        }
        assert summary.statistics.message_count == 43
        assert {a.name for a in summary.attachment_indexes} == {"scenario.yaml", "metrics.json"}


def test_exception_in_with_block_leaves_closed_file_with_aborted_event(tmp_path: Path) -> None:
    path = tmp_path / "boom.mcap"
    with (
        pytest.raises(RuntimeError, match="solver exploded"),
        RunLogWriter(path, scenario_name="boom", scenario_text=SCENARIO) as w,
    ):
        w.joint_states(0.25, JOINTS, np.zeros(4), np.zeros(4), np.zeros(4))
        raise RuntimeError("solver exploded")
    assert w.closed
    with open(path, "rb") as f:
        assert make_reader(f).get_summary() is not None
    log = read_log(path)
    assert log.complete
    ((t, event),) = list(log.messages("/events"))
    assert t == 0.25  # stamped at the last simulation time written
    assert event == {"kind": "aborted", "exception": "RuntimeError", "message": "solver exploded"}
    assert log.metadata["run_end"]["status"] == "aborted"
    assert log.metrics is None


def test_close_is_idempotent_and_writes_after_close_fail(tmp_path: Path) -> None:
    w = RunLogWriter(tmp_path / "c.mcap", scenario_name="c", scenario_text="")
    w.close()
    w.close()
    assert w.closed
    with pytest.raises(ValueError, match="closed"):
        w.json("/x", 0.0, {"a": 1})
    with pytest.raises(ValueError, match="closed"):
        w.finish({})
    assert read_log(tmp_path / "c.mcap").metadata["run_end"]["status"] == "closed"


def test_bad_arguments_are_rejected(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="flush_interval_s"):
        RunLogWriter(tmp_path / "a.mcap", scenario_name="a", scenario_text="", flush_interval_s=0)
    with pytest.raises(ValueError, match="reserved"):
        RunLogWriter(
            tmp_path / "a.mcap", scenario_name="a", scenario_text="", metadata={"scenario": "b"}
        )
    with RunLogWriter(tmp_path / "a.mcap", scenario_name="a", scenario_text="") as w:
        w.json("/x", 0.0, {"a": 1.0})
        with pytest.raises(ValueError, match="already carries"):
            w.scene("/x", 0.0, [])
        with pytest.raises(ValueError, match=">= 0"):
            w.json("/x", -0.001, {"a": 1.0})
        with pytest.raises(ValueError, match="start with"):
            w.json("x", 0.0, {"a": 1.0})
        with pytest.raises(ValueError):
            w.joint_states(0.0, JOINTS, np.zeros(3))
        with pytest.raises(ValueError):
            w.frame_transforms_arrays(0.0, "world", ["a", "b"], np.zeros((3, 3)), np.zeros((2, 4)))
        with pytest.raises(TypeError):
            w.json("/y", 0.0, {"a": object()})
    with pytest.raises(FileExistsError):
        RunLogWriter(tmp_path / "a.mcap", scenario_name="a", scenario_text="", overwrite=False)


def test_json_decimals_rounds_float_arrays(tmp_path: Path) -> None:
    path = tmp_path / "d.mcap"
    with RunLogWriter(path, scenario_name="d", scenario_text="", json_decimals=3) as w:
        w.json("/x", 0.0, {"v": np.array([1.23456789, math.nan]), "s": 1.23456789})
    ((_, msg),) = list(read_log(path).messages("/x"))
    assert msg == {"v": [1.235, None], "s": 1.23456789}  # scalars are kept in full


def test_flush_interval_bounds_what_an_unclosed_file_holds(tmp_path: Path) -> None:
    """Copy the file while the writer is still open (what a SIGKILL would leave) and check
    that it holds the messages written up to about one flush interval earlier."""
    import shutil
    import time

    interval = 0.2
    path = tmp_path / "open.mcap"
    w = RunLogWriter(path, scenario_name="f", scenario_text="", flush_interval_s=interval)
    start = time.monotonic()
    k = 0
    while time.monotonic() - start < 0.7:
        w.json("/wall", k * 1e-3, {"wall": time.monotonic()})
        k += 1
        time.sleep(1e-4)
    copied_at = time.monotonic()
    shutil.copy(path, tmp_path / "copy.mcap")
    log = read_log(tmp_path / "copy.mcap")
    assert not log.complete
    last = max(m["wall"] for _, m in log.messages("/wall"))
    # Unflushed data is at most one interval old; 0.1 s more for a busy shared machine.
    assert copied_at - last < interval + 0.1
    w.close()


def test_two_open_writers_do_not_mix(tmp_path: Path) -> None:
    """Each writer has its own Foxglove context: a channel of one never reaches the other."""
    with (
        RunLogWriter(tmp_path / "a.mcap", scenario_name="a", scenario_text="") as a,
        RunLogWriter(tmp_path / "b.mcap", scenario_name="b", scenario_text="") as b,
    ):
        for k in range(5):
            a.json("/x", k * 0.1, {"who": "a"})
            b.json("/x", k * 0.1, {"who": "b"})
            b.joint_states(k * 0.1, JOINTS, np.zeros(4))
    log_a, log_b = read_log(tmp_path / "a.mcap"), read_log(tmp_path / "b.mcap")
    assert set(log_a.topics) == {"/x"}
    assert {m["who"] for _, m in log_a.messages("/x")} == {"a"}
    assert {m["who"] for _, m in log_b.messages("/x")} == {"b"}
    assert log_b.topics["/joint_states"].message_count == 5


def test_prepared_scene_and_partial_joint_states_round_trip(tmp_path: Path) -> None:
    """A `PreparedScene` reads back as the same items passed as a list (only re-stamped), and
    joint states without velocity or effort leave those fields unset."""
    items = [box("b", [0.5, 0.0, 0.6], [0.2, 0.3, 0.4], color=RED), sphere("s", [0, 0, 1], 0.1)]
    path = tmp_path / "p.mcap"
    with RunLogWriter(path, scenario_name="p", scenario_text="") as w:
        prepared = prepare_scene(items)
        for k in range(3):
            w.scene("/scene/a", k * 0.1, prepared)
            w.scene("/scene/b", k * 0.1, items)
        w.joint_states(0.0, JOINTS, np.arange(4.0))
    log = read_log(path)
    for (ta, a), (tb, b) in zip(log.messages("/scene/a"), log.messages("/scene/b"), strict=True):
        # Parsed from two channels (two message classes): compare canonical encodings.
        assert ta == tb
        assert a.SerializeToString(deterministic=True) == b.SerializeToString(deterministic=True)
        assert [e.timestamp.nanos for e in a.entities] == [round(ta * 1e9)] * 2
    ((_, js),) = list(log.messages("/joint_states"))
    assert [j.position for j in js.joints] == [0.0, 1.0, 2.0, 3.0]
    assert not any(j.HasField("velocity") or j.HasField("effort") for j in js.joints)


def test_messages_hold_the_values_of_the_call(tmp_path: Path) -> None:
    """Messages are encoded in batches, later than the call: arrays, lists and live buffers
    the caller changes afterwards (as MuJoCo changes qpos every step) must not leak in."""
    path = tmp_path / "m.mcap"
    buf = np.zeros(4)
    flags = [True, False]
    with RunLogWriter(path, scenario_name="m", scenario_text="", json_decimals=6) as w:
        for k in range(3):
            buf[:] = k
            flags[0] = k % 2 == 0
            w.json("/x", k * 0.1, {"v": buf, "flags": flags, "view": buf[1:3]})
            w.frame_transforms_arrays(k * 0.1, "world", ["a"], buf[None, 1:4], buf[None, :])
            w.joint_states(k * 0.1, JOINTS, buf, buf, buf)
        buf[:] = 99.0
    log = read_log(path)
    for k, (_, m) in enumerate(log.messages("/x")):
        assert m == {"v": [float(k)] * 4, "flags": [k % 2 == 0, False], "view": [float(k)] * 2}
    for k, (_, tf) in enumerate(log.messages("/tf")):
        assert tf.transforms[0].translation.z == float(k)
    for k, (_, js) in enumerate(log.messages("/joint_states")):
        assert [j.effort for j in js.joints] == [float(k)] * 4


def test_unsupported_values_raise_at_the_call(tmp_path: Path) -> None:
    """Queued encoding must not move an encoding error away from the call that caused it."""
    with RunLogWriter(tmp_path / "e.mcap", scenario_name="e", scenario_text="") as w:
        w.json("/x", 0.0, {"a": np.zeros(2)})
        for bad in (np.array([object()]), [object()], {"k": object()}, object()):
            with pytest.raises(TypeError):
                w.json("/x", 0.1, {"a": bad})
        w.json("/x", 0.2, {"a": np.ones(2)})
    assert [m["a"] for _, m in read_log(tmp_path / "e.mcap").messages("/x")] == [
        [0.0] * 2,
        [1.0] * 2,
    ]
