"""`rei run --record` on real pybullet runs: the recording carries the run's exact trace and
its ROS 2 views, and `rei replay recording.mcap` gives exactly the live run's events.csv and
verdicts, also cut short, and refuses what is not a recording (issue 17.2-3)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_typestore

from rei.runtime.campaigns import plan_campaign
from rei.runtime.messages.ros import TOPICS
from rei.runtime.observation.recordings import TRACE_TOPIC, read_recording
from rei.runtime.trace import read_trace
from tests.conftest import EXAMPLES, REPO

SIMPLE_WALL = EXAMPLES / "simple_wall" / "simple_wall.mission"
CROSSING = Path(__file__).parents[1] / "scenes" / "crossing.mission"
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""
STORE = get_typestore(Stores.ROS2_HUMBLE)


def rei(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rei.runtime.commands", *args], cwd=REPO,
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("recorded")
    out = {}
    for name, mission, duration in (("wall", SIMPLE_WALL, "20"), ("crossing", CROSSING, "12")):
        folder = root / name
        done = rei("run", str(mission), "-o", str(folder), "--record", "--duration", duration)
        assert done.returncode in (0, 1), done.stderr
        assert (folder / "recording.mcap").is_file()
        out[name] = folder
    return out


def _topics(path: Path) -> dict[str, list[bytes]]:
    out: dict[str, list[bytes]] = {}
    with path.open("rb") as handle:
        for _, channel, message in make_reader(handle).iter_messages(log_time_order=False):
            out.setdefault(channel.topic, []).append(message.data)
    return out


@pytest.mark.parametrize("name", ["wall", "crossing"])
def test_replaying_the_recording_gives_the_live_events_and_verdicts(
        runs: dict[str, Path], tmp_path: Path, name: str) -> None:
    live = runs[name]
    done = rei("replay", str(live / "recording.mcap"), "-o", str(tmp_path / "replay"))
    assert done.returncode in (0, 1), done.stderr
    assert (tmp_path / "replay" / "events.csv").read_bytes() == \
        (live / "events.csv").read_bytes()
    a = json.loads((live / "summary.json").read_text(encoding="utf-8"))
    b = json.loads((tmp_path / "replay" / "summary.json").read_text(encoding="utf-8"))
    for key in ("verdicts", "verdict", "signal_counts", "total_utility", "outcome", "reason",
                "duration"):
        assert a[key] == b[key], key
    assert done.stdout.splitlines()[-1].split(";")[0] == \
        f"verdict: {a['verdict'].upper()}"


def test_a_new_specification_judges_the_recording_as_it_judges_the_trace(
        runs: dict[str, Path], tmp_path: Path) -> None:
    live = runs["crossing"]
    vepl = EXAMPLES / "navigation" / "human_safety.vepl"
    out = {}
    for name in ("recording.mcap", "trace.jsonl"):
        folder = tmp_path / name
        done = rei("replay", str(live / name), "--vepl", str(vepl), "-o", str(folder))
        assert done.returncode in (0, 1), done.stderr
        out[name] = folder
    assert (out["recording.mcap"] / "events.csv").read_bytes() == \
        (out["trace.jsonl"] / "events.csv").read_bytes()
    a, b = (json.loads((out[n] / "summary.json").read_text(encoding="utf-8"))
            for n in ("recording.mcap", "trace.jsonl"))
    assert a["verdicts"] == b["verdicts"] and a["verdicts"]


def test_the_same_run_records_the_same_bytes(runs: dict[str, Path], tmp_path: Path) -> None:
    done = rei("run", str(SIMPLE_WALL), "-o", str(tmp_path / "again"), "--record",
               "--duration", "20", "--quiet")
    assert done.returncode in (0, 1), done.stderr
    assert (tmp_path / "again" / "recording.mcap").read_bytes() == \
        (runs["wall"] / "recording.mcap").read_bytes()


def test_the_trace_channel_is_the_trace_file(runs: dict[str, Path]) -> None:
    live = runs["crossing"]
    lines = (live / "trace.jsonl").read_bytes().splitlines()
    carried = [STORE.deserialize_cdr(d, "std_msgs/msg/String").data.encode("utf-8")
               for d in _topics(live / "recording.mcap")[TRACE_TOPIC]]
    assert carried == lines


def test_ros_views_match_the_ground_truth_of_every_body(runs: dict[str, Path]) -> None:
    live = runs["crossing"]
    header, samples = read_trace(live / "trace.jsonl")
    trace = list(samples)
    topics = _topics(live / "recording.mcap")
    tf = [STORE.deserialize_cdr(d, TOPICS["/tf"]) for d in topics["/tf"]]
    assert len(tf) == len(trace)
    bodies = {header.robot.name, *(o.name for o in header.objects)}
    assert any(o.role == "human" for o in header.objects)
    latest: dict[str, tuple[float, float, float]] = {}
    for sample, message in zip(trace, tf, strict=True):
        for t in message.transforms:
            r = t.transform
            latest[t.child_frame_id] = (r.translation.x, r.translation.y,
                                        2 * math.atan2(r.rotation.z, r.rotation.w))
        assert set(latest) == bodies
        for i, obj in enumerate(header.objects):
            x, y, yaw = latest[obj.name]
            assert (x, y) == tuple(sample.poses[i, :2])
            assert math.remainder(yaw - sample.poses[i, 2], math.tau) == pytest.approx(
                0.0, abs=1e-9)
    scans = [STORE.deserialize_cdr(d, TOPICS["/scan"]) for d in topics["/scan"]]
    recorded = [s.belief.scan for s in trace if s.belief.scan is not None]
    assert len(scans) == len(recorded) > 0
    for message, scan in zip(scans, recorded, strict=True):
        assert message.ranges.dtype == np.float32
        # REP 117: a beam without a return (REI's range_max) is +inf, the others as measured
        no_return = scan.ranges >= scan.range_max
        assert np.isposinf(message.ranges[no_return]).all()
        np.testing.assert_allclose(message.ranges[~no_return], scan.ranges[~no_return],
                                   rtol=1e-7, atol=0)
    signals = [json.loads(STORE.deserialize_cdr(d, TOPICS["/rei/signals"]).data)
               for d in topics.get("/rei/signals", [])]
    rows = (live / "events.csv").read_text(encoding="utf-8").splitlines()[1:]
    assert [s["signal"] for s in signals] == [r.split(",")[1] for r in rows]
    events = [json.loads(STORE.deserialize_cdr(d, TOPICS["/rei/events"]).data)
              for d in topics["/rei/events"]]
    assert [e["kind"] for e in events] == [e.kind for s in trace for e in s.events]


def test_a_recording_cut_short_replays_as_an_interrupted_run(runs: dict[str, Path],
                                                             tmp_path: Path) -> None:
    data = (runs["crossing"] / "recording.mcap").read_bytes()
    cut = tmp_path / "recording.mcap"
    cut.write_bytes(data[:len(data) * 2 // 3])
    _, stream = read_recording(cut)
    kept = len(list(stream))
    done = rei("replay", str(cut), "-o", str(tmp_path / "replay"))
    assert "Traceback" not in done.stderr
    summary = json.loads((tmp_path / "replay" / "summary.json").read_text(encoding="utf-8"))
    assert summary["outcome"] == "interrupted"
    assert "cut short" in summary["reason"] and f"after {kept} sample(s)" in summary["reason"]
    assert done.returncode == 130
    assert "cut short" in done.stdout


def test_replay_refuses_what_is_not_a_recording(tmp_path: Path) -> None:
    fake = tmp_path / "fake.mcap"
    fake.write_bytes(b"PK\x03\x04 not a recording")
    done = rei("replay", str(fake), "-o", str(tmp_path / "out"))
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"{fake}: expected an MCAP recording" in done.stderr


def test_a_campaign_with_record_leaves_a_recording_in_every_run(tmp_path: Path) -> None:
    out = tmp_path / "campaign"
    done = rei("campaign", str(SIMPLE_WALL), "-o", str(out), "--repeat", "2", "--duration",
               "3", "--workers", "1", "--record", "--no-report", "--quiet")
    assert done.returncode in (0, 1), done.stderr
    runs = sorted((out / "runs").iterdir())
    assert len(runs) == 2
    for run in runs:
        header, samples = read_recording(run / "recording.mcap")
        assert header.mission == "to_the_wall" and len(list(samples)) > 0
        assert samples.end is not None


def test_campaign_record_reaches_every_run(tmp_path: Path) -> None:
    plan = plan_campaign([SIMPLE_WALL], repeat=2, record=True)
    assert all(r.record and r.run_argv(str(tmp_path))[-1] == "--record" for r in plan.runs)
    assert all("--record" not in r.run_argv(str(tmp_path))
               for r in plan_campaign([SIMPLE_WALL]).runs)
    assert plan.runs[0].to_json()["record"] is True
