"""`locoplan examples`: copy the example task scripts out of the package to start from."""

from __future__ import annotations

from pathlib import Path

import typer

from locoplan.cli.common import EXIT_BAD_INPUT, EXIT_OK, _fail, app, err, out


def examples_dir() -> Path:
    """The folder of the example task scripts: the one an installed package carries
    (`locoplan/_data/scenarios`, see setup.py), else the repository checkout's `scenarios/`."""
    import locoplan

    package = Path(locoplan.__file__).resolve().parent
    installed = package / "_data" / "scenarios"
    checkout = package.parent / "scenarios"
    if not installed.is_dir() and checkout.is_dir():
        return checkout
    return installed


def example_files() -> list[Path]:
    """The example task scripts, sorted by name."""
    folder = examples_dir()
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.suffix in (".yaml", ".yml") and p.is_file())


def _summary(path: Path, width: int = 76) -> str:
    """The first sentence of a script's `description`, cut to `width` characters."""
    from ruamel.yaml import YAML
    from ruamel.yaml.error import YAMLError

    try:
        data = YAML(typ="safe").load(path.read_text("utf-8"))
    except (OSError, YAMLError, UnicodeDecodeError):
        return ""
    text = data.get("description", "") if isinstance(data, dict) else ""
    if not isinstance(text, str):
        return ""
    text = " ".join(text.split())
    sentence = text.split(". ")[0].rstrip(".")
    return sentence if len(sentence) <= width else sentence[: width - 3].rstrip() + "..."


@app.command("examples")
def examples_command(
    directory: str | None = typer.Argument(
        None,
        metavar="DIR",
        help="Folder to copy the example task scripts into (created if missing).",
        show_default=False,
    ),
    force: bool = typer.Option(
        False, "--force", help="Overwrite scripts of the same name already in DIR."
    ),
    list_only: bool = typer.Option(
        False, "--list", help="Only list the examples, copy nothing (DIR not needed)."
    ),
) -> None:
    """Copy the example task scripts into DIR, to run and to start from.

    The examples are the paper's experiments (package-transfer,
    standing-load, model-comparison, pick-walk-drop, throw) and
    locomotion-only scripts (stand, step, walk-square, turn). They ship
    inside the package, so this works from any folder once locoplan is
    installed. Nothing is overwritten without --force: when DIR already
    holds a script of the same name, nothing is copied.

    Exit status 0, or 2 when DIR cannot be written or would be overwritten.

    Examples:

      locoplan examples my-scenarios

      locoplan run my-scenarios/stand.yaml

      locoplan examples --list
    """
    files = example_files()
    if not files:
        _fail(EXIT_BAD_INPUT, f"no example scripts found in {examples_dir()} (broken install?)")
    if list_only:
        for path in files:
            out.print(f"{path.name:<24} {_summary(path)}", markup=False, emoji=False)
        raise typer.Exit(EXIT_OK)
    if directory is None:
        _fail(EXIT_BAD_INPUT, "give the folder to copy the examples into: locoplan examples DIR")
    target = Path(directory)
    if target.exists() and not target.is_dir():
        _fail(EXIT_BAD_INPUT, f"{directory}: exists and is not a directory")
    clashes = [p.name for p in files if (target / p.name).exists()]
    if clashes and not force:
        _fail(
            EXIT_BAD_INPUT,
            f"{directory} already has {', '.join(clashes)}; nothing copied (--force overwrites)",
        )
    try:
        target.mkdir(parents=True, exist_ok=True)
        for path in files:
            (target / path.name).write_bytes(path.read_bytes())
    except OSError as exc:
        _fail(EXIT_BAD_INPUT, f"cannot write to {directory}: {exc.strerror or exc}")
    shown = [(target / p.name).as_posix() for p in files]
    width = max(len(s) for s in shown)
    for name, path in zip(shown, files, strict=True):
        out.print(f"{name:<{width}}  {_summary(path)}", markup=False, emoji=False)
    start = next((p for p in files if p.name == "stand.yaml"), files[0])
    first = (target / start.name).as_posix()
    err.print(
        f"copied {len(files)} example scripts to {directory}; try: locoplan run {first}",
        markup=False,
        emoji=False,
        highlight=False,
    )
