"""One exit rule for `rei campaign`, `rei demo` and `rei report` (campaign_outcome), and
inconclusive runs shown as inconclusive — never as failures — in the mission verdicts, the
--pair-static labels, the progress line, the report and JUnit.

The rule's table is tested on records written through the real store; the commands are tested
through their real command lines: a navigator that fails makes `rei demo --controller X` exit
1, a campaign cut short by --duration is inconclusive (exit 1, "inconclusive" everywhere), and
a run error is exit 3 (in test_campaign_runs.py, with crashing and hanging controllers).
"""

from __future__ import annotations

import io
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
from lxml import etree

from rei.lang.cli_support import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_RUN_ERROR
from rei.runtime.campaigns import CampaignStore, classify_pairs, mission_verdicts
from rei.runtime.campaigns.progress import Progress
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.stats import campaign_outcome

from .conftest import require_rei_run
from .records import EXAMPLES, example_plan, write_campaign

SAFETY_LIMIT = 900.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""


def _with_verdict(record: RunRecord, status: str) -> RunRecord:
    """The record as if its task requirement had ended ``status`` (pass/fail/inconclusive)."""
    assert record.summary is not None
    verdicts = tuple(replace(v, status=status) if v.requirement == "all_tasks_succeed" else v
                     for v in record.summary.verdicts)
    return replace(record, summary=replace(record.summary, outcome="completed",
                                           verdicts=verdicts))


def _records(tmp_path: Path) -> list[RunRecord]:
    plan = example_plan(repeat=2)
    plan = replace(plan, runs=tuple(r for r in plan.runs
                                    if r.run_id.startswith(("simple_wall", "navigation"))))
    write_campaign(tmp_path, plan)
    return list(CampaignStore.read(tmp_path)[2])


def test_the_exit_rule_in_order_of_precedence(tmp_path: Path) -> None:
    records = [_with_verdict(r, "pass") for r in _records(tmp_path)]
    planned = len(records)

    def outcome(runs: list[RunRecord], **kw: bool) -> tuple[str, int]:
        out = campaign_outcome(runs, mission_verdicts(runs), planned=planned, **kw)
        return out.status, out.exit_code

    assert outcome(records) == ("pass", EXIT_OK)
    cut_short = [_with_verdict(r, "inconclusive") if r.spec.run_id.startswith("navigation")
                 else r for r in records]
    assert outcome(cut_short) == ("inconclusive", EXIT_FAILED)
    failing = [_with_verdict(cut_short[0], "fail"), *cut_short[1:]]
    assert outcome(failing) == ("fail", EXIT_FAILED)  # a failure outranks an open question
    crashed = [replace(failing[0], status="crashed", summary=None), *failing[1:]]
    assert outcome(crashed) == ("error", EXIT_RUN_ERROR)  # an error outranks a failure
    assert outcome(crashed, interrupted=True) == ("interrupted", EXIT_INTERRUPTED)
    assert outcome(records[:-1]) == ("incomplete", EXIT_FAILED)  # a planned run is missing


def test_a_mission_none_of_whose_runs_failed_is_inconclusive(tmp_path: Path) -> None:
    records = [_with_verdict(r, "inconclusive") if r.spec.run_id.endswith(".r01")
               else _with_verdict(r, "pass") for r in _records(tmp_path)]
    verdicts = {v.mission: v for v in mission_verdicts(records)}
    assert {m: v.verdict for m, v in verdicts.items()} == {
        "simple_wall": "inconclusive", "navigation": "inconclusive"}
    assert "no run failed, 1 inconclusive" in verdicts["navigation"].reason
    records[0] = _with_verdict(records[0], "fail")
    assert mission_verdicts(records)[0].verdict == "fail"


def test_the_progress_line_counts_inconclusive_and_error_runs_apart() -> None:
    stream = io.StringIO()
    progress = Progress(total=4, stream=stream)
    for verdict in ("pass", "inconclusive", "inconclusive", "error"):
        progress.update(verdict)
    assert "4/4 runs  pass 1  fail 0  inconclusive 2  error 1  " in stream.getvalue()


