"""`locoplan batch --backend ray` (issue 13, part 4): the same statuses, exit codes, JUnit test
cases and cache as the local backend on one passing, one failing and one malformed script; a
crashed or hung Ray task is that script's error; --fail-fast on Ray (a stand-in `ray` module:
the scheduling logic, no cluster); bad --backend / --address exit 2 before anything runs."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from locoplan.batch import Job, Outcome, ray_backend
from locoplan.batch.errors import BackendUnavailable
from locoplan.scenario import load_scenario_file
from locoplan.sim.run import RunOptions, run_scenario

LOCOPLAN = [sys.executable, "-m", "locoplan.cli"]

STAND = """version: 1
name: {name}
tasks:
  - {{action: stand, start: 0.0, duration: {t}}}
end: {t}
expect:
  no_fall: true
  max_torque_ratio: {limit}
"""
MALFORMED = """version: 1
name: malformed
tasks:
  - {action: jump, start: 0.0, duration: 1.0}
"""
# JUnit properties that are wall-time figures: they differ from run to run on any backend.
WALL_TIME = ("wall_time", "real_time_factor", "mpc_solve_ms", "wbc_solve_ms")


def _script(path: Path, name: str, t: float = 0.5, limit: float = 1.0) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(STAND.format(name=name, t=t, limit=limit))
    return path


def _suite(root: Path) -> Path:
    _script(root / "passing.yaml", "passing")
    # max_torque_ratio 0.001: standing needs ~13% of the knee limit, so this always fails.
    _script(root / "tight" / "impossible.yml", "impossible", limit=0.001)
    (root / "malformed.yaml").write_text(MALFORMED)
    return root


def _batch(
    args: list[str], cwd: Path, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*LOCOPLAN, "batch", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        env={**os.environ, **(env or {})},
    )


def _cases(report: Path) -> dict[str, dict[str, Any]]:
    """Each JUnit test case by file: its attributes but time, its failure / error / skipped
    element (tag, message) and its properties but the wall-time ones."""
    cases = {}
    for case in ET.parse(report).getroot().iter("testcase"):
        verdicts = [(el.tag, el.get("message")) for el in case if el.tag != "properties"]
        props = {
            p.get("name"): p.get("value")
            for p in case.iter("property")
            if not str(p.get("name")).startswith(WALL_TIME)
        }
        attrs = {k: v for k, v in case.attrib.items() if k != "time"}
        cases[str(case.get("file"))] = {"attrs": attrs, "verdicts": verdicts, "props": props}
    return cases


def _ray_available() -> None:
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'locoplan[ray]')")


@pytest.mark.closed_loop
def test_ray_gives_the_local_backends_results(tmp_path: Path) -> None:
    _ray_available()
    _suite(tmp_path / "suite")
    # Relative paths, as a CI job writes them: the Ray workers get them made absolute.
    local = _batch(["suite", "--out", "out-local", "--junit", "local.xml", "--jobs", "2"], tmp_path)
    ray_args = ["suite", "--out", "out-ray", "--junit", "ray.xml", "--jobs", "2"]
    ray = _batch([*ray_args, "--backend", "ray"], tmp_path)
    assert local.returncode == ray.returncode == 1, ray.stderr
    assert "Traceback" not in ray.stdout + ray.stderr
    assert "1 passed, 1 failed, 1 error" in ray.stdout
    assert "on Ray (a local Ray)" in ray.stderr

    local_cases = _cases(tmp_path / "local.xml")
    ray_cases = _cases(tmp_path / "ray.xml")
    assert set(ray_cases) == {"suite/passing.yaml", "suite/tight/impossible.yml",
                              "suite/malformed.yaml"}  # fmt: skip
    for case_id, expected in local_cases.items():
        got = ray_cases[case_id]
        assert got["attrs"] == expected["attrs"]
        assert got["verdicts"] == expected["verdicts"]
        # The same metrics, but for the output folder in the log's path.
        assert {**got["props"], "log": None} == {**expected["props"], "log": None}
    assert ray_cases["suite/passing.yaml"]["props"]["log"] == "out-ray/passing.mcap"
    assert [v[0] for v in ray_cases["suite/tight/impossible.yml"]["verdicts"]] == ["failure"]
    assert [v[0] for v in ray_cases["suite/malformed.yaml"]["verdicts"]] == ["error"]

    # The workers wrote the logs where the driver looks, the driver the metrics JSON.
    assert (tmp_path / "out-ray" / "passing.mcap").is_file()
    metrics = json.loads((tmp_path / "out-ray" / "tight" / "impossible.json").read_text())
    assert metrics["scenario"] == "impossible" and metrics["passed"] is False
    assert metrics["log"] == "out-ray/tight/impossible.mcap"

    # The same cache: nothing left to run, so no Ray is even started.
    again = _batch([*ray_args, "--backend", "ray"], tmp_path)
    assert again.returncode == 1
    assert again.stdout.count("(cached)") == 2
    for case_id in ("suite/passing.yaml", "suite/tight/impossible.yml"):
        assert _cases(tmp_path / "ray.xml")[case_id]["props"]["cached"] == "true"


def _warm_kernels(tmp_path: Path) -> None:
    """A 0.5 s stand run in this process, so that numba's kernel cache is written before the
    Ray workers start: in a fresh clone each worker would otherwise compile the kernels
    (about 40 s of CPU each) within the --timeout."""
    loaded = load_scenario_file(_script(tmp_path / "warm.yaml", "warm"))
    run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path / "warm", log=False))


@pytest.mark.closed_loop
def test_crashed_and_hung_ray_tasks_are_that_scripts_error(tmp_path: Path) -> None:
    _ray_available()
    _warm_kernels(tmp_path)
    _script(tmp_path / "iso" / "crash.yaml", "crasher")
    _script(tmp_path / "iso" / "ok.yaml", "fine")
    _script(tmp_path / "hung" / "hang.yaml", "hanger")
    env = {"LOCOPLAN_TEST_CRASH": "crasher", "LOCOPLAN_TEST_HANG": "hanger"}
    # --timeout 300 for the crash and the fine script: Ray's worker start-up is counted.
    # Alone on an idle 2-core machine, the kernels cached, the crash came at 3.6 s and the
    # fine script took 0.6 s; on a busy one (the suite's other worker) the crash took more
    # than 15 s; beside an envelope benchmark on the same two cores, more than 40 s, and
    # beside two (load average 4) 61 s, the fine script 50 s (60 s failed in a fresh clone's
    # `make test` beside two envelope runs). The hung script times out whatever the load, so
    # it runs in a batch of its own with a short timeout: together with the others it held
    # this test, the suite's slowest, at 129 s.
    # 120 s failed too, in a fresh clone's `make test` beside a one-worker envelope run (load
    # about 3 on two cores: the crash was reported as a timeout). The timeout only bounds a
    # run that would fail anyway; a crash seen in time ends the batch at once.
    args = ["iso", "--out", "out", "--junit", "r.xml", "--timeout", "300", "--jobs", "2"]
    res = _batch([*args, "--backend", "ray"], tmp_path, env)
    assert res.returncode == 1, res.stderr
    assert "Traceback" not in res.stdout + res.stderr
    cases = _cases(tmp_path / "r.xml")
    crash = cases["iso/crash.yaml"]["verdicts"]
    assert crash[0][0] == "error" and "Ray task failed: WorkerCrashedError" in crash[0][1]
    assert cases["iso/ok.yaml"]["verdicts"] == []

    args = ["hung", "--out", "out-hung", "--junit", "h.xml", "--timeout", "10", "--jobs", "1"]
    res = _batch([*args, "--backend", "ray"], tmp_path, env)
    assert res.returncode == 1, res.stderr
    assert "Traceback" not in res.stdout + res.stderr
    hang = _cases(tmp_path / "h.xml")["hung/hang.yaml"]["verdicts"]
    assert hang == [("error", "timed out after 10 s (--timeout); Ray task cancelled")]


def test_bad_backend_options_exit_2_before_running(tmp_path: Path) -> None:
    _script(tmp_path / "s.yaml", "s")
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    for args, message in (
        (["--backend", "spark"], "unknown --backend 'spark'; allowed: local, ray"),
        (["--address", "auto"], "--address needs --backend ray"),
        (["--backend", "ray", "--address", f"127.0.0.1:{port}"], "cannot reach the Ray cluster"),
        (["--backend", "ray", "--address", f"ray://127.0.0.1:{port}"], "ray start --head"),
    ):
        res = _batch(["s.yaml", "--out", "out", *args], tmp_path)
        assert res.returncode == 2, (args, res.stderr)
        assert message in res.stderr
        assert "Traceback" not in res.stderr
        assert not (tmp_path / "out").exists()


def test_missing_ray_says_how_to_install(tmp_path: Path) -> None:
    (tmp_path / "ray.py").write_text("raise ImportError('No module named ray')\n")
    _script(tmp_path / "s.yaml", "s")
    res = _batch(["s.yaml", "--backend", "ray"], tmp_path, {"PYTHONPATH": str(tmp_path)})
    assert res.returncode == 2
    assert "pip install 'locoplan[ray]'" in res.stderr


def test_help_shows_the_backend() -> None:
    res = subprocess.run(
        [*LOCOPLAN, "batch", "--help"], capture_output=True, text=True, timeout=60, check=False
    )
    assert res.returncode == 0
    assert "--backend" in res.stdout and "--address" in res.stdout


# --- the scheduling loop against a stand-in for the `ray` module --------------------------


class _Ref:
    def __init__(self, job: Job) -> None:
        self.job = job


class _FakeRay:
    """Enough of `ray` for `ray_backend._run`: tasks finish in submission order, each with
    the outcome `verdicts[job_id]` gives; `cancel` is recorded."""

    class RayError(Exception):
        pass

    exceptions = SimpleNamespace(RayError=RayError)

    def __init__(self, verdicts: dict[str, str]) -> None:
        self.verdicts = verdicts
        self.submitted: list[Job] = []
        self.cancelled: list[str] = []
        self.forced: list[bool] = []

    def remote(self, **_: Any) -> Any:
        fake = self

        class _Remote:
            def __init__(self, fn: Any) -> None:
                pass

            def remote(self, job: Job, code: str | None = None) -> _Ref:
                fake.submitted.append(job)
                return _Ref(job)

        return _Remote

    def wait(self, refs: list[_Ref], num_returns: int, timeout: float) -> tuple[list, list]:
        return refs[:num_returns], refs[num_returns:]

    def get(self, ref: _Ref) -> Outcome:
        if ref.job.job_id in self.cancelled:
            raise self.RayError("TaskCancelledError")
        return Outcome(ref.job.job_id, self.verdicts[ref.job.job_id])  # type: ignore[arg-type]

    def cancel(self, ref: _Ref, force: bool) -> None:
        self.cancelled.append(ref.job.job_id)
        self.forced.append(force)


def _jobs(tmp_path: Path, n: int) -> list[Job]:
    options = RunOptions(out_dir=Path("runs/x"), log_name=None)
    return [Job(f"s{i}.yaml", f"s{i}", f"s{i}.yaml", "", options) for i in range(n)]


def test_fail_fast_cancels_and_skips_the_rest(tmp_path: Path) -> None:
    jobs = _jobs(tmp_path, 5)
    fake = _FakeRay({"s0.yaml": "passed", "s1.yaml": "failed", "s2.yaml": "passed",
                     "s3.yaml": "passed", "s4.yaml": "passed"})  # fmt: skip
    outcomes = ray_backend._run(fake, jobs, 2, None, None, fail_fast=True)
    assert [o.status for o in outcomes] == ["passed", "failed", "skipped", "skipped", "skipped"]
    assert fake.cancelled == ["s2.yaml"]  # in flight when s1 failed
    assert outcomes[2].message == "stopped (--fail-fast)"
    assert outcomes[3].message == outcomes[4].message == "not run (--fail-fast)"
    assert [j.job_id for j in fake.submitted] == ["s0.yaml", "s1.yaml", "s2.yaml"]


def test_without_fail_fast_every_job_runs(tmp_path: Path) -> None:
    jobs = _jobs(tmp_path, 3)
    fake = _FakeRay({"s0.yaml": "failed", "s1.yaml": "error", "s2.yaml": "passed"})
    outcomes = ray_backend._run(fake, jobs, 2, None, None)
    assert [o.status for o in outcomes] == ["failed", "error", "passed"]
    assert fake.cancelled == []


def test_a_signal_cancels_the_running_and_skips_the_rest(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from locoplan import interrupt

    jobs = _jobs(tmp_path, 4)
    fake = _FakeRay({job.job_id: "passed" for job in jobs})
    real_wait = fake.wait
    calls = 0

    def wait(refs: list[_Ref], num_returns: int, timeout: float) -> tuple[list, list]:
        nonlocal calls
        calls += 1
        if calls == 2:  # s0 done; a SIGTERM arrives while s1 and s2 run
            monkeypatch.setattr(interrupt.STATE, "signum", 15)
            return [], refs
        return real_wait(refs, num_returns, timeout)

    monkeypatch.setattr(fake, "wait", wait)
    outcomes = ray_backend._run(fake, jobs, 2, None, None)
    assert [o.status for o in outcomes] == ["passed", "skipped", "skipped", "skipped"]
    # The running task is cancelled gently first (its worker closes the log).
    assert fake.cancelled == ["s1.yaml", "s2.yaml"] and fake.forced == [False, False]
    assert outcomes[1].message.startswith("interrupted (SIGTERM); Ray task cancelled")
    assert outcomes[3].message == "not run (interrupted, SIGTERM)"


def test_jobs_go_out_absolute_and_logs_come_back_as_given(tmp_path: Path) -> None:
    (job,) = _jobs(tmp_path, 1)
    sent = ray_backend._absolute(job)
    assert Path(sent.source).is_absolute() and sent.options.out_dir.is_absolute()
    assert sent.options.out_dir == Path("runs/x").absolute()
    back = Outcome(job.job_id, "passed", {"log": str(sent.options.out_dir / "s0.mcap")})
    assert ray_backend._as_given(back, job).metrics == {"log": "runs/x/s0.mcap"}
    elsewhere = Outcome(job.job_id, "passed", {"log": "/elsewhere/s0.mcap"})
    assert ray_backend._as_given(elsewhere, job) == elsewhere


def test_a_node_with_other_code_is_that_jobs_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (job,) = _jobs(tmp_path, 1)
    monkeypatch.setattr(ray_backend, "_worker_code", lambda: "b" * 64)
    outcome = ray_backend._execute(job, "a" * 64)
    assert outcome.status == "error"
    assert "other locoplan code" in outcome.message and "aaaaaaaaaaaa" in outcome.message


def test_workers_for() -> None:
    assert ray_backend.workers_for(7, 3, None) == 3
    assert ray_backend.workers_for(7, None, "auto") == 7
    assert ray_backend.workers_for(7, None, None) >= 1


def test_check_reachable_names_the_address() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with pytest.raises(BackendUnavailable, match=f"127.0.0.1:{port}"):
        ray_backend.check_reachable(f"127.0.0.1:{port}", timeout=2.0)
    ray_backend.check_reachable("auto")  # left to Ray
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        ray_backend.check_reachable(f"ray://127.0.0.1:{server.getsockname()[1]}", timeout=2.0)
