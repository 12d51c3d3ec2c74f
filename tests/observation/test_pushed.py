"""Motion the robot did not command: a body that walks into a standing robot shoves it, and
requirements on driven motion (SPEED_LIMIT as driven, HUMAN_SLOW_ZONE, SMOOTH_MOTION) judge the
robot's own motion, so the shove is recorded (SIG_ROBOT_PUSHED, measurements["pushed"]) and
not blamed; the robot driving into a person is still its fault.

Synthetic streams pin the rule down sample by sample; the real simulator shows it on a scripted
person walking into a robot that commands (0, 0), and on a robot pushing into a person.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rei.runtime.observation.model.pushes import PushTracker
from tests.observation.streams import human
from tests.observation.test_default_requirements import Tick, run
from tests.simulation.test_humans import ROOM as HUMANS_ROOM

REPO = Path(__file__).resolve().parents[2]

# ---- the rule, sample by sample ------------------------------------------------------------


def _update(tracker: PushTracker, speed: float, cmd: tuple[float, float], touching: bool,
            approach: float = 0.0, yaw_rate: float = 0.0) -> tuple[float, float, bool]:
    own = tracker.update(speed, yaw_rate, cmd, np.array([touching]), np.array([approach]))
    return own.speed, own.yaw_rate, own.pushed


def test_a_shove_is_capped_at_the_command_until_the_robot_is_back_within_it() -> None:
    t = PushTracker()
    assert _update(t, 0.0, (0.0, 0.0), touching=False) == (0.0, 0.0, False)
    # a person walks into the standing robot: its speed is the shove's, not its own
    assert _update(t, 0.9, (0.0, 0.0), touching=True, yaw_rate=-0.5) == (0.0, 0.0, True)
    # the contact is over, the shove's momentum is not
    assert _update(t, 0.4, (0.1, 0.0), touching=False) == (0.1, 0.0, True)
    # back within its command: its own motion again, whatever comes next
    assert _update(t, 0.1, (0.1, 0.0), touching=False) == (0.1, 0.0, False)
    assert _update(t, 0.3, (0.1, 0.0), touching=False) == (0.3, 0.0, False)


def test_a_contact_the_robot_drives_into_is_no_push() -> None:
    t = PushTracker()
    assert _update(t, 0.6, (0.3, 0.0), touching=True, approach=0.3) == (0.6, 0.0, False)
    # commanding too fast while being pushed: it answers for its command
    t = PushTracker()
    assert _update(t, 0.9, (0.3, 0.2), touching=True, yaw_rate=0.8) == (0.3, 0.2, True)


# ---- the default requirements on synthetic streams -----------------------------------------

def _walks_in(robot_speed: float, cmd: float) -> list[Tick]:
    """bob walks in from +x until he touches the robot's front, then keeps shoving it along
    -x for a second at 0.9 m/s (the robot's command: ``cmd``)."""
    ticks = [Tick((0.0, 0.0, 0.0), objects=((2.0 - 1.7 * i / 9, 0.0, 0.0),))
             for i in range(10)]
    for i in range(10):
        x = -0.09 * (i + 1)
        ticks.append(Tick((x, 0.0, 0.0), (-robot_speed, 0.0, 0.4 * (-1) ** i), (cmd, 0.0),
                          objects=((x + 0.3, 0.0, 0.0),), contacts=(0,)))
    ticks += [Tick((-0.9, 0.0, 0.0), objects=((-0.6, 0.0, 0.0),))] * 3
    return ticks


def test_a_person_shoving_a_standing_robot_is_recorded_not_blamed(tmp_path: Path) -> None:
    verdicts, result = run(tmp_path, [human("bob", 2.0, 0.0)], _walks_in(0.9, 0.0))
    for requirement in ("SPEED_LIMIT", "HUMAN_SLOW_ZONE", "SMOOTH_MOTION", "NO_ROBOT_COLLISION"):
        assert verdicts[requirement].status == "pass", verdicts[requirement]
    assert result.signal_counts["SIG_ROBOT_PUSHED"] == 1
    assert result.signal_counts["SIG_HUMAN_WALKED_INTO_ROBOT"] == 1
    assert result.measurements["pushed"]["top_speed"] == pytest.approx(0.9)
    assert result.measurements["pushed"]["seconds"] == pytest.approx(1.0)  # 10 samples


def test_a_robot_pushing_into_a_person_fails(tmp_path: Path) -> None:
    # the robot drives into bob at 0.3 m/s and pushes him along: its own doing
    ticks = [Tick((0.03 * i, 0.0, 0.0), (0.3, 0.0, 0.0), (0.3, 0.0),
                  objects=((0.7 + max(0.0, 0.03 * (i - 5)), 0.0, 0.0),),
                  contacts=(0,) if i >= 5 else ()) for i in range(15)]
    verdicts, result = run(tmp_path, [human("bob", 0.7, 0.0)], ticks)
    assert verdicts["HUMAN_SLOW_ZONE"].status == "fail"
    assert verdicts["NO_ROBOT_COLLISION"].status == "fail"
    assert result.signal_counts["SIG_ROBOT_PUSHED"] == 0


# ---- the real simulator ----------------------------------------------------------------------

WALKER = "on g_2_1 trajectory stop { g_2_1 at 0  g_2_9 at 8 }BEHAVIOUR"
ROOM = HUMANS_ROOM.replace(WALKER, "PERSON")  # test_humans' corridor, the walker's line apart
WALKS_IN = WALKER.replace("BEHAVIOUR", "")  # scripted: it walks on through the robot
STANDS = "on g_2_7"
MISSION = """mission stand in "corridor.room" {
    goal here at g_2_5 tolerance 0.3 timeout 5
    goal there at g_2_8 tolerance 0.3 timeout 14
}
"""
CONTROLLERS = """
from rei.runtime.robot.contract import VelocityCommand
from rei.runtime.robot.navigator.reference import ReferenceNavigator


class Stands(ReferenceNavigator):
    \"\"\"Accepts the goal and commands (0, 0) throughout.\"\"\"

    def step(self, observation):
        super().step(observation)
        return VelocityCommand(0.0, 0.0)


class Pushes(ReferenceNavigator):
    \"\"\"Accepts the goal and drives straight ahead at 0.2 m/s, whatever is in the way.\"\"\"

    def step(self, observation):
        super().step(observation)
        return VelocityCommand(0.2, 0.0)
"""


def _rei_run(folder: Path, person: str, controller: str) -> dict[str, object]:
    folder.mkdir(parents=True)
    (folder / "corridor.room").write_text(ROOM.replace("PERSON", person))
    (folder / "stand.mission").write_text(MISSION)
    (folder / "pushers.py").write_text(CONTROLLERS)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(folder), str(REPO)])}
    done = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run",
                           str(folder / "stand.mission"), "-o", str(folder / "out"),
                           "--controller", f"pushers:{controller}", "--no-variation"],
                          capture_output=True, text=True, env=env, cwd=folder, timeout=600)
    assert done.returncode == 1, done.stderr  # the goal times out either way
    summary: dict[str, object] = json.loads((folder / "out" / "summary.json").read_text())
    return summary


