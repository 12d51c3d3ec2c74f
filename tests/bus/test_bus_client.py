"""The bus's client API against a real Zenoh router on loopback: messages published by one
role arrive decoded at another, configuration is asked for and answered, and bad input
(credentials, payloads, endpoints) is refused in one line or dropped and counted."""

from __future__ import annotations

import json
import stat
import threading
from pathlib import Path

import numpy as np
import pytest

from rei.runtime.bus import BusError, connect
from rei.runtime.bus.router import Router
from rei.runtime.messages import (
    CommandIssued,
    LaserScan,
    MissionEvent,
    MissionStatus,
    NavState,
    OdometryReading,
    ScanReading,
    SignalFired,
)
from tests.bus.conftest import SAFETY, Inbox


def _scan(seq: int) -> ScanReading:
    ranges = np.linspace(0.2, 3.5, 360)
    return ScanReading(seq, 0.1 * seq, LaserScan(-np.pi, 2 * np.pi / 360, 0.12, 3.5, ranges))


def test_messages_arrive_decoded_in_order(join) -> None:  # type: ignore[no-untyped-def]
    sim, viewer = join("simulation"), join("viewer")
    inbox = Inbox()
    viewer.subscribe(None, inbox)
    assert sim.await_readers("sensor/odometry", SAFETY)
    assert sim.await_readers("sensor/laser", SAFETY)
    sent = [OdometryReading(i, 0.05 * i, (0.1 * i, 0.0, 0.01 * i), (0.2, 0.0))
            for i in range(50)]
    for message in sent[:25]:
        sim.publish(message)
    sim.publish(_scan(0))
    for message in sent[25:]:
        sim.publish(message)
    got = inbox.wait(51)
    odometry = [m for t, m in got if t == "sensor/odometry"]
    assert odometry == sent  # every one, in order, equal field by field
    (scan,) = [m for t, m in got if t == "sensor/laser"]
    assert scan.seq == 0 and np.array_equal(scan.scan.ranges, _scan(0).scan.ranges)


def test_subscribing_to_topics_delivers_only_those(join) -> None:  # type: ignore[no-untyped-def]
    sim, monitor = join("simulation"), join("monitor")
    inbox = Inbox()
    monitor.subscribe(["robot/command"], inbox)
    assert sim.await_readers("robot/command", SAFETY)
    sim.publish(OdometryReading(0, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0)))
    sim.publish(CommandIssued(0, 0.0, (0.3, 0.1), (0.26, 0.1)))
    assert inbox.wait(1) == [("robot/command", CommandIssued(0, 0.0, (0.3, 0.1), (0.26, 0.1)))]


def test_configuration_is_asked_and_answered(join) -> None:  # type: ignore[no-untyped-def]
    sim, monitor = join("simulation"), join("monitor")
    sim.answer("world", lambda: {"world": "office", "tile_size": 1.0})
    assert monitor.query("world", timeout=SAFETY) == {"world": "office", "tile_size": 1.0}
    with pytest.raises(BusError, match="configuration name expected to be one of world"):
        monitor.query("passwords")


def test_a_question_asked_before_its_answerer_joins_waits_for_it(join) -> None:  # type: ignore[no-untyped-def]
    """A monitor started before the simulation asks again until the answer comes (the
    first asks find nobody to answer); a question nobody ever answers ends at its timeout."""
    sim, monitor = join("simulation"), join("monitor")
    later = threading.Timer(0.5, sim.answer, ("world", lambda: {"world": "late"}))
    later.start()
    try:
        assert monitor.query("world", timeout=SAFETY) == {"world": "late"}
    finally:
        later.cancel()
    with pytest.raises(BusError, match="rei/v1/config/robot: no answer within 0.3 s"):
        monitor.query("robot", timeout=0.3)


def test_mission_events_and_signals_round_trip(join) -> None:  # type: ignore[no-untyped-def]
    mission, sim, monitor = join("mission"), join("simulation"), join("monitor")
    inbox = Inbox()
    sim.subscribe(["monitor/signal"], inbox)
    watcher = Inbox()
    monitor.subscribe(["mission/status"], watcher)
    assert mission.await_readers("mission/status", SAFETY)
    assert monitor.await_readers("monitor/signal", SAFETY)
    status = MissionStatus(3, 1.5, (MissionEvent("task_fail", 1.5, "g1", 0, "timeout after 30 s",
                                                 "timeout"),), NavState.ABORTED, "g1")
    mission.publish(status)
    monitor.publish(SignalFired(0, 1.5, "SIG_MISSION_TASK_FAIL"))
    assert watcher.wait(1) == [("mission/status", status)]
    assert inbox.wait(1) == [("monitor/signal", SignalFired(0, 1.5, "SIG_MISSION_TASK_FAIL"))]


