"""SIGINT / SIGTERM handling: a signal sets a flag; long work checks it at safe points.

A Python signal handler runs between bytecodes of the main thread, which may be inside a call
into a numba-compiled kernel, a solver or the MCAP writer: raising there turned into
`SystemError: CPUDispatcher(...) returned a result with an exception set`. So, inside a
`deferring()` block (a simulation, a batch worker, a batch's parent), the handler only records
the signal; the simulation loop checks `STATE.signum` once per control tick and raises
`Interrupted` there, between ticks, where the log writer can close the file cleanly. Outside
such a block the handler raises `Interrupted` at once (nothing fragile runs there).

`Interrupted` is a `SystemExit` whose code is the shell's 128 + signal number (130 for SIGINT,
143 for SIGTERM): it unwinds `finally` blocks and context managers (the log is closed), a
process that lets it through exits with that status and prints no traceback, and handlers that
catch `(KeyboardInterrupt, SystemExit)` see it as an interruption.

Nothing here is installed by importing the module: `install()` does it (the CLI, once per
command; a batch or compare worker process, once). Without it, signals behave as Python's
defaults and the flag never rises, so library use and tests are unaffected.
"""

from __future__ import annotations

import contextlib
import os
import signal
from collections.abc import Callable, Iterator
from types import FrameType
from typing import Any

SIGNALS: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM)


class _State:
    """The process's interrupt state: `signum` is the first signal received (0: none);
    `deferring` counts the `deferring()` blocks entered."""

    __slots__ = ("announce", "deferring", "signum")

    def __init__(self) -> None:
        self.signum = 0
        self.deferring = 0
        self.announce = False


STATE = _State()


class Interrupted(SystemExit):
    """The process was asked to stop by signal `signum`; `code` is 128 + `signum`."""

    def __init__(self, signum: int) -> None:
        super().__init__(128 + signum)
        self.signum = signum

    @property
    def signal_name(self) -> str:
        """SIGINT, SIGTERM, ... (or "signal N")."""
        return signal_name(self.signum)

    def __str__(self) -> str:
        return f"interrupted by {self.signal_name}"

    def __reduce__(self) -> tuple[Any, tuple[int]]:
        # Crosses process boundaries (a compare worker's result): rebuild from the signal.
        return (Interrupted, (self.signum,))


def signal_name(signum: int) -> str:
    """SIGINT, SIGTERM, ... for a signal number (or "signal N")."""
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def exit_code(signum: int) -> int:
    """The exit status of a process stopped by `signum`: 128 + signum (130, 143)."""
    return 128 + signum


def _handler(signum: int, frame: FrameType | None) -> None:
    if not STATE.signum:
        STATE.signum = signum
    if not STATE.deferring:
        if STATE.announce:
            with contextlib.suppress(OSError):
                os.write(2, f"{Interrupted(STATE.signum)}\n".encode())
        raise Interrupted(STATE.signum)


def install(
    signals: tuple[signal.Signals, ...] = SIGNALS, announce: bool = False
) -> Callable[[], None]:
    """Handle `signals` (default SIGINT and SIGTERM) as described in the module docstring,
    with the flag cleared. With `announce`, an interruption outside `deferring()` blocks
    writes "interrupted by SIGTERM" to standard error (where it raises at once, no caller is
    there to say it). Returns a function that restores the previous handlers. Must be called
    from the main thread (ValueError otherwise: Python's rule)."""
    STATE.signum = 0
    STATE.announce = announce
    previous: dict[signal.Signals, Any] = {sig: signal.signal(sig, _handler) for sig in signals}

    def restore() -> None:
        for sig, handler in previous.items():
            signal.signal(sig, handler)

    return restore


def install_for_worker() -> None:
    """In a worker process that only runs simulations (a batch or compare worker): install
    the handlers with every signal deferred for the process's life, so a SIGTERM (a timeout,
    the parent stopping) or a SIGINT (Ctrl-C reaches the whole process group) stops the run
    at its next control tick and the process then exits with 128 + signal."""
    install()
    STATE.deferring += 1


@contextlib.contextmanager
def deferring() -> Iterator[None]:
    """Within the block, a signal only sets the flag (see `pending`, `check`); the block's
    code decides where to stop. Leaving it raises nothing: call `check()` after it when the
    caller should stop too. Blocks nest."""
    STATE.deferring += 1
    try:
        yield
    finally:
        STATE.deferring -= 1


def pending() -> int:
    """The signal received since `install()` (0: none)."""
    return STATE.signum


def check() -> None:
    """Raise `Interrupted` when a signal has been received."""
    if STATE.signum:
        raise Interrupted(STATE.signum)


def interruption(exc: BaseException) -> int | None:
    """The exit status when `exc` means the process was interrupted: an `Interrupted`, a
    KeyboardInterrupt (130), a SystemExit with status 130 or 143, or an exception caused by
    one of them (a compiled kernel that saw the interruption reports a SystemError caused by
    it). None otherwise."""
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        seen.add(id(current))
        if isinstance(current, Interrupted):
            return exit_code(current.signum)
        if isinstance(current, KeyboardInterrupt):
            return exit_code(signal.SIGINT)
        if isinstance(current, SystemExit) and current.code in (130, 143):
            return int(current.code)
        current = current.__cause__ or current.__context__
    return None
