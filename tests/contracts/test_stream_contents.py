"""What a run puts in the stream for requirements: every body the robot touched (also between
two samples) in the next sample's ``contacts``, the controller's raw command, the mission's
facts in the header and the cause of every failed task, in pybullet, not mocked."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

from rei.runtime.artifacts.monitor_config import load_monitor_config
from rei.runtime.artifacts.world import load_manifest
from rei.runtime.messages.sink import SampleList
from rei.runtime.observation.model.geometry import FootprintSet
from rei.runtime.observation.model.runtime_model import RuntimeModel
from rei.runtime.robot import Controller
from rei.runtime.runs.session import run_into
from rei.runtime.simulation.assembly import LoopRecord, RunConfig, generate_world, run_mission
from rei.runtime.trace import read_trace
from tests.robot.scripted import Ram

EPS_COLLISION = 0.02
"""default.vepl's ε_collision."""

LANE = """room ram_{kind} {{
    tile 1.0
    grid lane {{
        legend {{ "R" = floor start }}
        "#####"
        "#R..#"
        "#####"
    }}
    robot waffle : turtlebot3_waffle on start heading 0
    {body}
}}
"""
BODIES = {
    # The robot starts at x = 0 facing +x; the east wall's face is at x = 2.5, a body on
    # lane_1_3 stands at x = 2 with its face at 1.8 (box, pillar) or 1.7 (cart).
    "wall": ("lane_1_4", ""),
    "box": ("crate", "object crate : box on lane_1_3"),
    "pillar": ("post", "object post : pillar on lane_1_3"),
    "human": ("person", "human person on lane_1_3 trajectory total 8 { lane_1_3 lane_1_2 }"),
    "dynamic": ("trolley", "dynamic trolley : cart on lane_1_3"),
}


def _lane(folder: Path, kind: str, goals: str = "goal a at start\n    goal b at lane_1_2"
          ) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "lane.room").write_text(LANE.format(kind=kind, body=BODIES[kind][1]),
                                      encoding="utf-8")
    mission = folder / "lane.mission"
    mission.write_text(f'mission ram in "lane.room" {{\n    {goals}\n}}\n', encoding="utf-8")
    return mission


def _run(mission_path: Path, controller: Controller, config: RunConfig,
         monitor_rate: float | None = None) -> tuple[SampleList, LoopRecord]:
    """Run in-process (the control rate and the sample rate are the test's to choose)."""
    world = mission_path.parent / "world"
    mission = generate_world(mission_path, world)
    monitor = load_monitor_config(world)
    if monitor_rate is not None:
        monitor = replace(monitor, rate=monitor_rate)
    sink = SampleList()
    # the exact declared scene: these tests place the robot to the millimetre
    config = replace(config, jitter=None, vary=False)
    record = run_mission(mission, load_manifest(world), monitor, controller, [sink], config)
    return sink, record


@pytest.mark.parametrize("kind", list(BODIES))
def test_driving_into_a_body_shows_its_contact_and_a_monitor_collision(kind: str,
                                                                      tmp_path: Path) -> None:
    sink, record = _run(_lane(tmp_path, kind), Ram(0.2), RunConfig(duration=13.0,
                                                                    watchdog=None))
    header = sink.header
    assert header is not None
    name = BODIES[kind][0]
    index = [o.name for o in header.objects].index(name)
    assert record.measurements["collided_with"] == [name]
    touching = [s for s in sink.samples if s.contacts]
    assert touching and all(s.contacts == (index,) for s in touching)
    model = RuntimeModel(header)
    footprints = FootprintSet.build(header.robot.footprint,
                                    [o.footprint for o in header.objects], header.tile_size)
    for s in sink.samples:
        distance = model.observe(s).distance
        if s.contacts:
            assert distance[index] <= 0.0, s.time
            # The footprints agree with the pybullet bodies: held against the body, the
            # footprint distance alone is a collision too (within ε_collision).
            assert footprints.distances(s.robot_pose, s.poses)[index] < EPS_COLLISION, s.time


