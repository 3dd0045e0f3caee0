"""Live view of a run: its log's channels served to Foxglove while it goes, paced.

`run --live` starts foxglove-sdk's WebSocket server on the run's log writer
(`RunLogWriter.serve`) once the controller is built (its kernels compiled or loaded): the
topics that go to the MCAP file are served too, with the simulation time as the server's
time. The run then waits, at most `wait` s, for a client to subscribe to a topic, so the
viewer sees it from its first tick: Foxglove reconnects with a back-off of a second or more,
and `compare --live`'s second run, 1-5 s of wall time, would otherwise be over or half over
when it is back (in CI a test client that reconnected got no /tf message of a 1 s run).

The loop calls a `Pacer` after each recorded sample (every 10 ms simulated): it hands the
queued messages to the server at once and sleeps so that simulated time advances `pace` times
as fast as wall time (0: no sleeping). A run that falls behind its pace (a slow stretch, a
busy core) is not made to sprint to catch up.
Without a live view the loop has no pacer and nothing here runs.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from locoplan.log.writer import RunLogWriter

DEFAULT_PORT = 8765
# How long (s) a live run waits for a client to subscribe before it starts without one.
DEFAULT_WAIT_S = 30.0
# Behind the pace by more than this (s of wall time), the pacer starts afresh from now.
MAX_LAG_S = 0.25


@dataclass(frozen=True, slots=True)
class LiveView:
    """Serve the run on 127.0.0.1:`port` (0: any free port), paced to `pace` x real time,
    starting when a client subscribes or after `wait` s (0: at once)."""

    port: int = DEFAULT_PORT
    pace: float = 1.0
    wait: float = DEFAULT_WAIT_S
    host: str = "127.0.0.1"


def live_view_options(port: int, pace: float | None, wait: float | None) -> LiveView:
    """The live view of `--port`, `--pace` and `--wait` (None: their defaults)."""
    return LiveView(port, 1.0 if pace is None else pace, DEFAULT_WAIT_S if wait is None else wait)


class Pacer:
    """Publishes the writer's queued messages and keeps pace; call it with the simulation
    time (s) after each recorded sample."""

    def __init__(self, writer: RunLogWriter, pace: float) -> None:
        if not pace >= 0.0:
            raise ValueError(f"pace must be >= 0, got {pace}")
        self.writer = writer
        self.pace = pace
        self._anchor: tuple[float, float] | None = None  # (wall s, simulated s)

    def __call__(self, t: float) -> None:
        self.writer.publish(t)
        if self.pace == 0.0:
            return
        now = time.perf_counter()
        if self._anchor is None:
            self._anchor = (now, t)
            return
        wall0, t0 = self._anchor
        delay = wall0 + (t - t0) / self.pace - now
        if delay > 0.0:
            time.sleep(delay)
        elif delay < -MAX_LAG_S:
            self._anchor = (now, t)
