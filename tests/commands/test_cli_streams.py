"""`rei run` and `rei replay` print results on stdout and diagnostics on stderr (issue 14.2).

Each case runs the real command in a subprocess with stdout and stderr captured apart, the
way a CI job or a shell pipeline sees them.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, REPO

NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""


def rei(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rei.runtime.commands", *args], cwd=REPO,
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False)


Done = tuple[Path, subprocess.CompletedProcess[str]]


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Done]:
    root = tmp_path_factory.mktemp("streams")
    done = {}
    for mode in ("default", "quiet", "verbose"):
        out = root / mode
        flags = [] if mode == "default" else [f"--{mode}"]
        done[mode] = (out, rei("run", str(NAVIGATION), "-o", str(out), "--duration", "3",
                               *flags))
    return done


def test_results_go_to_stdout_and_end_with_the_verdict_line(runs) -> None:  # type: ignore[no-untyped-def]
    out, done = runs["default"]
    assert done.returncode == 1  # cut short: the mission's requirements are inconclusive
    lines = done.stdout.splitlines()
    assert lines[0].startswith("to_the_elevator: timeout (duration limit of 3 s reached) "
                               "after 3.0 s simulated")
    assert lines[-1] == f"verdict: INCONCLUSIVE; total utility {_utility(out)}; outputs in {out}"
    assert f"  run page: {out / 'report.html'}" in lines
    summary = json.loads((out / "summary.json").read_text())
    shown = {line.split(":")[0].strip() for line in lines[1:-1] if line.startswith("  ")}
    undecided = {v["requirement"] for v in summary["verdicts"]
                 if v["status"] in ("fail", "inconclusive")}
    assert undecided and undecided <= shown
    # passed / not applicable ones are counted, not listed
    passed = [v for v in summary["verdicts"] if v["status"] == "not_applicable"]
    assert f"  {len(passed)} not applicable" in lines
    # stderr holds the diagnostics (the speed of the run), never a result
    assert "real time" in done.stderr and "verdict" not in done.stderr
    assert "to_the_elevator" not in done.stderr


def test_quiet_prints_only_the_final_verdict_line(runs) -> None:  # type: ignore[no-untyped-def]
    out, done = runs["quiet"]
    assert done.returncode == 1
    assert done.stdout.splitlines() == [
        f"verdict: INCONCLUSIVE; total utility {_utility(out)}; outputs in {out}"]
    assert done.stderr == ""


def test_verbose_lists_every_requirement_and_the_mission_events(runs) -> None:  # type: ignore[no-untyped-def]
    out, done = runs["verbose"]
    assert done.returncode == 1
    summary = json.loads((out / "summary.json").read_text())
    for v in summary["verdicts"]:
        assert f"  {v['requirement']}: {v['status'].replace('_', ' ')}" in done.stdout
        assert v["reason"] in done.stdout
    # the events as they happened, on stderr (progress, not results)
    assert "task_start start_place (#0)" in done.stderr
    assert "task_start" not in done.stdout


def test_the_outputs_are_the_same_whatever_is_printed(runs) -> None:  # type: ignore[no-untyped-def]
    trees = [(out / "trace.jsonl").read_bytes() + (out / "summary.json").read_bytes()
             for out, _ in runs.values()]
    assert trees[0] == trees[1] == trees[2]


def test_replay_prints_the_same_lines_as_the_run(runs, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    out, live = runs["default"]
    again = rei("replay", str(out / "trace.jsonl"), "-o", str(tmp_path))
    assert again.returncode == live.returncode == 1
    assert again.stdout.splitlines()[-1] == live.stdout.splitlines()[-1].replace(
        str(out), str(tmp_path))
    assert "verdict" not in again.stderr
    quiet = rei("replay", str(out / "trace.jsonl"), "-o", str(tmp_path / "q"), "--quiet")
    assert quiet.stdout.splitlines() == [again.stdout.splitlines()[-1].replace(
        str(tmp_path), str(tmp_path / "q"))]


def test_bad_input_writes_nothing_on_stdout(tmp_path: Path) -> None:
    done = rei("run", str(NAVIGATION), "-o", str(tmp_path), "--controller", "nope")
    assert done.returncode == 2 and done.stdout == ""
    assert "--controller: expected one of reference" in done.stderr
    done = rei("run", str(NAVIGATION), "-o", str(tmp_path), "--duration", "-1")
    assert done.returncode == 2 and done.stdout == ""
    assert "--duration: expected a positive number of seconds, found -1" in done.stderr


def test_quiet_and_verbose_exclude_each_other(tmp_path: Path) -> None:
    done = rei("run", str(NAVIGATION), "-o", str(tmp_path), "--quiet", "--verbose")
    assert done.returncode == 2 and "not allowed with argument" in done.stderr


def _utility(out: Path) -> str:
    return f"{json.loads((out / 'summary.json').read_text())['total_utility']:g}"


def test_campaign_quiet_prints_only_its_verdict_line(tmp_path: Path) -> None:
    out = tmp_path / "campaign"
    done = rei("campaign", str(EXAMPLES / "simple_wall" / "simple_wall.mission"), "-o",
               str(out), "--duration", "1", "--workers", "1", "--quiet")
    assert done.returncode == 1, done.stderr  # cut short: not a pass
    assert done.stdout.splitlines() == [
        f"verdict: INCONCLUSIVE; 0 of 1 missions passed; report: {out / 'report.html'}"]
    assert done.stderr == ""


def test_what_a_controller_prints_goes_to_stderr(tmp_path: Path) -> None:
    done = rei("run", str(NAVIGATION), "-o", str(tmp_path), "--duration", "1", "--quiet",
               "--controller", "tests.robot.faulty:Chatty")
    assert done.returncode == 1
    assert done.stdout.startswith("verdict: ") and len(done.stdout.splitlines()) == 1
    assert "chatty: step at t=0.0" in done.stderr
