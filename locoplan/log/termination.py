"""Turn termination signals into `SystemExit` so `finally` blocks and `__exit__` run.

Python's default SIGTERM action kills the process without unwinding the stack, which would
leave an MCAP log without its summary and footer. With these handlers `RunLogWriter.__exit__`
records an "aborted" event and closes the file.
"""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterable
from types import FrameType
from typing import Any


def _raise_system_exit(signum: int, frame: FrameType | None) -> None:
    # 128 + signal number is the shell's convention for "killed by signal N".
    raise SystemExit(128 + signum)


def install_termination_handlers(
    signals: Iterable[signal.Signals] = (signal.SIGTERM,),
) -> Callable[[], None]:
    """Make each of `signals` (default SIGTERM) raise ``SystemExit(128 + signum)``.

    Returns a function that restores the previous handlers. Must be called from the main
    thread (Python's `signal.signal` rule); ValueError otherwise.
    """
    previous: dict[signal.Signals, Any] = {}
    for sig in signals:
        previous[sig] = signal.signal(sig, _raise_system_exit)

    def restore() -> None:
        for sig, handler in previous.items():
            signal.signal(sig, handler)

    return restore
