"""`rei watch --foxglove`: a Foxglove WebSocket server read by an independent client.

The client is Foxglove's own: the npm packages @foxglove/ws-protocol (the protocol, asking
for the `foxglove.sdk.v1` subprotocol) and @foxglove/rosmsg2-serialization (ROS 2 CDR), run
in Node (tests/presentation/node/client.mjs, installed from the npm registry into the git-ignored
tests/presentation/node/node_modules). It subscribes to every advertised channel and decodes every
message by its channel's schema; the tests check what it decoded against the run's trace and
events.csv: the scene, laser, odometry, paths and signals in the recording's ROS 2 types."""

from __future__ import annotations

import json
import math
import re
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import pytest

from rei.runtime.messages.ros import TOPICS
from rei.runtime.observation.evaluator.signal_log import read_csv
from rei.runtime.presentation.live.foxglove import LIVE_TOPICS
from rei.runtime.trace import read_trace
from tests.conftest import REPO, require_tool
from tests.presentation.conftest import SAFETY_LIMIT

CLIENT = Path(__file__).parent / "node"


@pytest.fixture(scope="session")
def node_client() -> Path:
    """client.mjs with its npm packages (installed once, as .ci/run does)."""
    require_tool("node")
    npm = require_tool("npm")
    if not (CLIENT / "node_modules" / "@foxglove" / "ws-protocol").is_dir():
        subprocess.run([npm, "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=CLIENT,
                       check=True, capture_output=True, timeout=SAFETY_LIMIT)
    return CLIENT / "client.mjs"


def start_watch(path: Path, *args: str) -> tuple[subprocess.Popen[str], str]:
    """`rei watch --replay PATH --foxglove 0 --plain ARGS`, and its server's URL."""
    watch = subprocess.Popen(
        [sys.executable, "-m", "rei.runtime.commands", "watch", "--replay", str(path),
         "--foxglove", "0", "--plain", *args],
        cwd=REPO, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True)
    assert watch.stderr is not None
    for line in watch.stderr:
        found = re.search(r"ws://127\.0\.0\.1:\d+", line)
        if found:
            return watch, found.group(0)
    watch.kill()
    raise AssertionError(f"no server address on stderr (exit {watch.wait()})")


def read_messages(lines: IO[str]) -> Iterator[dict[str, Any]]:
    for line in lines:
        yield json.loads(line)


@pytest.fixture
def processes() -> Iterator[list[subprocess.Popen[str]]]:
    started: list[subprocess.Popen[str]] = []
    yield started
    for p in started:
        if p.poll() is None:
            p.kill()
        p.wait(timeout=SAFETY_LIMIT)
        for stream in (p.stdout, p.stderr):
            if stream is not None:
                stream.close()


def _close(a: float, b: float, tol: float = 1e-6) -> bool:
    return math.isclose(a, b, abs_tol=tol)


@pytest.mark.parametrize("name", ["pass", "fail"])
def test_a_foxglove_client_decodes_the_run_on_the_recordings_channels(
        recorded: dict[str, Path], node_client: Path, name: str,
        processes: list[subprocess.Popen[str]]) -> None:
    run = recorded[name]
    # --wait: the run plays once the client has subscribed, so it sees every message
    watch, url = start_watch(run / "trace.jsonl", "--wait", "--exit", "--speed", "20")
    processes.append(watch)
    client = subprocess.Popen(["node", str(node_client), url], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
    processes.append(client)
    out, err = client.communicate(timeout=SAFETY_LIMIT)
    assert client.returncode == 0, err
    status = watch.wait(timeout=SAFETY_LIMIT)
    assert status == {"pass": 0, "fail": 1}[name]
    messages = [json.loads(line) for line in out.splitlines()]
    by_topic: dict[str, list[dict[str, Any]]] = {}
    for m in messages:
        by_topic.setdefault(m["topic"], []).append(m)

    # the channels of the MCAP recording, in its ROS 2 types and CDR, plus the two paths
    schemas = {t: ms[0]["schema"] for t, ms in by_topic.items()}
    for topic in LIVE_TOPICS:
        assert schemas[topic] == TOPICS[topic], topic
        assert by_topic[topic][0]["encoding"] == "cdr"
    assert schemas["/rei/path"] == schemas["/rei/goals"] == "nav_msgs/msg/Path"
    assert by_topic["/rei/trace"][0]["encoding"] == "json"

    header, samples = read_trace(run / "trace.jsonl")
    trace = list(samples)
    # the exact trace, line for line
    records = [m["message"] for m in by_topic["/rei/trace"]]
    assert records[0]["format"] == "rei-trace" and records[0]["mission"] == header.mission
    assert [r["seq"] for r in records[1:-1]] == [s.seq for s in trace]
    # ... and its end line, as the recording's /rei/trace ends
    assert records[-1] == json.loads((run / "trace.jsonl").read_text().splitlines()[-1])

    # signals: events.csv, row for row
    events = read_csv(run / "events.csv")
    signals = [json.loads(m["message"]["data"]) for m in by_topic["/rei/signals"]]
    assert [(s["time"], s["signal"], s["utility"], s["total_utility"], tuple(s["objects"]))
            for s in signals] == [(r.time, r.signal, r.utility, r.total_utility, r.objects)
                                  for r in events]
    # what the screen shows, for Foxglove's panels: the last one says how it ended
    monitor = [json.loads(m["message"]["data"]) for m in by_topic["/rei/monitor"]]
    assert len(monitor) == len(trace) + 1
    live = json.loads((run / "summary.json").read_text())
    assert (monitor[-1]["verdict"], monitor[-1]["total_utility"]) == (
        live["verdict"], live["total_utility"])
    assert set(monitor[-1]["objects"]) == {o.name for o in header.objects}
    if name == "fail":
        assert monitor[-1]["robot_state"] == "COLLISION"
        assert monitor[-1]["objects"]["wall_e"]["state"] == "COLLISION"
    else:
        assert {m["robot_state"] for m in monitor} == {"FAR", "CLOSE"}
    # mission events
    kinds = [json.loads(m["message"]["data"])["kind"] for m in by_topic["/rei/events"]]
    assert kinds[0] == "begin" and kinds[-1] == "end"

    # /tf: the robot's ground-truth pose at every sample, stamped with simulated time
    robot = header.robot.name
    tf = [(m["logTime"], t) for m in by_topic["/tf"] for t in m["message"]["transforms"]
          if t["child_frame_id"] == robot]
    assert len(tf) == len(trace)
    for (log_time, t), sample in zip(tf, trace, strict=True):
        assert int(log_time) == round(sample.time * 1e9)
        x, y, yaw = sample.robot_pose
        assert t["header"]["frame_id"] == "map"
        assert (t["transform"]["translation"]["x"], t["transform"]["translation"]["y"]) \
            == (x, y)
        q = t["transform"]["rotation"]
        assert _close(2 * math.atan2(q["z"], q["w"]), yaw) or _close(
            abs(2 * math.atan2(q["z"], q["w"]) - yaw), 2 * math.pi)
    # every body gets a frame, so its marker is drawn
    framed = {t["child_frame_id"] for m in by_topic["/tf"] for t in m["message"]["transforms"]}
    assert framed == {robot} | {o.name for o in header.objects}

    # the scene: one marker per body (its name as text) and the floor's tiles
    markers = by_topic["/world/markers"][-1]["message"]["markers"]
    assert [m["text"] for m in markers] == [robot, *(o.name for o in header.objects), "floor"]
    assert [m["ns"] for m in markers[1:-1]] == [o.role for o in header.objects]
    laser = by_topic["/tf_static"][-1]["message"]["transforms"][0]
    assert laser["child_frame_id"] == f"{robot}/laser"
    assert laser["transform"]["translation"]["x"] == header.laser_mount[0]

    # the laser: every scan, its beams as float32 of the trace's ranges
    scans = [s for s in trace if s.belief.scan is not None]
    assert 0 < len(by_topic["/scan"]) <= len(trace)
    last_scan = by_topic["/scan"][-1]["message"]
    ranges = scans[-1].belief.scan.ranges  # type: ignore[union-attr]
    assert len(last_scan["ranges"]) == len(ranges)
    # REP 117 (the shared mapping, issue 24): a beam without a return (REI's range_max) is
    # +inf, which the client's JSON decoding gives as null
    range_max = scans[-1].belief.scan.range_max  # type: ignore[union-attr]
    assert all((a is None or a == math.inf) if b >= range_max else _close(a, b, 1e-5)
               for a, b in zip(last_scan["ranges"], ranges, strict=True))
    assert last_scan["header"]["frame_id"] == f"{robot}/laser"
    odom = by_topic["/odom"][-1]["message"]
    assert (odom["pose"]["pose"]["position"]["x"], odom["pose"]["pose"]["position"]["y"]) \
        == trace[-1].belief.odom[:2]

    # paths: the robot's route so far ends where the robot is; the goals in mission order
    route = by_topic["/rei/path"][-1]["message"]["poses"]
    end = route[-1]["pose"]["position"]
    assert math.hypot(end["x"] - trace[-1].robot_pose[0],
                      end["y"] - trace[-1].robot_pose[1]) < 0.05 + 1e-9
    assert len(route) >= 2
    goals = by_topic["/rei/goals"][-1]["message"]["poses"]
    assert header.mission_facts is not None
    assert [(g["pose"]["position"]["x"], g["pose"]["position"]["y"]) for g in goals] == [
        (g.x, g.y) for g in header.mission_facts.goals]


def test_a_client_that_joins_late_still_gets_the_scene(
        recorded: dict[str, Path], node_client: Path,
        processes: list[subprocess.Popen[str]]) -> None:
    run = recorded["pass"]
    watch, url = start_watch(run / "recording.mcap", "--speed", "0")
    processes.append(watch)
    assert watch.stdout is not None
    for line in watch.stdout:  # the whole run has played before the client connects
        if line.startswith("ended at"):
            break
    # the client gives up after 10 s without a message: a missing resend fails, never hangs
    client = subprocess.Popen(["node", str(node_client), url, "10000"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    processes.append(client)
    assert client.stdout is not None
    wanted = {"/tf_static", "/world/markers", "/rei/goals", "/tf", "/rei/path"}
    got: dict[str, dict[str, Any]] = {}
    for message in read_messages(client.stdout):
        got.setdefault(message["topic"], message)
        if wanted <= set(got):
            break
    assert wanted <= set(got), f"only {sorted(got)} came"
    watch.send_signal(signal.SIGINT)  # ends the server; the verdict stays the run's
    watch.communicate(timeout=SAFETY_LIMIT)  # drained, so no write of its can block it
    assert watch.returncode == 0
    header, samples = read_trace(run / "trace.jsonl")
    last = list(samples)[-1]
    # the latest /tf of every body, walls included, at the last sample's time
    tf = got["/tf"]
    assert int(tf["logTime"]) == round(last.time * 1e9)
    assert {t["child_frame_id"] for t in tf["message"]["transforms"]} == {
        header.robot.name} | {o.name for o in header.objects}
    assert len(got["/world/markers"]["message"]["markers"]) == len(header.objects) + 2
    client.communicate(timeout=SAFETY_LIMIT)  # drained: it exits once its output is read