def test_a_malformed_payload_is_dropped_and_counted(join) -> None:  # type: ignore[no-untyped-def]
    monitor, sim = join("monitor"), join("simulation")
    inbox = Inbox()
    sim.subscribe(["monitor/signal"], inbox)
    assert monitor.await_readers("monitor/signal", SAFETY)
    key = "rei/v1/monitor/signal"
    for bad in (b"\xff\xfe", b"{not json", b'{"topic":"monitor/signal","seq":0,"time":NaN,'
                b'"name":"X"}', json.dumps({"topic": "sensor/laser", "seq": 0}).encode(),
                b"[" * 100000, b"x" * (4 << 20 | 1)):
        monitor.put(key, bad)
    monitor.publish(SignalFired(0, 2.0, "SIG_OK"))  # after the bad ones, from one session
    assert inbox.wait(1) == [("monitor/signal", SignalFired(0, 2.0, "SIG_OK"))]
    assert sim.dropped == 6
    assert "rei/v1/monitor/signal" in sim.last_drop


def test_a_non_finite_message_is_never_sent(join) -> None:  # type: ignore[no-untyped-def]
    sim = join("simulation")
    with pytest.raises(BusError, match="sensor/odometry: cannot send seq 4"):
        sim.publish(OdometryReading(4, 0.2, (float("nan"), 0.0, 0.0), (0.0, 0.0)))


def test_wrong_or_missing_credentials_are_refused(router: Router, tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    forged = tmp_path / "robot.json"
    real = json.loads((router.bus.path / "robot.json").read_text())
    forged.write_text(json.dumps({**real, "password": "guessed"}))
    forged.chmod(0o600)
    with pytest.raises(BusError, match=r"^the bus at tcp/127\.0\.0\.1:\d+ refused the robot "
                                       r"role's credentials \(user rei-robot\)$"):
        connect(router.bus.endpoint, role="robot", credentials=forged)
    # another role's password for this role's user
    other = json.loads((router.bus.path / "simulation.json").read_text())
    forged.write_text(json.dumps({**real, "password": other["password"]}))
    with pytest.raises(BusError, match="refused the robot role's credentials"):
        connect(router.bus.endpoint, role="robot", credentials=forged)
    with pytest.raises(BusError, match="robot.json: the robot role's credentials expected, "
                                       "found no file"):
        connect(router.bus.endpoint, role="robot", credentials=tmp_path / "empty")
    forged.chmod(0o644)
    with pytest.raises(BusError, match="readable by the owner only expected"):
        connect(router.bus.endpoint, role="robot", credentials=forged)


def test_no_credentials_and_no_bus_say_so(router: Router, monkeypatch: pytest.MonkeyPatch
                                          ) -> None:
    monkeypatch.delenv("REI_BUS_CREDENTIALS", raising=False)
    with pytest.raises(BusError, match="the viewer role needs credentials"):
        connect(router.bus.endpoint, role="viewer")
    monkeypatch.setenv("REI_BUS_CREDENTIALS", str(router.bus.path))
    connect(router.bus.endpoint, role="viewer").close()
    with pytest.raises(BusError, match="an endpoint expected as tcp/HOST:PORT"):
        connect("http://localhost", role="viewer")
    with pytest.raises(BusError, match="a role expected to be one of simulation, robot"):
        connect(router.bus.endpoint, role="admin")


def test_the_bus_folder_is_private(router: Router) -> None:
    assert stat.S_IMODE(router.bus.path.stat().st_mode) == 0o700
    files = sorted(p.name for p in router.bus.path.iterdir())
    assert files == ["mission.json", "monitor.json", "robot.json", "router.json5",
                     "simulation.json", "users.txt", "viewer.json"]
    for path in router.bus.path.iterdir():
        assert stat.S_IMODE(path.stat().st_mode) == 0o600, path
    config = json.loads(router.bus.config.read_text())
    assert config["listen"]["endpoints"] == [router.bus.endpoint]
    assert router.bus.endpoint.startswith("tcp/127.0.0.1:")
    assert config["scouting"]["multicast"]["enabled"] is False
    assert config["access_control"]["default_permission"] == "deny"


def test_a_late_monitor_gets_the_trace_header_from_the_simulation(  # type: ignore[no-untyped-def]
        join, tmp_path: Path) -> None:
    from rei.runtime.bus.distributed_run import TracePublisher
    from rei.runtime.bus.reception import ask_header
    from rei.runtime.bus.schema import TRACE, config_key
    from rei.runtime.trace import TraceDecoder, TraceWriter
    from tests.contracts.test_trace import _header

    sim, monitor = join("simulation"), join("monitor")
    header = _header()
    writer = TraceWriter(tmp_path / "trace.jsonl")
    publisher = TracePublisher(sim, writer)
    inbox = Inbox()
    monitor.subscribe_raw(TRACE, inbox)
    assert sim.await_readers(TRACE, SAFETY)
    writer.start(header)
    try:
        publisher.start(header)
        line = ask_header(monitor.call, config_key("trace"), SAFETY)()
        assert TraceDecoder(line, "asked").header == header
        assert inbox.wait(1)[0][1] == line
    finally:
        writer.finish(0.0, "interrupted", "a test")
