"""Faults in `rei run` end to end (issue 17): the mission's fault section and --fault are
checked together before anything runs, every sample and events.csv row names the faults
active when it was taken, the summary and the run's page say which fault was active when,
and a replay of the trace gives the live events.csv byte for byte."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from functools import partial
from pathlib import Path

import pytest

from rei.lang.errors import LanguageError
from rei.lang.mission.faults import Activation, FaultDefinition, parse_fault_option
from rei.runtime.simulation.faults import active_at
from rei.runtime.simulation.faults.composition import fault_stage
from rei.runtime.simulation.faults.configuration import run_faults
from rei.runtime.trace import read_trace
from tests.conftest import EXAMPLES, REPO

SIMPLE_WALL = EXAMPLES / "simple_wall" / "simple_wall.mission"
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""
WINDOW = "laser_dropout as blind share 0.5 from 1 to 3"
PULSED = "laser_poisson rate 4 gain 0.2 period 2 width 0.25"


def rei(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rei.runtime.commands", *args], cwd=REPO,
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False)


@pytest.fixture(scope="module")
def faulted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("faulted")
    done = rei("run", str(SIMPLE_WALL), "-o", str(out), "--duration", "5", "-q",
               "--fault", WINDOW, "--fault", PULSED)
    assert done.returncode in (0, 1), done.stderr
    return out


def test_the_summary_says_which_fault_was_active_when(faulted: Path) -> None:
    m = json.loads((faulted / "summary.json").read_text())["measurements"]
    assert [f["fault"] for f in m["faults_injected"]] == ["blind", "laser_poisson"]
    assert m["faults_injected"][0]["entry"] == parse_fault_option(WINDOW).text()
    windows = [(f["start"], f["end"]) for f in m["faults"] if f["fault"] == "blind"]
    assert windows == [(1.0, 3.0)]
    # the impulse-switched fault lies only while its impulse is high: 0.5 s of every 2 s
    pulses = [(f["start"], f["end"]) for f in m["faults"] if f["fault"] == "laser_poisson"]
    assert pulses[:3] == [(0.0, 0.5), (2.0, 2.5), (4.0, 4.5)]
    dropped = m["fault_statistics"]["blind"]
    assert 0.4 < dropped["dropped"] / dropped["beams"] < 0.6
    assert f"fault blind: {parse_fault_option(WINDOW).text()}" in \
        (faulted / "run.log").read_text()


def test_every_sample_names_the_faults_active_when_it_was_taken(faulted: Path) -> None:
    header, lazy = read_trace(faulted / "trace.jsonl")
    samples = list(lazy)
    assert [name for name, _ in header.faults] == ["blind", "laser_poisson"]
    for s in samples:
        # a window fault is on from its start to its end, as the samples at 10 Hz see it
        assert ("blind" in s.faults) == (1.0 - 1e-9 <= s.time < 3.0 - 1e-9), (s.time, s.faults)
        assert ("laser_poisson" in s.faults) == (s.time % 2.0 < 0.5 - 1e-9), (s.time, s.faults)
    # what the robot was told: the dropped beams read the maximum range in the belief
    inside = [s for s in samples if 1.2 < s.time < 2.8 and s.belief.scan is not None]
    assert inside and all((s.belief.scan.ranges == s.belief.scan.range_max).mean() > 0.4
                          for s in inside)


def test_events_csv_names_the_active_faults_and_replay_gives_the_same_bytes(
        faulted: Path, tmp_path: Path) -> None:
    with open(faulted / "events.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert rows and "faults" in rows[0]
    _, lazy = read_trace(faulted / "trace.jsonl")
    samples = list(lazy)
    by_time = {s.time: s.faults for s in samples}
    for row in rows:
        time = float(row["time"])
        if time in by_time:  # a signal fired on a sample: that sample's active faults
            assert row["faults"] == ";".join(by_time[time])
    done = rei("replay", str(faulted / "trace.jsonl"), "-o", str(tmp_path), "-q")
    assert done.returncode in (0, 1), done.stderr
    assert (tmp_path / "events.csv").read_bytes() == (faulted / "events.csv").read_bytes()
    # the replay's summary and page say which fault was active when, as the samples saw it
    live = json.loads((faulted / "summary.json").read_text())["measurements"]
    again = json.loads((tmp_path / "summary.json").read_text())["measurements"]
    assert again["faults_injected"] == live["faults_injected"]
    windows = [(f["start"], f["end"]) for f in again["faults"] if f["fault"] == "blind"]
    assert windows == [(1.0, 3.0)]
    assert 'data-fault="blind"' in (tmp_path / "report.html").read_text()


def test_the_run_page_lists_the_faults(faulted: Path) -> None:
    page = (faulted / "report.html").read_text()
    assert 'id="faults-table"' in page and 'data-fault="blind"' in page
    assert "1.0 s – 3.0 s" in page or "1 s – 3 s" in page or "1.00 s – 3.00 s" in page


def test_a_run_without_faults_keeps_five_columns(tmp_path: Path) -> None:
    done = rei("run", str(SIMPLE_WALL), "-o", str(tmp_path), "--duration", "1", "-q")
    assert done.returncode in (0, 1), done.stderr
    assert (tmp_path / "events.csv").read_text().splitlines()[0] == \
        "time,signal,utility,total_utility,objects"
    assert '"faults"' not in (tmp_path / "trace.jsonl").read_text()
    assert "faults" not in json.loads((tmp_path / "summary.json").read_text())["measurements"]


@pytest.mark.parametrize(("args", "expected"), [
    (["--fault", "laser_dropout share 0.3 when SIG_GEOM_FAR_TRANSIT_CLOS for 2"],
     ["FAULT-SIGNAL", "SIG_GEOM_FAR_TRANSIT_CLOS", "did you mean 'SIG_GEOM_FAR_TRANSIT_CLOSE'"]),
    (["--no-monitor", "--fault", "laser_freeze when SIG_MISSION_BEGIN for 1"],
     ["FAULT-SIGNAL", "--no-monitor"]),
    (["--fault", "laser_freeze", "--fault", "laser_freeze from 2"], ["FAULT-NAME", "twice"]),
    (["--fault", "laser_dropout share 2"], ["--fault", "share"]),
    (["--fault", "laser_freeze from 5 to 6"], ["FAULT-WINDOW", "ends at 1 s", "from 5"]),
    (["--fault", "cmd_drop share 1 when SIG_MISSION_BEGIN for 0.1"],
     ["FAULT-WINDOW", "'for' longer than 0.1 s", "found 0.1 s"]),
    (["--fault", "laser_freeze from 0.25 to 0.35"], ["FAULT-WINDOW", "hold a scan (every 0.2 s)"]),
    (["--fault", "laser_dropout"], ["--fault", "expected the parameter 'share'"]),
])
def test_a_fault_the_run_cannot_deliver_is_refused_before_anything_runs(
        tmp_path: Path, args: list[str], expected: list[str]) -> None:
    done = rei("run", str(SIMPLE_WALL), "-o", str(tmp_path), "--duration", "1", *args)
    assert done.returncode == 2, done.stderr
    for text in expected:
        assert text in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "trace.jsonl").exists()


def test_run_faults_locates_each_problem() -> None:
    mission = (FaultDefinition.of("laser_freeze", Activation(signal="SIG_A", duration=1.0)),)
    extra = (FaultDefinition.of("laser_freeze", Activation(start=1.0)),)
    with pytest.raises(LanguageError) as err:
        run_faults(mission, extra, ("SIG_B",), "m.mission", "spec.vepl")
    codes = sorted(d.rule for d in err.value.diagnostics)
    assert codes == ["FAULT-NAME", "FAULT-SIGNAL"]
    assert run_faults(mission, (), ("SIG_A",), "m.mission", "spec.vepl") == mission


@pytest.mark.parametrize(("entry", "refused"), [
    ("laser_sector min_deg 0.2 max_deg 0.8", True),  # between two beams 1 deg apart
    ("laser_sector min_deg 10 max_deg 10", False),
    ("laser_sector min_deg -0.5 max_deg 0.5", False),
])
def test_run_faults_refuses_a_sector_holding_no_beam(entry: str, refused: bool) -> None:
    fault = (parse_fault_option(entry),)
    check = partial(run_faults, (), fault, (), "m.mission", "spec.vepl", 100.0, None,
                    (-math.pi, math.tau / 360, 360))
    if refused:
        with pytest.raises(LanguageError, match="hold a beam of the scanner"):
            check()
    else:
        assert check() == fault


@pytest.mark.parametrize(("entry", "refused"), [
    ("cmd_drop share 1 when SIG_A for 0.1", True),  # one tick: the summary said 'active'
    ("cmd_drop share 1 when SIG_A for 0.15", False),  # with 'asked 0': it never acted
    ("laser_dropout share 1 from 1.05 to 1.15", True),
    ("laser_dropout share 1 from 1.05 to 1.25", False),
    ("laser_delay seconds 1 from 1.05 to 1.15", False),  # a delay acts at every tick
    ("odom_jump dx 1 from 1.01 to 1.09", True),
    ("laser_poisson rate 5 gain 1 when SIG_A for 0.01", False),  # occurrences: any time
])
def test_run_faults_refuses_windows_no_tick_falls_in(entry: str, refused: bool) -> None:
    fault = (parse_fault_option(entry),)
    check = partial(run_faults, (), fault, ("SIG_A",), "m.mission", "spec.vepl", 100.0,
                    (0.1, 0.1, 0.2))
    if refused:
        with pytest.raises(LanguageError, match="FAULT-WINDOW"):
            check()
    else:
        assert check() == fault


def test_active_at_follows_the_pulses() -> None:
    stage = fault_stage([parse_fault_option(PULSED)], seed=0)
    stage.command(7.0, (0.0, 0.0))  # the stage's clock reaches 7 s
    timeline = stage.timeline()
    assert timeline[:4] == (("laser_poisson", 0.0, 0.5), ("laser_poisson", 2.0, 2.5),
                            ("laser_poisson", 4.0, 4.5), ("laser_poisson", 6.0, 6.5))
    order = ("laser_poisson",)
    assert active_at(timeline, 0.25, order) == order
    assert active_at(timeline, 0.5, order) == ()
    assert active_at(timeline, 6.4, order) == order
    assert active_at(timeline, 6.6, order) == ()


def test_the_loops_quick_active_set_agrees_with_the_timeline() -> None:
    """The loop asks the plan which faults act now (``active_now``) instead of building the
    whole timeline every control tick; both must say the same at every tick."""
    stage = fault_stage([parse_fault_option(PULSED), parse_fault_option(WINDOW),
                         parse_fault_option("odom_jump dx 0.2 from 2.5")], seed=3)
    order = tuple(name for name, _ in stage.described())
    for k in range(81):
        now = k / 10
        stage.command(now, (0.0, 0.0))
        assert stage.active_now(now) == active_at(stage.timeline(), now, order), now
