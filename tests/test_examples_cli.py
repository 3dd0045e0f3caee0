"""`locoplan examples DIR`: copies the packaged example scripts out (issue 13)."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from locoplan.cli import app
from locoplan.cli.examples import example_files, examples_dir

ROOT = Path(__file__).resolve().parents[1]


def _examples(*args: str):  # type: ignore[no-untyped-def]
    return CliRunner().invoke(app, ["examples", *args])


def test_examples_come_from_the_checkout_here() -> None:
    assert examples_dir() == ROOT / "scenarios"
    expected = sorted(p.name for p in ROOT.glob("scenarios/*.yaml"))
    assert [p.name for p in example_files()] == expected


def test_copies_every_example_and_they_validate(tmp_path: Path) -> None:
    target = tmp_path / "new" / "folder"
    res = _examples(str(target))
    assert res.exit_code == 0, res.output
    copied = sorted(p.name for p in target.iterdir())
    assert copied == [p.name for p in example_files()]
    for path in example_files():
        assert (target / path.name).read_bytes() == path.read_bytes()
    assert "stand.yaml" in res.output
    res = CliRunner().invoke(app, ["validate", *(str(p) for p in sorted(target.iterdir()))])
    assert res.exit_code == 0, res.output


def test_refuses_to_overwrite_without_force(tmp_path: Path) -> None:
    (tmp_path / "stand.yaml").write_text("mine\n")
    res = _examples(str(tmp_path))
    assert res.exit_code == 2
    assert "stand.yaml" in res.output and "--force" in res.output
    assert (tmp_path / "stand.yaml").read_text() == "mine\n"
    assert not (tmp_path / "turn.yaml").exists()  # nothing copied
    res = _examples(str(tmp_path), "--force")
    assert res.exit_code == 0, res.output
    assert (tmp_path / "stand.yaml").read_bytes() == (ROOT / "scenarios/stand.yaml").read_bytes()


def test_bad_targets_exit_2_without_traceback(tmp_path: Path) -> None:
    file = tmp_path / "a-file"
    file.write_text("")
    for args in ([str(file)], [], [str(file / "below")]):
        res = _examples(*args)
        assert res.exit_code == 2, (args, res.output)
        assert "Traceback" not in res.output


def test_list_names_each_example_with_its_description() -> None:
    res = _examples("--list")
    assert res.exit_code == 0
    lines = res.output.splitlines()
    assert len(lines) == len(example_files())
    assert any(line.startswith("stand.yaml") and "Stand still" in line for line in lines)