def test_a_touch_between_two_samples_is_in_the_next_sample(tmp_path: Path) -> None:
    # Exact odometry and control at the physics rate: the robot backs off the step after it
    # touches the wall at x = 2.3595 (its front at the face, 2.5); samples come every 0.5 s.
    sink, record = _run(_lane(tmp_path, "wall"), Ram(0.26, bounce_at=2.359),
                        RunConfig(duration=12.0, watchdog=None, control_rate=100.0),
                        monitor_rate=2.0)
    header = sink.header
    assert header is not None
    wall = [o.name for o in header.objects].index("lane_1_4")
    first = record.measurements["first_collision"]
    assert first is not None and record.measurements["collisions"] == 1
    [touched] = [s for s in sink.samples if s.contacts]
    assert touched.contacts == (wall,) and touched.time - 0.5 < first <= touched.time
    footprints = FootprintSet.build(header.robot.footprint,
                                    [o.footprint for o in header.objects], header.tile_size)
    # By the sample the robot is well away: the sampled footprints alone miss the collision…
    assert footprints.distances(touched.robot_pose, touched.poses)[wall] > 5 * EPS_COLLISION
    # …but the monitor does not.
    assert RuntimeModel(header).observe(touched).distance[wall] == 0.0


def test_the_raw_command_is_recorded_before_the_drive_clips_it(tmp_path: Path) -> None:
    sink, _ = _run(_lane(tmp_path, "wall"), Ram(2.0), RunConfig(duration=2.0, watchdog=None))
    header = sink.header
    assert header is not None and header.mission_facts is not None
    limit = header.mission_facts.speed_limit
    moving = sink.samples[5:]
    assert all(s.belief.cmd == (2.0, 0.0) for s in moving)
    assert all(math.hypot(*s.robot_twist[:2]) <= limit + 1e-6 for s in moving)
    assert sink.samples[0].belief.cmd == (2.0, 0.0)  # the command of the sample's own tick


def test_a_wrong_heading_fails_the_task_with_cause_heading(tmp_path: Path) -> None:
    # ClaimsSuccess claims every goal at once, without moving, facing 0°.
    mission = _lane(tmp_path, "wall",
                    "max_speed 0.2\n    time_limit 50\n    cycles 2\n"
                    "    goal wrong at start heading 90\n"
                    "    goal near at start heading 10\n"
                    "    goal wide at start heading -40 heading_tolerance 45\n"
                    "    goal far at lane_1_2")
    summary, _ = run_into(mission, tmp_path / "out", "tests.robot.faulty:ClaimsSuccess",
                          duration=3.0, monitor=False, variation=False)
    header, rows = read_trace(tmp_path / "out" / "trace.jsonl")
    ends = [e for s in rows for e in s.events if e.kind in ("task_success", "task_fail")]
    assert [(e.task, e.kind, e.cause) for e in ends][:4] == [
        ("wrong", "task_fail", "heading"), ("near", "task_success", ""),
        ("wide", "task_success", ""), ("far", "task_fail", "position")]
    assert ends[0].reason == "heading off by 90.0° (tolerance 15°)"
    tasks = summary.measurements["tasks"]
    assert tasks[0]["reason"] == ends[0].reason and not tasks[0]["succeeded"]
    assert [t["cause"] for t in tasks[:4]] == ["heading", "", "", "position"]
    facts = header.mission_facts
    assert facts is not None
    assert [(g.name, g.heading, g.tolerance, g.timeout) for g in facts.goals] == [
        ("wrong", pytest.approx(math.pi / 2), 0.25, 120.0),
        ("near", pytest.approx(math.radians(10)), 0.25, 120.0),
        ("wide", pytest.approx(math.radians(-40)), 0.25, 120.0),
        ("far", None, 0.25, 120.0)]
    assert [g.heading_tolerance for g in facts.goals] == pytest.approx(
        [math.radians(d) for d in (15, 15, 45, 15)])
    assert (facts.goals[0].x, facts.goals[0].y, facts.goals[3].x) == (0.0, 0.0, 1.0)
    assert (facts.cycles, facts.time_limit, facts.mission_max_speed) == (2, 50.0, 0.2)
    assert facts.speed_limit == 0.2 and facts.turn_limit == pytest.approx(1.82)


def test_a_task_cut_short_by_the_duration_limit_is_cut(tmp_path: Path) -> None:
    summary, _ = run_into(_lane(tmp_path, "wall"), tmp_path / "out", "tests.robot.faulty:Idle",
                          duration=1.0, monitor=False, variation=False)
    _, rows = read_trace(tmp_path / "out" / "trace.jsonl")
    [fail] = [e for s in rows for e in s.events if e.kind == "task_fail"]
    # the user's --duration stopped the run: the task's end was never seen
    assert fail.cause == "cut" and fail.reason == "duration limit of 1 s reached"