def test_pair_labels_say_inconclusive_when_nothing_failed(tmp_path: Path) -> None:
    from rei.runtime.campaigns import plan_campaign  # noqa: PLC0415

    plan = plan_campaign([EXAMPLES / "simple_wall"], repeat=2, seed=3,
                         static_dir=tmp_path / "static")
    write_campaign(tmp_path / "c", plan)
    records = [_with_verdict(r, "inconclusive") for r in CampaignStore.read(tmp_path / "c")[2]]
    (pair,) = classify_pairs(records)
    assert pair.cause == "inconclusive in the static room too"
    twins_pass = [_with_verdict(r, "pass") if r.spec.static_pair else r for r in records]
    assert classify_pairs(twins_pass)[0].cause == "inconclusive with people only"
    people_fail = [_with_verdict(r, "fail") if not r.spec.static_pair else r for r in records]
    assert classify_pairs(people_fail)[0].cause == "fails with people only"
    both_fail = [_with_verdict(r, "fail") for r in records]
    assert classify_pairs(both_fail)[0].cause == "fails in the static room too"


GIVES_UP = """\
from rei.runtime.messages import NavState
from rei.runtime.robot.navigator.reference import ReferenceNavigator


class GivesUp(ReferenceNavigator):
    \"\"\"A navigator whose planner finds no path: it accepts each goal and aborts it.\"\"\"

    name = "gives-up"

    def step(self, observation):
        if self._tracker.state == NavState.PENDING:
            self._tracker.accept()
            self._tracker.abort("no valid plan")
        return super().step(observation)
"""


def _rei(tmp_path: Path, *argv: str) -> subprocess.CompletedProcess[str]:
    plugins = tmp_path / "plugins"
    plugins.mkdir(exist_ok=True)
    (plugins / "gives_up.py").write_text(GIVES_UP)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(plugins), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, "-m", "rei.runtime.commands", *argv],
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, env=env)


@pytest.mark.slow
def test_a_failing_navigator_makes_rei_demo_exit_1_and_rei_report_agrees(tmp_path: Path
                                                                         ) -> None:
    require_rei_run()
    demo = _rei(tmp_path, "demo", "-o", str(tmp_path / "demo"), "--count", "1", "--repeat",
                "1", "--workers", "1", "--controller", "gives_up:GivesUp")
    assert demo.returncode == EXIT_FAILED, demo.stderr
    assert "verdict: FAIL; 0 of 1 missions passed" in demo.stdout
    junit = etree.parse(str(tmp_path / "demo" / "campaign" / "junit.xml")).getroot()
    assert int(junit.get("failures", "0")) >= 1
    report = _rei(tmp_path, "report", str(tmp_path / "demo" / "campaign"), "--no-html")
    assert report.returncode == EXIT_FAILED, report.stderr
    # The reference navigator on the same suite: the gate opens.
    good = _rei(tmp_path, "demo", "-o", str(tmp_path / "good"), "--count", "1", "--repeat",
                "1", "--workers", "1")
    assert good.returncode == EXIT_OK, good.stderr + good.stdout


@pytest.mark.slow
def test_a_campaign_cut_short_is_inconclusive_everywhere(tmp_path: Path) -> None:
    require_rei_run()
    out = tmp_path / "smoke"
    done = _rei(tmp_path, "campaign", str(EXAMPLES / "simple_wall"), "-o", str(out),
                "--repeat", "2", "--workers", "2", "--duration", "1", "--pair-static")
    assert done.returncode == EXIT_FAILED, done.stderr
    assert "pass 0  fail 0  inconclusive 4" in done.stderr
    assert "INCONCLUSIVE  simple_wall:" in done.stderr
    assert "inconclusive in the static room too" in done.stderr
    assert "fails in the static room too" not in done.stderr
    assert "verdict: INCONCLUSIVE; 0 of 1 missions passed" in done.stdout
    html = (out / "report.html").read_text()
    assert "<b>INCONCLUSIVE</b>campaign" in html
    cases = etree.parse(str(out / "junit.xml")).getroot().iter("failure")
    assert {c.get("type") for c in cases} == {"inconclusive"}
    again = _rei(tmp_path, "report", str(out), "--no-html")
    assert again.returncode == EXIT_FAILED
    assert "verdict: INCONCLUSIVE" in again.stdout
