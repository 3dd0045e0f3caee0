"""Command-line interface. The only package that imports typer; commands stay thin.

`common` holds the typer `app`, the consoles, the exit codes and the helpers every
command shares; each other module holds one group of commands and registers them on
`app` when imported (imported below in the order `locoplan --help` lists them). Commands
import heavy modules (mujoco, pinocchio, numba kernels) inside their function, so that
`locoplan validate` stays fast.

Exit codes (shared/cli-contract.md): 0 ok, 1 expectation failed, 2 bad input,
3 the run broke (solver failure, simulator instability), 130 interrupted.
"""

from __future__ import annotations

import sys

# Importing a command module registers its commands on `app`; typer lists them in that
# order, so the order below is the one `locoplan --help` shows (kept out of isort's hands).
# isort: off
from locoplan.cli import scenario  # noqa: F401  (validate, schema)
from locoplan.cli import plan  # noqa: F401
from locoplan.cli import run  # noqa: F401
from locoplan.cli import batch  # noqa: F401  (batch, sweep)
from locoplan.cli import compare  # noqa: F401
from locoplan.cli import view  # noqa: F401  (render, inspect)
from locoplan.cli import examples  # noqa: F401

# isort: on
from locoplan.cli.common import (
    EXIT_BAD_INPUT,
    EXIT_EXPECTATION,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_RUN_BROKE,
    app,
    err,
    out,
)

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_EXPECTATION",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_RUN_BROKE",
    "app",
    "err",
    "main",
    "out",
]


def main() -> None:
    """Console-script entry point."""
    try:
        app()
    except KeyboardInterrupt:
        err.print("interrupted", markup=False)
        sys.exit(EXIT_INTERRUPTED)
    except Exception as exc:
        # Bugs end here: say what broke without a traceback unless --debug asked for one.
        if "--debug" in sys.argv:
            raise
        err.print(
            f"internal error: {type(exc).__name__}: {exc} (rerun with --debug for the traceback)",
            markup=False,
        )
        sys.exit(EXIT_RUN_BROKE)
