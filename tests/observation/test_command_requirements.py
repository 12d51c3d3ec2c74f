"""The requirements on the commands themselves (issue 40): COMMAND_ACCELERATION (within the
drive's acceleration limits, with accel_margin), COMMAND_CHATTER (no flip and back within
500 ms) and COMMAND_AT_REST (nothing commanded from rest_after into the settle period). Each
is shown failing on a stream that breaks it, passing on one that does not, and not
applicable where its premise never held; the rates are pinned down on the tracker itself,
for commands slower than the samples and for a replay's irregular stamps."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from rei.runtime.observation.model.commands import CommandTracker
from tests.observation.test_default_requirements import FAR_WALL, Tick, facts, run

LIMITS = dataclasses.replace(facts(), accel_limit=2.5, decel_limit=2.5, turn_accel_limit=3.2,
                             turn_decel_limit=3.2)


def commanded(cmds: list[tuple[float, float]]) -> list[Tick]:
    """The robot standing at the origin while it commands ``cmds``, one per 0.1 s sample
    (its motion is not what these requirements read)."""
    return [Tick((0.0, 0.0, 0.0), cmd=c) for c in cmds]


def ramp(top: float, step: float) -> list[tuple[float, float]]:
    n = round(top / step)
    up = [(step * i, 0.0) for i in range(n + 1)]
    return [(0.0, 0.0)] + up + [(top, 0.0)] * 5 + up[::-1] + [(0.0, 0.0)] * 3


def test_commands_within_the_limits_pass_and_a_jump_fails(tmp_path: Path) -> None:
    # 0.2 m/s per 0.1 s tick is 2.0 m/s^2, under the waffle's 2.5
    verdicts, _ = run(tmp_path / "ramp", FAR_WALL, commanded(ramp(0.26, 0.02)), LIMITS)
    assert verdicts["COMMAND_ACCELERATION"].status == "pass"
    assert verdicts["COMMAND_ACCELERATION"].margin is not None
    assert verdicts["COMMAND_ACCELERATION"].margin > 0
    # a stop from full speed in one tick (2.6 m/s^2) is within the 25 % margin
    stop = [(0.0, 0.0)] + [(0.02 * i, 0.0) for i in range(14)] + [(0.26, 0.0), (0.0, 0.0)] * 1
    verdicts, _ = run(tmp_path / "stop", FAR_WALL, commanded(stop + [(0.0, 0.0)] * 3), LIMITS)
    assert verdicts["COMMAND_ACCELERATION"].status == "pass"
    # a turn dropped from 1.09 rad/s to nothing in one tick: 10.9 rad/s^2 against 3.2
    turn = [(0.0, 0.3 * i) for i in range(4)] + [(0.0, 1.09)] * 5 + [(0.0, 0.0)] * 3
    verdicts, _ = run(tmp_path / "turn", FAR_WALL, commanded(turn), LIMITS)
    assert verdicts["COMMAND_ACCELERATION"].status == "fail"
    assert verdicts["COMMAND_ACCELERATION"].margin is not None
    assert verdicts["COMMAND_ACCELERATION"].margin < 0


def test_limits_the_stream_does_not_carry_judge_nothing(tmp_path: Path) -> None:
    # a trace recorded before the limits were in the header: no limit, no failure
    turn = [(0.0, 0.0)] + [(0.0, 1.09)] * 5 + [(0.0, 0.0)] * 3
    verdicts, _ = run(tmp_path, FAR_WALL, commanded(turn), facts())
    assert verdicts["COMMAND_ACCELERATION"].status == "pass"
    assert verdicts["COMMAND_ACCELERATION"].margin is None


def test_a_command_that_flips_back_and_forth_chatters(tmp_path: Path) -> None:
    flips = [(0.1, 0.4), (0.1, -0.4), (0.1, 0.4)]
    verdicts, _ = run(tmp_path / "flips", FAR_WALL,
                      commanded([(0.1, 0.0)] * 3 + flips + [(0.1, 0.0)] * 3), LIMITS)
    assert verdicts["COMMAND_CHATTER"].status == "fail"
    forward_back = [(0.1, 0.0), (-0.1, 0.0), (-0.1, 0.0), (0.1, 0.0)]
    verdicts, _ = run(tmp_path / "drive", FAR_WALL,
                      commanded([(0.0, 0.0)] * 3 + forward_back + [(0.0, 0.0)] * 3), LIMITS)
    assert verdicts["COMMAND_CHATTER"].status == "fail"
    # one reversal is a correction, not chatter; so is a slow back and forth (weaving's)
    once = [(0.1, 0.4)] * 3 + [(0.1, -0.4)] * 3 + [(0.1, 0.0)] * 3
    slow = [(0.1, 0.4)] * 4 + [(0.1, -0.4)] * 4 + [(0.1, 0.4)] * 4
    for name, cmds in (("once", once), ("slow", slow)):
        verdicts, _ = run(tmp_path / name, FAR_WALL, commanded([(0.1, 0.0)] + cmds), LIMITS)
        assert verdicts["COMMAND_CHATTER"].status == "pass", name
    # small flips about nothing (within chatter_turn) are no direction at all
    noise = [(0.1, 0.05 * (-1) ** i) for i in range(10)]
    verdicts, _ = run(tmp_path / "noise", FAR_WALL, commanded(noise), LIMITS)
    assert verdicts["COMMAND_CHATTER"].status == "pass"


def test_a_robot_that_never_commands_motion_is_not_judged_on_it(tmp_path: Path) -> None:
    verdicts, _ = run(tmp_path, FAR_WALL, commanded([(0.0, 0.0)] * 12), LIMITS)
    assert verdicts["COMMAND_ACCELERATION"].status == "not_applicable"
    assert verdicts["COMMAND_CHATTER"].status == "not_applicable"


def settling(tmp: Path, after: list[tuple[float, float]]):  # type: ignore[no-untyped-def]
    """One task that succeeds at t = 1.0 s, then ``after`` commanded (the settle period)."""
    from rei.runtime.messages import MissionEvent
    from tests.observation.helpers import monitor
    from tests.observation.test_default_requirements import stream

    ticks = commanded([(0.1, 0.0)] * 10 + [(0.0, 0.0)] + after)
    events = {0: (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g0", 0)),
              10: (MissionEvent("task_success", 1.0, "g0", 0),),
              len(ticks) - 1: (MissionEvent("end", (len(ticks) - 1) / 10),)}
    ticks = [dataclasses.replace(t, events=events.get(i, ())) for i, t in enumerate(ticks)]
    h, samples = stream(FAR_WALL, ticks, LIMITS)
    _, result = monitor(h, samples, tmp)
    return {v.requirement: v for v in result.verdicts}


def test_a_robot_commanding_motion_once_settled_fails(tmp_path: Path) -> None:
    still = settling(tmp_path / "still", [(0.0, 0.0)] * 30)
    assert still["COMMAND_AT_REST"].status == "pass"
    assert still["COMMAND_AT_REST"].margin == pytest.approx(0.001)
    # a navigator that keeps turning on the spot after its last goal: SETTLE (travel) does
    # not see it, this does
    turning = settling(tmp_path / "turning", [(0.0, 0.0)] * 5 + [(0.0, 0.3)] * 25)
    assert turning["COMMAND_AT_REST"].status == "fail"
    assert turning["SETTLE"].status == "pass"
    # braking within rest_after is allowed
    braking = settling(tmp_path / "braking", [(0.0, 0.3), (0.0, 0.1)] + [(0.0, 0.0)] * 28)
    assert braking["COMMAND_AT_REST"].status == "pass"


def test_a_run_that_never_settles_is_not_judged_at_rest(tmp_path: Path) -> None:
    verdicts, _ = run(tmp_path, FAR_WALL, commanded([(0.1, 0.0)] * 12), LIMITS)
    assert verdicts["COMMAND_AT_REST"].status == "not_applicable"


# ---- the rates, on the tracker -------------------------------------------------------------

def test_a_held_command_dropped_at_once_is_dropped_within_one_period() -> None:
    t = CommandTracker()
    times = [0.1 * i for i in range(60)]
    cmds = [(0.0, 0.0), (0.1, 0.0), (0.2, 0.0)] + [(0.26, 0.0)] * 56 + [(0.0, 0.0)]
    rates = [t.observe(time, cmd) for time, cmd in zip(times, cmds, strict=True)]
    assert rates[2].accel == pytest.approx(1.0)
    # held for 5.6 s, then stopped within one control period: 2.6 m/s^2, not 0.05
    assert rates[-1].decel == pytest.approx(2.6)
    assert rates[-1].accel == 0.0


def test_samples_faster_than_the_commands_divide_by_the_commands_period() -> None:
    # physics-rate samples (100 Hz) of a 10 Hz controller ramping at 1 m/s^2
    t = CommandTracker()
    seen = []
    for k in range(100):
        time = 0.01 * k
        seen.append(t.observe(time, (0.1 * (k // 10), 0.0)).accel)
    assert max(seen[30:]) == pytest.approx(1.0)


def test_irregular_stamps_never_divide_by_nothing() -> None:
    t = CommandTracker()
    t.observe(0.0, (0.0, 0.0))
    t.observe(0.1, (0.1, 0.0))
    rate = t.observe(0.1, (0.2, 0.0))  # a replayed bag's two stamps the same
    assert rate.accel < 1e3
    # a reversal is a deceleration (Nav2's smoother decides it so)
    assert t.observe(0.2, (-0.1, 0.0)).decel == pytest.approx(3.0)
