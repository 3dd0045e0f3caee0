"""`locoplan.render.samples`: which samples become frames, the /sim/qpos payload, task labels.
Pure Python, no simulation and no OpenGL."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from locoplan.log.jsonenc import make_json_encoder
from locoplan.plan import PlannedTask
from locoplan.render.camera import CameraSettings, TrackingCamera, yaw_of_quat_wxyz
from locoplan.render.samples import (
    FrameClock,
    RenderSample,
    TaskTimeline,
    frame_count,
    task_label,
    to_ns,
)
from locoplan.render.video import expected_frames


def _loop_sample_times(t_end: float) -> list[int]:
    """Sample times of a run: t = 0 before the first tick, then after every 10th 1 ms step
    (MuJoCo's time accumulates dt, so these are floats with rounding error, as in a run)."""
    times = [0]
    t = 0.0
    for i in range(round(t_end / 0.001)):
        t += 0.001
        if i % 10 == 0:
            times.append(to_ns(t))
    return times


def test_two_seconds_of_samples_make_sixty_frames() -> None:
    # The figure: 2 s at 30 fps. Frames at k / 30 s for k = 0..59; the last sample
    # (1.991 s) is after frame 59 (1.967 s) and before frame 60 (2.0 s).
    assert frame_count(_loop_sample_times(2.0), 30) == 60
    assert expected_frames(1.991) == 60


def test_each_frame_shows_the_first_sample_at_or_after_its_time() -> None:
    clock = FrameClock(30)
    times = _loop_sample_times(0.2)
    shown = [t for t in times for _ in range(clock.frames_for(t))]
    for k, t in enumerate(shown):
        frame_ns = k * 1_000_000_000 // 30
        assert t >= frame_ns
        # Samples are 10 ms apart: the shown one is less than 10 ms after the frame time.
        assert t - frame_ns < 10_000_000


def test_sparse_samples_fill_every_frame() -> None:
    # One sample every 0.1 s covers three frame times each; nothing is skipped.
    clock = FrameClock(30)
    counts = [clock.frames_for(to_ns(0.1 * i)) for i in range(11)]
    assert sum(counts) == 31  # frames 0..30, the last at exactly 1.0 s
    assert counts[0] == 1


def test_samples_out_of_order_are_refused() -> None:
    clock = FrameClock(30)
    clock.frames_for(to_ns(0.5))
    with pytest.raises(ValueError, match="out of time order"):
        clock.frames_for(to_ns(0.4))


def test_payload_round_trips_bit_for_bit_through_the_log_encoding() -> None:
    rng = np.random.default_rng(3)
    qpos = rng.normal(size=30)
    sample = RenderSample(1.234, qpos, (True, False), "pick box + turn -90 deg")
    encoded = make_json_encoder()(sample.to_payload())  # what RunLogWriter.json writes
    back = RenderSample.from_payload(1.234, json.loads(encoded))
    assert np.array_equal(back.qpos, qpos)  # exact: run --video and render must agree
    assert back.stance == (True, False)
    assert back.task == sample.task
    assert back.t_ns == sample.t_ns


@pytest.mark.parametrize(
    "payload",
    [
        {},
        {"qpos": "x"},
        {"qpos": [[1.0, 2.0]]},
        {"qpos": [1.0, None]},
        {"qpos": [1.0], "stance": 3},
    ],
)
def test_bad_payloads_raise_value_error(payload: dict[str, object]) -> None:
    with pytest.raises(ValueError):
        RenderSample.from_payload(0.0, payload)


def test_task_labels_and_overlaps() -> None:
    tasks = (
        PlannedTask(0, "pick", 0.5, 1.5, object="box", hands="both"),
        PlannedTask(1, "turn", 1.3, 2.9, angle=math.radians(-90.0)),
        PlannedTask(2, "walk", 3.0, 5.4, distance=(0.6, 0.0)),
        PlannedTask(3, "drop", 5.0, 6.0, object="box", onto="platform"),
    )
    assert [task_label(t) for t in tasks] == [
        "pick box",
        "turn -90 deg",
        "walk 0.60, 0.00 m",
        "drop box onto platform",
    ]
    timeline = TaskTimeline(
        tuple(t.start for t in tasks), tuple(t.end for t in tasks), tuple(map(task_label, tasks))
    )
    assert timeline.label_at(0.0) == "idle"
    assert timeline.label_at(1.4) == "pick box + turn -90 deg"
    assert timeline.label_at(1.5) == "turn -90 deg"  # intervals are [start, end)
    assert timeline.label_at(2.95) == "idle"
    assert timeline.label_at(5.2) == "walk 0.60, 0.00 m + drop box onto platform"


def test_camera_low_pass_converges_and_fixes_the_azimuth() -> None:
    settings = CameraSettings(time_constant=0.4, height_offset=0.0, azimuth_offset_deg=-45.0)
    cam = TrackingCamera(settings, fps=30)
    yaw90 = np.array([math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)])
    assert yaw_of_quat_wxyz(yaw90) == pytest.approx(math.pi / 2)
    first = cam.update([0.0, 0.0, 0.6], yaw90)
    assert np.allclose(first, [0.0, 0.0, 0.6])
    assert cam.azimuth_deg == pytest.approx(45.0)
    # A 1 m step of the trunk: after one time constant (12 frames at 30 fps) the look-at point
    # has covered 1 - 1/e of it (exact discretisation of the first-order filter).
    for _ in range(12):
        p = cam.update([1.0, 0.0, 0.6], np.array([1.0, 0.0, 0.0, 0.0]))
    assert p[0] == pytest.approx(1.0 - math.exp(-1.0), abs=1e-9)
    assert cam.azimuth_deg == pytest.approx(45.0)  # the view direction stays fixed


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(0, 20), st.integers(1, 8)).map(lambda p: (p[0] * 0.25, p[1] * 0.25)),
        max_size=6,
    ),
    st.lists(st.floats(-1.0, 8.0), min_size=1, max_size=20),
)
def test_label_lookup_equals_a_scan_of_all_tasks(
    intervals: list[tuple[float, float]], times: list[float]
) -> None:
    """The bisection over interval bounds gives the labels a scan of every task gives
    (touching and overlapping intervals, times on the bounds included)."""
    labels = tuple(f"task {i}" for i in range(len(intervals)))
    starts = tuple(s for s, _ in intervals)
    ends = tuple(s + d for s, d in intervals)
    timeline = TaskTimeline(starts, ends, labels)
    for t in [*times, *starts, *ends]:
        active = [lab for s, e, lab in zip(starts, ends, labels, strict=True) if s <= t < e]
        assert timeline.label_at(t) == (" + ".join(active) if active else "idle")
