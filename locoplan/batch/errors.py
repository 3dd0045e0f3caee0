"""Errors of batch runs and sweeps. They carry data; `locoplan.cli` maps them to exit code 2."""

from __future__ import annotations

from locoplan.exceptions import LocoplanError


class BatchInputError(LocoplanError):
    """The command line names no usable task script: a path that does not exist, or no
    `*.yaml` / `*.yml` file under the paths given. `path` is the offending path, if one."""

    def __init__(self, message: str, path: str | None = None) -> None:
        self.path = path
        super().__init__(message)


class SweepSpecError(LocoplanError):
    """A `--set KEY=VALUES` option cannot be used: a malformed spec, a range with a zero step
    or too many points, or a key that does not exist in the script. `spec` is the option as
    given."""

    def __init__(self, spec: str, message: str) -> None:
        self.spec = spec
        super().__init__(f"--set {spec}: {message}")


class BackendUnavailable(LocoplanError):
    """An execution backend cannot be used here (Ray not installed, cluster unreachable).
    `backend` names it; `hint` says how to fix it."""

    def __init__(self, backend: str, message: str, hint: str = "") -> None:
        self.backend = backend
        self.hint = hint
        super().__init__(f"{message}; {hint}" if hint else message)
