"""REACTION_TIME on real pybullet runs (issue 22): in a generated stress room of `rei demo`'s
suite (seed 1: a person emerges from behind a wall stub beside the route), the reference
navigator passes and the same navigator with its commands 0.5 s or 0.8 s late fails, the
margin falls with the latency and has the verdict's sign, a second run of the same scenario
and seed writes the same bytes, and replaying the recorded trace gives the same verdict and
margin."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from bench.defects.timing import ControlLatency
from rei.runtime.commands.demo import generate_suite
from rei.runtime.commands.replay import replay
from rei.runtime.results import Verdict
from rei.runtime.runs.session import run_into

REPO = Path(__file__).resolve().parents[2]
SEED = 1


class Latency02(ControlLatency):
    """Commands 0.2 s late: within REACTION_TIME's 300 ms window."""

    latency = 0.2


class Latency08(ControlLatency):
    latency = 0.8


def _reaction(out: Path, mission: Path, controller: str) -> Verdict:
    summary, _ = run_into(mission, out, controller=controller, seed=SEED)
    return {v.requirement: v for v in summary.verdicts}["REACTION_TIME"]


@pytest.mark.slow
def test_late_commands_fail_reaction_time_in_an_emerging_person_room(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p))
    generate_suite(tmp_path / "suite", 6, "small", SEED)
    mission = tmp_path / "suite" / "stress" / "stress_0001.mission"
    room = (tmp_path / "suite" / "stress" / "stress_0001.room").read_text(encoding="utf-8")
    assert "stressor: kind=emerge" in room  # the scenario this test is about
    here = "tests.observation.test_reaction_runs"
    verdicts = {
        "reference": _reaction(tmp_path / "ref", mission, "reference"),
        "0.2": _reaction(tmp_path / "l02", mission, f"{here}:Latency02"),
        "0.5": _reaction(tmp_path / "l05", mission, "bench.defects.timing:ControlLatency"),
        "0.8": _reaction(tmp_path / "l08", mission, f"{here}:Latency08"),
    }
    status = {k: v.status for k, v in verdicts.items()}
    assert status == {"reference": "pass", "0.2": "pass", "0.5": "fail", "0.8": "fail"}
    for v in verdicts.values():
        assert v.margin is None or (v.margin < 0) == (v.status == "fail")
    late, later = verdicts["0.5"].margin, verdicts["0.8"].margin
    assert late is not None and later is not None and later < late < 0
    prompt = verdicts["0.2"].margin
    assert prompt is None or prompt >= 0
    # the same scenario and seed give the same bytes (verdicts, margins, event log)
    _reaction(tmp_path / "l05again", mission, "bench.defects.timing:ControlLatency")
    for name in ("summary.json", "events.csv"):
        assert (tmp_path / "l05again" / name).read_bytes() == (tmp_path / "l05" / name).read_bytes()
    # the recorded trace replays to the same verdict (the scans are in it)
    again = replay(tmp_path / "l05" / "trace.jsonl", None, tmp_path / "replay")
    replayed = {v.requirement: v for v in again.verdicts}["REACTION_TIME"]
    assert (replayed.status, replayed.margin) == (verdicts["0.5"].status, late)
