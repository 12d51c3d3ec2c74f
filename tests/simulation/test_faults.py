"""The fault models, measured on real scans of a generated world (issue 17).

Scans come from ``Laser2D`` in examples/simple_wall's generated world, the robot driving from
its start towards the east wall; every statistic (Poisson rate, pulse width, dropout share,
noise sigma, delays) is measured on what the stage delivers, against a confidence band.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rei.lang.errors import LanguageError
from rei.lang.mission.faults import Activation, FaultDefinition
from rei.runtime.artifacts.world import load_manifest
from rei.runtime.errors import RunError
from rei.runtime.messages import LaserScan
from rei.runtime.raycast import scene_shapes
from rei.runtime.simulation.assembly import generate_world
from rei.runtime.simulation.faults import NO_FAULTS, FaultPlan, FaultStage, fault_stage
from rei.runtime.simulation.sensors.laser import Laser2D
from tests.conftest import EXAMPLES


@pytest.fixture(scope="module")
def scans(tmp_path_factory: pytest.TempPathFactory) -> list[LaserScan]:
    """40 real scans along the robot's way from its start to the wall (simple_wall)."""
    out_dir: Path = tmp_path_factory.mktemp("simple_wall")
    generate_world(EXAMPLES / "simple_wall" / "simple_wall.mission", out_dir)
    m = load_manifest(out_dir)
    laser = Laser2D(m.laser, scene_shapes(m, m.objects))
    x0, y0, yaw = m.robot.x, m.robot.y, m.robot.yaw
    out = []
    for i in range(40):
        pose = (x0 + 1.6 * i / 40, y0 + 0.05 * math.sin(i), yaw + 0.1 * math.sin(i / 3))
        out.append(LaserScan(laser.angle_min, laser.angle_increment, m.laser.min_range,
                             m.laser.max_range, laser.scan(pose)))
    return out


