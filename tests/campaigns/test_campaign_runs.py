"""Campaigns of real `rei run` processes: 50 runs that survive kill -9 and resume with every run
exactly once, crashes and hangs recorded, the same campaign on a real Dask cluster, and the
same seeds giving the same results on either engine."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from lxml import etree

from rei.runtime.campaigns import CampaignStore, plan_campaign
from rei.runtime.results import judge

from .conftest import require_rei_run
from .records import EXAMPLES

MISSIONS = [EXAMPLES / "simple_wall", EXAMPLES / "small_dense"]
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""


def campaign_argv(out: Path, *extra: str, repeat: int = 25) -> list[str]:
    return [sys.executable, "-m", "rei.runtime.commands", "campaign", *map(str, MISSIONS),
            "-o", str(out), "--repeat", str(repeat), "--seed", "5", "--duration", "2", *extra]


def recorded(out: Path) -> int:
    runs = out / "runs"
    return sum(1 for p in runs.glob("*/record.json")) if runs.is_dir() else 0


def kill_and_resume(out: Path, argv: list[str], after: int, runs: int = 50
                    ) -> subprocess.CompletedProcess[str]:
    """Start the campaign of ``runs`` runs, SIGKILL its whole process group once ``after``
    runs are recorded, then run the same command again to the end."""
    process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               start_new_session=True)
    deadline = time.monotonic() + SAFETY_LIMIT
    while recorded(out) < after and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    assert process.returncode == -signal.SIGKILL, process.stderr.read() if process.stderr else ""
    if process.stderr:
        process.stderr.close()
    interrupted_at = recorded(out)
    assert after <= interrupted_at < runs
    resumed = subprocess.run(argv, capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert f"{interrupted_at} of {runs} runs already recorded" in resumed.stderr
    return resumed


def assert_every_run_once(out: Path, repeat: int = 25) -> None:
    plan = plan_campaign(MISSIONS, repeat=repeat, seed=5, duration=2.0)
    _, manifest, records = CampaignStore.read(out)
    assert [r.spec.run_id for r in records] == [s.run_id for s in plan.runs]
    assert len(plan.runs) == 2 * repeat
    assert len(manifest["sessions"]) == 2
    table = pq.read_table(out / "results.parquet").to_pylist()
    assert sorted(r["run_id"] for r in table) == sorted(s.run_id for s in plan.runs)
    assert {r["seed"] for r in table} == {s.seed for s in plan.runs}
    assert all(r["status"] == "ran" for r in table)
    assert not (out / "runs" / ".partial").exists()
    runs = [p for p in (out / "runs").iterdir()]
    assert len(runs) == 2 * repeat
    for folder in runs:
        summary = json.loads((folder / "summary.json").read_text())
        assert summary["seed"] == next(s.seed for s in plan.runs if s.run_id == folder.name)
        assert (folder / "trace.jsonl").is_file()
    suites = etree.parse(str(out / "junit.xml")).getroot().findall("testsuite")
    assert [s.get("name") for s in suites] == ["simple_wall", "small_dense"]
    assert (out / "report.html").stat().st_size > 0


@pytest.mark.slow
def test_fifty_runs_survive_kill_9_and_resume_with_every_run_once(tmp_path: Path) -> None:
    require_rei_run()
    out = tmp_path / "campaign"
    resumed = kill_and_resume(out, campaign_argv(out, "--workers", "2"), after=6)
    # Two simulated seconds are too short to finish these missions: every run times out, so
    # the campaign reports failures and exits 1, as CI should see it.
    assert resumed.returncode == 1, resumed.stderr
    assert "50 of 50 runs recorded, 0 passed, 50 failed" in resumed.stderr
    assert_every_run_once(out)


@pytest.mark.slow
def test_the_dask_engine_passes_the_same_test_on_a_real_cluster(tmp_path: Path,
                                                                 dask_scheduler: str) -> None:
    require_rei_run()
    out = tmp_path / "campaign"
    # 20 runs, not the local engine's 50: the kill and the resume are what is tested here,
    # on the cluster (the longest test of the suite at 50, about 100 s).
    argv = campaign_argv(out, "--engine", "dask", "--scheduler", dask_scheduler, repeat=10)
    resumed = kill_and_resume(out, argv, after=6, runs=20)
    assert resumed.returncode == 1, resumed.stderr
    assert_every_run_once(out, repeat=10)
    manifest = json.loads((out / "campaign.json").read_text())
    assert manifest["sessions"][0]["engine"] == {"engine": "dask", "scheduler": dask_scheduler,
                                                 "pages": "failed"}


def _summaries(out: Path) -> dict[str, str]:
    return {p.parent.name: p.read_text() for p in sorted(out.glob("runs/*/summary.json"))}


@pytest.mark.slow
def test_same_seed_same_results_on_both_engines_and_any_worker_count(
        tmp_path: Path, dask_scheduler: str) -> None:
    require_rei_run()
    runs = {}
    for name, extra in (("one", ["--workers", "1"]), ("two", ["--workers", "2"]),
                        ("dask", ["--engine", "dask", "--scheduler", dask_scheduler])):
        out = tmp_path / name
        done = subprocess.run(campaign_argv(out, *extra, "--no-report", repeat=2),
                              capture_output=True, text=True, timeout=SAFETY_LIMIT)
        assert done.returncode == 1, done.stderr
        runs[name] = _summaries(out)
    assert len(runs["one"]) == 4
    assert runs["one"] == runs["two"] == runs["dask"]


CONTROLLERS = """
import os
import signal
import time