def _statuses(summary: dict[str, object]) -> dict[str, str]:
    verdicts = summary["verdicts"]
    assert isinstance(verdicts, list)
    return {v["requirement"]: v["status"] for v in verdicts}


@pytest.mark.slow
def test_a_scripted_person_shoving_a_standing_robot_in_the_simulator(tmp_path: Path) -> None:
    summary = _rei_run(tmp_path / "shoved", WALKS_IN, "Stands")
    status = _statuses(summary)
    assert status["SPEED_LIMIT"] == "pass"
    assert status["HUMAN_SLOW_ZONE"] == "pass"
    assert status["SMOOTH_MOTION"] == "pass"
    assert status["NO_ROBOT_COLLISION"] == "pass"
    counts = summary["signal_counts"]
    assert isinstance(counts, dict)
    assert counts["SIG_ROBOT_PUSHED"] >= 1 and counts["SIG_HUMAN_WALKED_INTO_ROBOT"] >= 1
    measurements = summary["measurements"]
    assert isinstance(measurements, dict)
    assert measurements["pushed"]["top_speed"] > 0.5  # shoved well past the slow zone's 0.15


@pytest.mark.slow
def test_a_robot_pushing_into_a_standing_person_in_the_simulator_fails(tmp_path: Path) -> None:
    summary = _rei_run(tmp_path / "pushing", STANDS, "Pushes")
    status = _statuses(summary)
    assert status["HUMAN_SLOW_ZONE"] == "fail"
    assert status["NO_ROBOT_COLLISION"] == "fail"
    counts = summary["signal_counts"]
    assert isinstance(counts, dict)
    assert counts["SIG_ROBOT_PUSHED"] == 0