def feed(stage: FaultStage, scans: list[LaserScan], seconds: float, scan_dt: float = 0.2,
         tick_dt: float = 0.1) -> Iterator[tuple[float, LaserScan, float, LaserScan | None,
                                                  float | None]]:
    """Drive a stage like the run loop: a control tick every ``tick_dt``, a new scan (a fresh
    object, cycling through ``scans``) every ``scan_dt``. Yields (time, measured, measured_at,
    delivered, delivered stamp) at every tick."""
    ticks = round(seconds / tick_dt)
    per_scan = round(scan_dt / tick_dt)
    measured: LaserScan | None = None
    measured_at: float | None = None
    for k in range(ticks + 1):
        time = k * tick_dt
        if k % per_scan == 0:
            source = scans[(k // per_scan) % len(scans)]
            measured = LaserScan(source.angle_min, source.angle_increment, source.range_min,
                                 source.range_max, source.ranges.copy())
            measured_at = time
        assert measured is not None
        out, stamp = stage.scan(time, measured, measured_at)
        yield time, measured, measured_at, out, stamp  # type: ignore[misc]


def new_scans(stage: FaultStage, scans: list[LaserScan], seconds: float, scan_dt: float = 0.2
              ) -> list[tuple[float, LaserScan, LaserScan | None, float | None]]:
    """(stamp, measured, delivered, delivered stamp) once per measured scan."""
    out = []
    last = None
    for _time, measured, at, delivered, stamp in feed(stage, scans, seconds, scan_dt,
                                                      tick_dt=scan_dt / 2):
        if measured is not last:
            assert at is not None
            out.append((at, measured, delivered, stamp))
            last = measured
    return out


def poisson_counts(rows: list[tuple[float, LaserScan, LaserScan | None, float | None]],
                   gain: float) -> list[tuple[float, int]]:
    """(stamp, k) per scan: k read off the scan as (delivered - previous reading) / gain, on
    beams that stayed inside the scanner's limits (0 when the scan passed unchanged)."""
    out = []
    previous: LaserScan | None = None
    for at, measured, delivered, _ in rows:
        assert delivered is not None
        if delivered is measured:
            out.append((at, 0))
        else:
            assert previous is not None
            inside = delivered.ranges < delivered.range_max - 1e-9
            steps = (delivered.ranges[inside] - previous.ranges[inside]) / gain
            k = int(round(float(np.median(steps))))
            assert np.allclose(steps, k, atol=1e-6), "the same offset on every beam"
            out.append((at, k))
        previous = measured
    return out


# ---- the thesis's laser fault ---------------------------------------------------------------

def test_poisson_occurrences_follow_the_rate(scans: list[LaserScan]) -> None:
    rate, seconds = 3.0, 600.0
    stage = fault_stage([FaultDefinition.of("laser_poisson", rate=rate, gain=0.05)], seed=11)
    counts = poisson_counts(new_scans(stage, scans, seconds), gain=0.05)
    total = sum(k for _, k in counts)
    expected = rate * seconds
    assert abs(total - expected) < 4 * math.sqrt(expected), (total, expected)
    # Per 0.2 s scan interval the count is Poisson(0.6): P(k >= 1) = 1 - e^-0.6.
    share = sum(1 for _, k in counts if k) / (len(counts) - 1)
    p = 1 - math.exp(-rate * 0.2)
    assert abs(share - p) < 4 * math.sqrt(p * (1 - p) / len(counts)), share


@pytest.mark.parametrize("width", [0.01, 0.1])
def test_poisson_counts_only_while_the_impulse_is_high(scans: list[LaserScan],
                                                       width: float) -> None:
    """The thesis's 1 % and 10 % pulse widths: occurrences land only in the pulses, at the
    rate times the pulse width on average."""
    rate, period, seconds, dt = 40.0, 1.0, 400.0, 0.005
    stage = fault_stage([FaultDefinition.of("laser_poisson", rate=rate, gain=0.02,
                                            period=period, width=width)], seed=5)
    counts = poisson_counts(new_scans(stage, scans, seconds, scan_dt=dt), gain=0.02)
    for at, k in counts:
        if k:  # the scan's interval (at - dt, at] overlaps a pulse [n, n + width)
            assert math.fmod(at, period) < width * period + dt + 1e-9, at
    total = sum(k for _, k in counts)
    expected = rate * width * seconds
    assert abs(total - expected) < 4 * math.sqrt(expected), (total, expected)


def test_poisson_adds_to_the_previous_reading_and_a_negative_gain_brings_walls_nearer(
        scans: list[LaserScan]) -> None:
    stage = fault_stage([FaultDefinition.of("laser_poisson", rate=50.0, gain=-0.1)], seed=2)
    rows = new_scans(stage, scans, 10.0)
    changed = [(prev, row) for prev, row in zip(rows, rows[1:], strict=False)
               if row[2] is not row[1]]
    assert len(changed) > 40
    for (_, previous, _, _), (_, _, delivered, _) in changed:
        assert delivered is not None
        assert np.all(delivered.ranges <= previous.ranges)
        assert np.all(delivered.ranges >= delivered.range_min)


def test_poisson_gain_changes_during_the_mission(scans: list[LaserScan]) -> None:
    """Two entries, each with its gain and window: the gain in effect changes at 20 s."""
    stage = fault_stage([
        FaultDefinition.of("laser_poisson", Activation(end=20.0), "low", rate=5.0, gain=0.01),
        FaultDefinition.of("laser_poisson", Activation(start=20.0), "high", rate=5.0,
                           gain=0.5)], seed=1)
    rows = new_scans(stage, scans, 40.0)
    offsets_before: set[int] = set()
    offsets_after: set[int] = set()
    previous = None
    for at, measured, delivered, _ in rows:
        assert delivered is not None
        if delivered is not measured and previous is not None:
            inside = (delivered.ranges < delivered.range_max - 1e-9) & (
                previous.ranges < previous.range_max - 1.0)
            step = float(np.median(delivered.ranges[inside] - previous.ranges[inside]))
            (offsets_before if at <= 20.0 + 1e-9 else offsets_after).add(round(step / 0.01))
        previous = measured
    assert offsets_before and offsets_after
    assert max(offsets_before) < 10 <= min(offsets_after)
    assert stage.timeline() == (("low", 0.0, 20.0), ("high", 20.0, None))


# ---- the other laser faults -----------------------------------------------------------------

def test_dropout_share_of_beams(scans: list[LaserScan]) -> None:
    stage = fault_stage([FaultDefinition.of("laser_dropout", share=0.3)], seed=4)
    dropped = seen = 0
    for _, measured, delivered, _ in new_scans(stage, scans, 40.0):
        assert delivered is not None
        hit = measured.ranges < measured.range_max
        seen += int(hit.sum())
        dropped += int((delivered.ranges[hit] == delivered.range_max).sum())
        assert np.array_equal(delivered.ranges[~hit], measured.ranges[~hit])
        kept = hit & (delivered.ranges < delivered.range_max)
        assert np.array_equal(delivered.ranges[kept], measured.ranges[kept])
    share = dropped / seen
    assert abs(share - 0.3) < 4 * math.sqrt(0.3 * 0.7 / seen), (share, seen)


def test_gaussian_noise_sigma(scans: list[LaserScan]) -> None:
    stage = fault_stage([FaultDefinition.of("laser_noise", sigma=0.02)], seed=8)
    errors = []
    for _, measured, delivered, _ in new_scans(stage, scans, 40.0):
        assert delivered is not None
        inner = (measured.ranges > measured.range_min + 0.2) & (
            measured.ranges < measured.range_max - 0.2)
        errors.append(delivered.ranges[inner] - measured.ranges[inner])
    e = np.concatenate(errors)
    assert len(e) > 5000
    assert abs(float(e.mean())) < 4 * 0.02 / math.sqrt(len(e))
    assert abs(float(e.std()) / 0.02 - 1.0) < 0.03


def test_frozen_scan_from_the_signal_until_the_other(scans: list[LaserScan]) -> None:
    stage = fault_stage([FaultDefinition.of("laser_freeze", Activation(signal="SIG_A",
                                                                       stop="SIG_B"))], seed=0)
    frozen: tuple[LaserScan | None, float | None] | None = None
    had: tuple[LaserScan | None, float | None] = (None, None)
    for time, measured, at, delivered, stamp in feed(stage, scans, 12.0):
        if abs(time - 4.0) < 1e-9:
            had = (delivered, stamp)
            stage.signal(time, "SIG_A")
        if abs(time - 8.0) < 1e-9:
            stage.signal(time, "SIG_B")
        if 4.0 < time < 8.0 - 1e-9:
            frozen = frozen or (delivered, stamp)
            assert (delivered, stamp) == had and delivered is had[0]
        elif time >= 8.2 - 1e-9 or time < 4.0:
            assert delivered is measured and stamp == at
    assert frozen is not None
    assert stage.timeline() == (("laser_freeze", 4.0, 8.0),)


def test_delayed_scan_lags_by_at_least_the_delay(scans: list[LaserScan]) -> None:
    stage = fault_stage([FaultDefinition.of("laser_delay", seconds=0.5)], seed=0)
    lags = []
    for time, _, _, delivered, stamp in feed(stage, scans, 30.0, tick_dt=0.05):
        if time < 0.5 - 1e-9:
            assert delivered is None and stamp is None
            continue
        assert delivered is not None and stamp is not None
        lags.append(time - stamp)
    assert min(lags) >= 0.5 - 1e-9
    assert max(lags) <= 0.5 + 0.2 + 0.05 + 1e-9  # one scan period plus one tick at most


def test_blocked_sector(scans: list[LaserScan]) -> None:
    stage = fault_stage([FaultDefinition.of("laser_sector", min_deg=-30, max_deg=30,
                                            distance=0.3)], seed=0)
    for _, measured, delivered, _ in new_scans(stage, scans, 4.0):
        assert delivered is not None
        bearing = np.degrees(measured.angle_min + measured.angle_increment
                             * np.arange(len(measured.ranges)))
        bearing = (bearing + 180.0) % 360.0 - 180.0
        inside = np.abs(bearing) <= 30.0 + 1e-9
        assert inside.sum() >= 60
        assert np.all(delivered.ranges[inside] == 0.3)
        assert np.array_equal(delivered.ranges[~inside], measured.ranges[~inside])


# ---- odometry ---------------------------------------------------------------------------------

def drive(stage: FaultStage, seconds: float, speed: float = 0.2, dt: float = 0.1,
          signals: dict[float, str] | None = None) -> list[tuple[float, tuple[float, float, float],
                                                             tuple[float, float, float]]]:
    """(time, true pose, reported pose) while the robot drives straight along +x."""
    out = []
    for k in range(round(seconds / dt) + 1):
        t = k * dt
        for at, name in (signals or {}).items():
            if abs(t - at) < 1e-9:
                stage.signal(t, name)
        pose = (1.0 + speed * t, 2.0, 0.0)
        reported, _ = stage.odometry(t, pose, (speed, 0.0))
        out.append((t, pose, reported))
    return out


def test_odometry_jump_once_at_start_and_kept() -> None:
    stage = fault_stage([FaultDefinition.of("odom_jump", Activation(start=2.0), dx=0.3,
                                            dy=-0.2, dyaw=90)], seed=0)
    rows = drive(stage, 6.0)
    for t, pose, reported in rows:
        if t < 2.0 - 1e-9:
            assert reported == pose
    at_jump = next(r for r in rows if r[0] >= 2.0 - 1e-9)
    _, pose, reported = at_jump
    assert reported == pytest.approx((pose[0] + 0.3, pose[1] - 0.2, math.pi / 2))
    _, end_pose, end_reported = rows[-1]
    # It integrates on from the jumped pose: 0.8 m forward is 0.8 m along the turned heading.
    moved = end_pose[0] - pose[0]
    assert end_reported[0] == pytest.approx(reported[0], abs=1e-9)
    assert end_reported[1] - reported[1] == pytest.approx(moved)
    assert stage.timeline() == (("odom_jump", 2.0, None),)


def test_odometry_drift_grows_with_distance() -> None:
    stage = fault_stage([FaultDefinition.of("odom_drift", scale=0.05, yaw_per_metre=2.0)],
                        seed=0)
    rows = drive(stage, 50.0)
    _, pose, reported = rows[-1]
    travelled = pose[0] - 1.0
    assert travelled == pytest.approx(10.0)
    assert reported[2] == pytest.approx(math.radians(2.0) * 10.0, rel=1e-6)
    # Along the drifting heading the reported path is 5 % longer than the true one.
    length = sum(math.dist(a[2][:2], b[2][:2]) for a, b in zip(rows, rows[1:], strict=False))
    assert length == pytest.approx(10.5, rel=1e-6)


def test_odometry_random_walk_grows_with_the_square_root_of_time() -> None:
    finals = []
    for seed in range(300):
        stage = fault_stage([FaultDefinition.of("odom_drift", walk=0.05)], seed=seed)
        _, pose, reported = drive(stage, 16.0, speed=0.0)[-1]
        finals.append((reported[0] - pose[0], reported[1] - pose[1]))
    error = np.array(finals)
    expected = 0.05 * math.sqrt(16.0)
    assert abs(float(error.std()) / expected - 1.0) < 0.1


# ---- commands -------------------------------------------------------------------------------

def test_dropped_commands_keep_the_previous_one() -> None:
    stage = fault_stage([FaultDefinition.of("cmd_drop", share=0.25)], seed=9)
    lost = 0
    delivered_before = (0.0, 0.0)
    n = 4000
    for k in range(n):
        asked = (0.001 * k, -0.001 * k)
        got = stage.command(k * 0.1, asked)
        if got != asked:
            lost += 1
            assert got == delivered_before
        delivered_before = got
    assert abs(lost / n - 0.25) < 4 * math.sqrt(0.25 * 0.75 / n)


def test_delayed_commands() -> None:
    stage = fault_stage([FaultDefinition.of("cmd_delay", seconds=0.3)], seed=0)
    for k in range(100):
        time = k * 0.1
        got = stage.command(time, (float(k), 0.0))
        assert got == ((0.0, 0.0) if k < 3 else (float(k - 3), 0.0))


# ---- activation -------------------------------------------------------------------------------

def test_event_triggered_dropout_for_a_duration_and_retriggered(scans: list[LaserScan]) -> None:
    stage = fault_stage([FaultDefinition.of("laser_dropout", Activation(signal="SIG_CLOSE",
                                                                        duration=2.0),
                                            share=1.0)], seed=0)
    signals = {5.0: "SIG_CLOSE", 6.0: "SIG_CLOSE", 9.0: "SIG_OTHER", 12.0: "SIG_CLOSE"}
    blind = []
    for time, measured, _, delivered, _ in feed(stage, scans, 16.0):
        for at, name in signals.items():
            if abs(time - at) < 1e-9:
                stage.signal(time, name)
        assert delivered is not None
        if delivered is not measured:
            assert np.all(delivered.ranges == delivered.range_max)
            blind.append(round(time, 6))
    # Scans are taken up at the first tick after each is measured (every 0.2 s).
    assert blind == [round(k * 0.1, 6) for k in (*range(52, 80), *range(122, 140))]
    assert stage.timeline() == (("laser_dropout", 5.0, 8.0), ("laser_dropout", 12.0, 14.0))


def test_until_signal_and_open_intervals() -> None:
    stage = fault_stage([
        FaultDefinition.of("cmd_drop", Activation(stop="SIG_STOP"), share=1.0),
        FaultDefinition.of("cmd_delay", Activation(signal="SIG_GO"), seconds=1.0)], seed=0)
    assert stage.timeline() == (("cmd_drop", 0.0, None),)
    stage.command(1.0, (0.1, 0.0))
    stage.signal(2.0, "SIG_GO")
    stage.signal(3.0, "SIG_STOP")
    stage.command(3.5, (0.2, 0.0))
    assert stage.timeline() == (("cmd_drop", 0.0, 3.0), ("cmd_delay", 2.0, None))


# ---- determinism and composition ------------------------------------------------------------

def run_all(seed: int, scans: list[LaserScan], extra: bool = False) -> list[bytes]:
    definitions = [FaultDefinition.of("laser_poisson", rate=4.0, gain=0.1, width=0.5),
                   FaultDefinition.of("laser_dropout", share=0.1),
                   FaultDefinition.of("laser_noise", sigma=0.01),
                   FaultDefinition.of("odom_drift", scale=0.01, walk=0.01),
                   FaultDefinition.of("cmd_drop", share=0.3)]
    if extra:
        definitions.append(FaultDefinition.of("laser_noise", name="more", sigma=0.5,
                                              activation=Activation(start=1e6)))
    stage = fault_stage(definitions, seed)
    out = []
    for time, _, _, delivered, stamp in feed(stage, scans, 10.0):
        pose, twist = stage.odometry(time, (time, 0.0, 0.0), (1.0, 0.0))
        command = stage.command(time, (time, 0.0))
        assert delivered is not None
        out.append(delivered.ranges.tobytes() + repr((stamp, pose, twist, command)).encode())
    return out


def test_same_seed_same_outputs(scans: list[LaserScan]) -> None:
    assert run_all(7, scans) == run_all(7, scans)
    assert run_all(7, scans) != run_all(8, scans)


def test_an_added_fault_shifts_no_other_fault(scans: list[LaserScan]) -> None:
    assert run_all(7, scans) == run_all(7, scans, extra=True)


def test_no_faults_is_the_empty_stage() -> None:
    assert fault_stage([], 3) is NO_FAULTS


def test_duplicate_names_are_refused() -> None:
    with pytest.raises(RunError, match="unique fault names"):
        FaultPlan([FaultDefinition.of("cmd_drop", share=0.1),
                   FaultDefinition.of("cmd_drop", share=0.2)], 0)


@given(kind=st.sampled_from(["laser_dropout", "cmd_drop"]),
       share=st.floats(allow_nan=True, allow_infinity=True))
@settings(max_examples=60, deadline=None)
def test_definitions_reject_what_is_not_a_share(kind: str, share: float) -> None:
    if math.isfinite(share) and 0.0 < share <= 1.0:
        assert FaultDefinition.of(kind, share=share).value("share") == share
    else:
        with pytest.raises(LanguageError, match="share"):
            FaultDefinition.of(kind, share=share)


@given(share=st.floats(0.0, 1.0, exclude_min=True), seed=st.integers(0, 2**63))
@settings(max_examples=30, deadline=None)
def test_dropped_commands_are_always_a_previous_command(share: float, seed: int) -> None:
    stage = fault_stage([FaultDefinition.of("cmd_drop", share=share)], seed)
    asked_so_far = {(0.0, 0.0)}
    for k in range(50):
        asked = (float(k), 0.0)
        asked_so_far.add(asked)
        assert stage.command(k * 0.1, asked) in asked_so_far


def test_statistics_count_what_each_fault_did(scans: list[LaserScan]) -> None:
    stage = FaultPlan([FaultDefinition.of("laser_poisson", rate=3.0, gain=0.05),
                       FaultDefinition.of("laser_dropout", share=0.5),
                       FaultDefinition.of("cmd_drop", share=0.5),
                       FaultDefinition.of("odom_jump", Activation(start=1.0), dx=1.0)], seed=3)
    for time, measured, _, delivered, _ in feed(stage, scans, 20.0, tick_dt=0.2):
        stage.command(time, (time, 0.0))
        stage.odometry(time, (0.0, 0.0, 0.0), (0.0, 0.0))
        assert delivered is not None and delivered is not measured  # half the beams drop
    stats = {s.name: dict(s.counts) for s in stage.statistics()}
    assert stats["laser_poisson"]["corrupted"] >= 1
    assert stats["laser_poisson"]["occurrences"] >= stats["laser_poisson"]["corrupted"]
    assert stats["laser_dropout"]["beams"] == 101 * len(scans[0].ranges)
    assert stats["cmd_drop"]["asked"] == 101 and 0 < stats["cmd_drop"]["lost"] < 101
    assert stats["odom_jump"] == {"jumps": 1}


def test_the_impulse_starts_with_an_event_triggered_fault(scans: list[LaserScan]) -> None:
    """Pulses are timed from the moment the signal fired, not from the start of the run."""
    dt = 0.01
    stage = fault_stage([FaultDefinition.of("laser_poisson", Activation(signal="SIG_A"),
                                            rate=400.0, gain=0.01, period=1.0, width=0.1)],
                        seed=6)
    fired = 3.37
    rows: list[tuple[float, LaserScan, LaserScan | None, float | None]] = []
    last = None
    for time, measured, at, delivered, _ in feed(stage, scans, 12.0, scan_dt=dt, tick_dt=dt):
        if abs(time - fired) < 1e-9:
            stage.signal(time, "SIG_A")
        if measured is not last:
            assert at is not None
            rows.append((at, measured, delivered, None))
            last = measured
    counts = poisson_counts(rows, gain=0.01)
    hit = [at for at, k in counts if k]
    assert hit and min(hit) > fired
    for at in hit:
        assert math.fmod(at - fired + 1e-9, 1.0) < 0.1 + dt + 2e-9, at
    # Every pulse after the signal (8 whole ones) shows occurrences: 400/s x 0.1 s = 40 each.
    assert {math.floor(at - fired + 1e-9) for at in hit} == set(range(9))


@given(st.lists(st.tuples(st.floats(0.0, 50.0), st.sampled_from(["SIG_A", "SIG_B", "X"])),
                max_size=12),
       st.sampled_from([Activation(signal="SIG_A", duration=3.0),
                        Activation(signal="SIG_A", stop="SIG_B"),
                        Activation(signal="SIG_A"), Activation(stop="SIG_B"),
                        Activation(start=10.0, end=30.0)]))
@settings(max_examples=150, deadline=None)
def test_activation_follows_the_signals(events: list[tuple[float, str]],
                                        activation: Activation) -> None:
    """Against a tick-by-tick reference: active at t exactly when the definition says."""
    events.sort()
    stage = FaultPlan([FaultDefinition.of("laser_freeze", activation)], seed=0)
    tracker = stage.trackers[0]
    for time, name in events:
        stage.signal(time, name)
    for k in range(601):
        t = k * 0.1
        before = [(time, name) for time, name in events if time <= t]
        if activation.signal is None:
            stopped = any(name == "SIG_B" for _, name in before) and activation.stop
            expected = (activation.start <= t and (activation.end is None or t < activation.end)
                        and not stopped)
        else:
            starts = [time for time, name in before if name == "SIG_A"]
            stops = [time for time, name in before if name == "SIG_B"]
            if activation.duration is not None:
                expected = any(t < s + activation.duration for s in starts)
            elif activation.stop is not None:
                expected = bool(starts) and (not stops or max(starts) > max(stops)) \
                    if starts else False
            else:
                expected = bool(starts)
        assert tracker.active(t) == bool(expected), (t, events)
    for name, start, end in stage.timeline():
        assert name == "laser_freeze" and (end is None or end > start)


def test_every_kind_reports_its_statistics() -> None:
    """A laser_sector run ended in an internal error while writing its summary: the
    statistics took the model's ``beams`` method for a counter (int() of a method)."""
    definitions = [FaultDefinition.of("laser_sector", min_deg=-30.0, max_deg=30.0),
                   FaultDefinition.of("laser_dropout", name="drop", share=0.5)]
    stage = FaultPlan(definitions, seed=0)
    assert [(s.name, s.counts) for s in stage.statistics()] == [
        ("laser_sector", ()), ("drop", (("dropped", 0), ("beams", 0)))]