from rei.runtime.robot.navigator.reference import ReferenceNavigator


class Segfaulting(ReferenceNavigator):
    \"\"\"A controller whose native code crashes the whole run process.\"\"\"

    def step(self, observation):
        os.kill(os.getpid(), signal.SIGSEGV)


class Crawling(ReferenceNavigator):
    \"\"\"A controller so slow that the run never ends in useful time (each call is within
    `rei run`'s own per-call watchdog, so only the campaign's watchdog can stop it).\"\"\"

    def step(self, observation):
        time.sleep(0.2)
        return super().step(observation)
"""


def _campaign(tmp_path: Path, out: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(tmp_path / "plugins"), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, "-m", "rei.runtime.commands", "campaign", *args,
                           "-o", str(out)], capture_output=True, text=True, env=env,
                          timeout=SAFETY_LIMIT)


@pytest.mark.slow
def test_crashed_and_hung_runs_are_recorded_and_the_campaign_goes_on(tmp_path: Path) -> None:
    require_rei_run()
    (tmp_path / "plugins").mkdir()
    (tmp_path / "plugins" / "bad_controllers.py").write_text(CONTROLLERS)
    good = str(EXAMPLES / "simple_wall" / "simple_wall.mission")
    crashed = _campaign(tmp_path, tmp_path / "crash", good, "--repeat", "2", "--duration", "2",
                        "--controller", "bad_controllers:Segfaulting")
    assert crashed.returncode == 3, crashed.stderr  # a run error is exit 3, not a failure
    assert "verdict: ERROR" in crashed.stdout and "2 run(s) errored" in crashed.stdout
    records = CampaignStore.read(tmp_path / "crash")[2]
    # `rei run` supervises its simulation: the crash is the run's error, with its summary
    assert [r.status for r in records] == ["ran", "ran"]
    assert [r.verdict for r in records] == ["error", "error"]
    assert records[0].summary is not None
    assert "killed by signal 11 (SIGSEGV)" in records[0].summary.reason
    # A watchdog far shorter than the run: it is killed and recorded as hung.
    hung = _campaign(tmp_path, tmp_path / "hung", good, "--duration", "100", "--timeout", "2",
                     "--controller", "bad_controllers:Crawling")
    assert hung.returncode == 3, hung.stderr
    (record,) = CampaignStore.read(tmp_path / "hung")[2]
    assert record.status == "hung" and "watchdog" in record.message
    junit = etree.parse(str(tmp_path / "hung" / "junit.xml")).getroot()
    assert junit.find("testsuite/testcase/error").get("type") == "hung"
    # The campaign goes on past bad runs: a good mission next to a broken one still runs.
    broken = tmp_path / "missions" / "broken.mission"
    broken.parent.mkdir()
    broken.write_text('mission broken in "nowhere.room" {\n goal a at x timeout 5\n}\n')
    mixed = _campaign(tmp_path, tmp_path / "mixed", str(broken), good, "--duration", "2")
    assert mixed.returncode == 3, mixed.stderr
    by_id = {r.spec.run_id: r for r in CampaignStore.read(tmp_path / "mixed")[2]}
    assert by_id["broken.r00"].status == "crashed"
    assert "exit status 2, no summary.json" in by_id["broken.r00"].message
    assert by_id["simple_wall.r00"].status == "ran"


@pytest.mark.slow
def test_ctrl_c_stops_the_campaign_and_the_same_command_finishes_it(tmp_path: Path) -> None:
    require_rei_run()
    out = tmp_path / "campaign"
    argv = campaign_argv(out, "--workers", "2", "--no-report", repeat=4)
    # As a terminal's Ctrl-C does: SIGINT to the whole foreground process group.
    process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)
    deadline = time.monotonic() + SAFETY_LIMIT
    while recorded(out) < 2 and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGINT)
    _, err = process.communicate(timeout=SAFETY_LIMIT)
    assert process.returncode == 130, err
    assert "Run the same command again" in err
    assert "Traceback" not in err
    done = recorded(out)
    assert 2 <= done < 8
    assert not list((out / "runs" / ".partial").glob("*"))
    resumed = subprocess.run(argv, capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert f"{done} of 8 runs already recorded" in resumed.stderr
    assert resumed.returncode == 1
    plan = plan_campaign(MISSIONS, repeat=4, seed=5, duration=2.0)
    assert [r.spec.run_id for r in CampaignStore.read(out)[2]] == [s.run_id for s in plan.runs]


@pytest.mark.slow
def test_demo_generates_runs_and_reports(tmp_path: Path) -> None:
    require_rei_run()
    done = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "demo", "-o",
                           str(tmp_path), "--count", "2", "--repeat", "1", "--workers", "2"],
                          capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert done.returncode == 0, done.stderr
    report = tmp_path / "campaign" / "report.html"
    assert report.as_uri() in done.stdout
    assert len(CampaignStore.read(tmp_path / "campaign")[2]) == 2
    assert (tmp_path / "suite" / "index.csv").is_file()


@pytest.mark.slow
def test_a_worker_without_the_campaign_folder_sends_the_run_files_back(tmp_path: Path) -> None:
    require_rei_run()
    from rei.runtime.campaigns.execute import execute_run_remote  # noqa: PLC0415

    plan = plan_campaign([EXAMPLES / "simple_wall"], duration=2.0)
    (spec,) = plan.runs
    result = execute_run_remote(spec, str(tmp_path / "not-on-this-machine" / spec.run_id))
    assert result.status == "ran"
    assert {"summary.json", "trace.jsonl", "run.log"} <= set(result.files)
    assert not (tmp_path / "not-on-this-machine").exists()
    with CampaignStore.open(tmp_path / "campaign", plan, {}) as store:
        record = store.record(spec, result, store.new_work_dir(spec.run_id))
        assert record is not None and record.summary is not None
        run_dir = store.run_dir(spec.run_id)
    assert (run_dir / "summary.json").read_bytes() == result.files["summary.json"]
    assert json.loads((run_dir / "summary.json").read_text())["seed"] == spec.seed


@pytest.mark.slow
def test_a_users_vepl_reaches_every_run_and_its_requirements_reach_junit(tmp_path: Path) -> None:
    require_rei_run()
    vepl = EXAMPLES / "navigation" / "human_safety.vepl"
    out = tmp_path / "campaign"
    done = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "campaign",
                           str(EXAMPLES / "navigation"), "-o", str(out), "--vepl", str(vepl),
                           "--duration", "5", "--no-report"],
                          capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert done.returncode in (0, 1), done.stderr
    (record,) = CampaignStore.read(out)[2]
    assert record.summary is not None
    requirements = {v.requirement for v in record.summary.verdicts}
    assert requirements == {"HUMAN_PERSONAL_SPACE", "HUMAN_NO_COLLISION"}
    cases = etree.parse(str(out / "junit.xml")).getroot().iter("testcase")
    assert {c.get("name", "").split(" [")[0] for c in cases} == requirements
    columns = (out / "results.csv").read_text().splitlines()[0].split(",")
    assert {"req:HUMAN_PERSONAL_SPACE", "req:HUMAN_NO_COLLISION"} <= set(columns)


@pytest.mark.slow
def test_demo_passes_a_users_controller_vepl_and_seed_to_every_run(tmp_path: Path) -> None:
    require_rei_run()
    (tmp_path / "plugins").mkdir()
    (tmp_path / "plugins" / "my_nav.py").write_text(
        "from rei.runtime.robot.navigator.reference import ReferenceNavigator\n\n\n"
        "class MyNavigator(ReferenceNavigator):\n    name = 'my-navigator'\n")
    vepl = EXAMPLES / "navigation" / "human_safety.vepl"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(tmp_path / "plugins"), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "demo", "-o",
                           str(tmp_path / "demo"), "--count", "1", "--repeat", "1",
                           "--workers", "1", "--seed", "4", "--controller", "my_nav:MyNavigator",
                           "--vepl", str(vepl)],
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, env=env)
    assert done.returncode in (0, 1), done.stderr
    plan, manifest, records = CampaignStore.read(tmp_path / "demo" / "campaign")
    assert plan.seed == 4
    (record,) = records
    assert record.summary is not None
    # The demo exits by the one pass rule: this room's walker comes within the strict .vepl's
    # personal space (a verdict about the run, not about the demo passing its options on).
    assert done.returncode == (0 if judge(record.summary) == "pass" else 1), done.stderr
    assert record.spec.controller == "my_nav:MyNavigator"
    assert record.spec.vepl == str(vepl.resolve())
    assert {v.requirement for v in record.summary.verdicts} == {"HUMAN_PERSONAL_SPACE",
                                                               "HUMAN_NO_COLLISION"}
    assert manifest["sessions"][0]["controller"] == "my_nav:MyNavigator"
    bad = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "demo", "-o",
                          str(tmp_path / "bad"), "--vepl", str(tmp_path / "missing.vepl")],
                         capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert bad.returncode == 2 and "missing.vepl' does not exist" in bad.stderr
    assert not (tmp_path / "bad" / "suite").exists()  # refused before generating anything
