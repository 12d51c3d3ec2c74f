"""The settle period: after its last goal the mission goes on (the .mission's ``settle``,
default 3 s) and SETTLE fails a robot that does not stay where it ended its last task — a
navigator that never sends a stop, or drifts off after reporting success — and passes one
that stops, and one a person shoves (its own motion is what counts).

Synthetic streams pin the rule down; the real simulator shows the default period, the
reference navigator passing and a navigator that keeps its last command failing.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rei.lang.errors import LanguageError
from rei.lang.mission.model import DEFAULT_SETTLE
from rei.lang.workspace import load_mission
from rei.runtime.messages import MissionEvent
from tests.observation.helpers import monitor
from tests.observation.streams import human, wall
from tests.observation.test_default_requirements import Tick
from tests.observation.test_default_requirements import stream as make_stream

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
REPO = Path(__file__).resolve().parents[2]


def _settling(tmp: Path, after: list[Tick], placed=None):  # type: ignore[no-untyped-def]
    """One task that succeeds at t = 1.0 s, then ``after`` (the settle period), then the end."""
    ticks = [Tick((0.02 * i, 0.0, 0.0), (0.2, 0.0, 0.0), (0.2, 0.0)) for i in range(10)]
    ticks.append(Tick((0.2, 0.0, 0.0)))
    ticks += after
    events = {0: (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g0", 0)),
              10: (MissionEvent("task_success", 1.0, "g0", 0),),
              len(ticks) - 1: (MissionEvent("end", (len(ticks) - 1) / 10),)}
    ticks = [Tick(t.pose, t.twist, t.cmd, t.objects, events.get(i, ()), t.contacts)
             for i, t in enumerate(ticks)]
    h, samples = make_stream(placed or [wall("w", 5.0, 0.0)], ticks)
    _, result = monitor(h, samples, tmp)
    return {v.requirement: v for v in result.verdicts}, result


def test_a_robot_that_stays_put_after_its_last_goal_passes(tmp_path: Path) -> None:
    verdicts, result = _settling(tmp_path, [Tick((0.2, 0.0, 0.0))] * 30)
    assert verdicts["SETTLE"].status == "pass"
    assert result.measurements["settle_travel"] == 0.0


def test_a_robot_that_keeps_driving_after_its_last_goal_fails(tmp_path: Path) -> None:
    # it never sent a stop: the base keeps the last command, 0.1 m/s for 3 s
    keeps = [Tick((0.2 + 0.01 * i, 0.0, 0.0), (0.1, 0.0, 0.0), (0.1, 0.0)) for i in range(30)]
    verdicts, result = _settling(tmp_path, keeps)
    assert verdicts["SETTLE"].status == "fail"
    assert verdicts["SETTLE"].decided_at is not None and verdicts["SETTLE"].decided_at > 1.0
    assert result.measurements["settle_travel"] > 0.1


def test_a_robot_shoved_after_its_last_goal_is_not_blamed(tmp_path: Path) -> None:
    shoved = [Tick((0.2 - 0.05 * i, 0.0, 0.0), (-0.5, 0.0, 0.0), (0.0, 0.0),
                   objects=((0.2 - 0.05 * i + 0.3, 0.0, 0.0),), contacts=(0,))
              for i in range(10)]
    still = [Tick((-0.25, 0.0, 0.0), objects=((1.5, 0.0, 0.0),))] * 20
    verdicts, _ = _settling(tmp_path, shoved + still, [human("bob", 1.5, 0.0)])
    assert verdicts["SETTLE"].status == "pass"


def test_the_settle_period_is_declared_in_the_mission_with_a_default(tmp_path: Path) -> None:
    room = EXAMPLES / "simple_wall" / "simple_wall.room"
    text = (EXAMPLES / "simple_wall" / "simple_wall.mission").read_text()
    assert load_mission(EXAMPLES / "simple_wall" / "simple_wall.mission").mission.settle \
        == DEFAULT_SETTLE == 3.0
    (tmp_path / room.name).write_text(room.read_text())
    longer = tmp_path / "longer.mission"
    longer.write_text(text.replace("{", "{\n    settle 5", 1))
    doc = load_mission(longer)
    assert doc.ok and doc.mission is not None and doc.mission.settle == 5.0
    bad = tmp_path / "bad.mission"
    bad.write_text(text.replace("{", "{\n    settle -1", 1))
    with pytest.raises(LanguageError, match=r"bad.mission:\d+:5: NUM-RANGE: settle \(seconds\): "
                       r"expected a number >= 0 and <= 1e\+06, found -1"):
        load_mission(bad)


NEVER_STOPS = """
from rei.runtime.messages import NavState
from rei.runtime.robot.contract import VelocityCommand
from rei.runtime.robot.navigator.reference import ReferenceNavigator


class NeverStops(ReferenceNavigator):
    \"\"\"Reports success as the reference does, but never sends a stop: after its goal the
    base keeps its last moving command.\"\"\"

    def reset(self, context):
        super().reset(context)
        self._last = VelocityCommand(0.0, 0.0)

    def step(self, observation):
        command = super().step(observation)
        if command.linear != 0.0 or command.angular != 0.0:
            self._last = command
        return self._last
"""


def _run(tmp: Path, controller: str) -> dict[str, object]:
    (tmp / "nav").mkdir(parents=True)
    (tmp / "nav" / "never_stops.py").write_text(NEVER_STOPS)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp / "nav"), str(REPO)])}
    subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run",
                    str(EXAMPLES / "simple_wall" / "simple_wall.mission"), "-o",
                    str(tmp / "out"), "--controller", controller, "-q"],
                   capture_output=True, text=True, env=env, timeout=600, check=False)
    summary: dict[str, object] = json.loads((tmp / "out" / "summary.json").read_text())
    return summary


@pytest.mark.slow
def test_the_reference_settles_and_a_navigator_that_never_stops_does_not(tmp_path: Path
                                                                          ) -> None:
    reference = _run(tmp_path / "reference", "reference")
    verdicts = {v["requirement"]: v["status"] for v in reference["verdicts"]}  # type: ignore[union-attr]
    assert verdicts["SETTLE"] == "pass" and reference["verdict"] == "pass"
    # the run lasts the settle period longer than the last goal's end
    goals = reference["measurements"]["time_to_goal"]  # type: ignore[index]
    assert reference["duration"] == pytest.approx(goals[-1]["ended"] + DEFAULT_SETTLE, abs=0.11)
    moving = _run(tmp_path / "never", "never_stops:NeverStops")
    verdicts = {v["requirement"]: v["status"] for v in moving["verdicts"]}  # type: ignore[union-attr]
    assert verdicts["SETTLE"] == "fail"
    assert verdicts["MISSION_GOALS_REACHED"] == "pass"  # every goal was reached all the same
