"""Command-line interface. The only module that imports typer; commands stay thin.

Exit codes (shared/cli-contract.md): 0 ok, 1 expectation failed, 2 bad input,
3 the run broke (solver failure, simulator instability), 130 interrupted.
"""

from __future__ import annotations

import sys
from typing import NoReturn

import typer
from rich.console import Console

from locoplan import __version__

EXIT_OK = 0
EXIT_EXPECTATION = 1
EXIT_BAD_INPUT = 2
EXIT_RUN_BROKE = 3
EXIT_INTERRUPTED = 130

app = typer.Typer(
    name="locoplan",
    help=(
        "Plan and simulate humanoid loco-manipulation task scripts "
        "(multi-contact MPC + whole-body control in MuJoCo).\n\n"
        "Examples:\n\n"
        "  locoplan validate scenarios/*.yaml\n\n"
        "  locoplan plan scenarios/package-transfer.yaml --plot plan.png\n\n"
        "  locoplan run scenarios/package-transfer.yaml --metrics-json m.json"
    ),
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode="rich",
    pretty_exceptions_enable=False,
)

out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)


def _fail(code: int, message: str) -> NoReturn:
    err.print(message, markup=False)
    raise typer.Exit(code)


@app.callback(invoke_without_command=True)
def _root(
    version: bool = typer.Option(False, "--version", help="Print the version and exit."),
) -> None:
    if version:
        out.print(f"locoplan {__version__}")
        raise typer.Exit(EXIT_OK)


# --- validate / schema (scenario) -------------------------------------------------------------

# --- plan -----------------------------------------------------------------------------------

# --- run ------------------------------------------------------------------------------------


def main() -> None:
    """Console-script entry point."""
    try:
        app()
    except KeyboardInterrupt:
        err.print("interrupted", markup=False)
        sys.exit(EXIT_INTERRUPTED)
