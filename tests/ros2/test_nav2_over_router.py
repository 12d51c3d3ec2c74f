"""A ROS 2 navigation stack over a real Zenoh router as REI's robot under test.

The stack is ``standin.StandInNav2``: written on Zenoh and rosbags alone from rmw_zenoh's
published format, it shares no code with ``rei.runtime.bus.ros2``. The tests prove that what
REI puts on the wire is what such a node reads (topics, attachments, liveliness tokens,
the action's services), that a mission driven through it reaches its goals with REI's own
verdict, and that a missing stack or a wrong option ends as a located error, not a hang.
Every wait is bounded.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
import zenoh
from rosbags.typesys import Stores, get_typestore

from rei.catalogue import DriveSpec, LaserSpec
from rei.runtime.bus.ros2.adapter import Ros2Controller, parse_options
from rei.runtime.bus.ros2.errors import Ros2Error
from rei.runtime.messages import LaserScan, NavState
from rei.runtime.robot.contract import ControllerContext, NavGoal, Observation
from tests.ros2.standin import StandInNav2, wait_for

REPO = Path(__file__).resolve().parents[2]
LASER = LaserSpec(beams=36, min_range=0.1, max_range=5.0, rate=10.0, fov=2 * math.pi,
                  mount_x=0.1)
CONTEXT = ControllerContext(robot_size=(0.4, 0.3), drive=DriveSpec(0.5, 1.5, 0.3, 0.05),
                            laser=LASER, start_pose=(0.0, 0.0, 0.0), obstacles=(),
                            bounds=(-5.0, -5.0, 5.0, 5.0), tile_size=1.0, control_rate=10.0,
                            seed=3)


@pytest.fixture
def standin(zenoh_router: str) -> Iterator[StandInNav2]:
    node = StandInNav2(zenoh_router).start()
    try:
        yield node
    finally:
        node.close()


@contextmanager
def adapter(options: str) -> Iterator[Ros2Controller]:
    """REI's side, reset and given a moment for its subscriptions to meet the stack's."""
    robot = Ros2Controller(parse_options(options, {}))
    try:
        robot.reset(CONTEXT)
        wait_for(lambda: False, 0.3)
        yield robot
    finally:
        robot.close()


def reaches(robot: Ros2Controller, state: NavState, time: float = 0.1,
            pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> bool:
    """Whether stepping in place brings the goal to ``state`` within 5 wall seconds."""
    def stepped() -> bool:
        robot.step(observation(time, pose))
        return robot.feedback().state == state
    return wait_for(stepped, 5)


def observation(time: float, pose: tuple[float, float, float]) -> Observation:
    scan = LaserScan(-math.pi, 2 * math.pi / 36, 0.1, 5.0, np.full(36, 5.0))
    return Observation(time, pose, (0.0, 0.0), scan, time)


def tokens(router: str) -> list[str]:
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", f'["{router}"]')
    config.insert_json5("scouting/multicast/enabled", "false")
    with zenoh.open(config) as session:
        return [str(r.ok.key_expr) for r in session.liveliness().get("@ros2_lv/0/**",
                                                                       timeout=2.0)
                if r.ok is not None]


def run_mission(router: str, out: Path, distro: str = "humble"
                ) -> tuple[subprocess.CompletedProcess[str], dict]:
    spec = f"ros2:router={router},distro={distro},cmd-wait=10,server-wait=20"
    run = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run",
                          str(REPO / "examples/simple_wall/simple_wall.mission"), "-o", str(out),
                          "--controller", spec, "--no-variation", "--watchdog", "60"],
                         capture_output=True, text=True, timeout=600)
    return run, json.loads((out / "summary.json").read_text())


def test_a_mission_driven_through_a_ros2_node_reaches_its_goals(
        zenoh_router: str, standin: StandInNav2, tmp_path: Path) -> None:
    run, summary = run_mission(zenoh_router, tmp_path / "out")
    assert run.returncode == 0, (run.stdout[-2000:], run.stderr[-2000:], summary)
    assert summary["verdict"] == "pass" and summary["outcome"] == "completed"
    # what the stand-in saw came in rmw_zenoh's format, on simulated time
    assert standin.counts["goals"] == 2 and standin.counts["bad_attachment"] == 0
    assert standin.counts["odom"] > 10 and standin.counts["scan"] > 5
    assert standin.counts["cmd_vel"] >= standin.counts["odom"] - 1
    assert standin.clock_ns == sorted(standin.clock_ns) and standin.clock_ns[0] >= 0


def test_a_ros2_stack_that_breaks_a_requirement_fails_by_reis_own_rules(
        zenoh_router: str, standin: StandInNav2, tmp_path: Path) -> None:
    # The same stand-in, configured faster than the robot's drive (0.26 m/s): the goals are
    # still reached, and the default .vepl's SPEED_LIMIT fails the run (exit 1).
    standin.max_linear = 0.4
    run, summary = run_mission(zenoh_router, tmp_path / "out")
    assert run.returncode == 1, (run.stdout[-2000:], run.stderr[-2000:])
    failed = {v["requirement"] for v in summary["verdicts"] if v["status"] == "fail"}
    assert summary["outcome"] == "completed" and failed == {"SPEED_LIMIT"}


def test_the_adapter_announces_itself_in_the_ros_graph(
        zenoh_router: str, standin: StandInNav2) -> None:
    with adapter(f"router={zenoh_router},distro=humble"):
        seen = "\n".join(tokens(zenoh_router))
    zid = r"[0-9a-f]+"
    for pattern in [
        rf"@ros2_lv/0/{zid}/0/0/NN/%/%/rei_sim",
        rf"@ros2_lv/0/{zid}/0/\d+/MP/%/%/rei_sim/%clock/rosgraph_msgs::msg::dds_::Clock_/"
        r"TypeHashNotSupported/::,10:,:,:,,",
        rf"@ros2_lv/0/{zid}/0/\d+/MP/%/%/rei_sim/%scan/sensor_msgs::msg::dds_::LaserScan_/"
        r"TypeHashNotSupported/2::,5:,:,:,,",
        rf"@ros2_lv/0/{zid}/0/\d+/MP/%/%/rei_sim/%tf_static/tf2_msgs::msg::dds_::TFMessage_/"
        r"TypeHashNotSupported/:1:,1:,:,:,,",
        rf"@ros2_lv/0/{zid}/0/\d+/MS/%/%/rei_sim/%cmd_vel/geometry_msgs::msg::dds_::Twist_/"
        r"TypeHashNotSupported/::,10:,:,:,,",
        rf"@ros2_lv/0/{zid}/0/\d+/SC/%/%/rei_sim/%navigate_to_pose%_action%send_goal/"
        r"nav2_msgs::action::dds_::NavigateToPose_SendGoal_/TypeHashNotSupported/::,10:,:,:,,",
        rf"@ros2_lv/0/{zid}/0/\d+/MS/%/%/rei_sim/%navigate_to_pose%_action%status/"
        r"action_msgs::msg::dds_::GoalStatusArray_/TypeHashNotSupported/:1:,1:,:,:,,",
        # and the stand-in's own tokens are visible to the same query
        rf"@ros2_lv/0/{zid}/0/0/NN/%/%/standin_nav2",
    ]:
        assert re.search(f"^{pattern}$", seen, re.MULTILINE), (pattern, seen)


def test_jazzy_key_expressions_carry_rihs01_hashes(zenoh_router: str) -> None:
    # the stand-in computes its hashes with rosbags directly, not with rei.runtime.bus.ros2
    store = get_typestore(Stores.ROS2_JAZZY)
    hashes = {f"{t.replace('/msg/', '::msg::dds_::')}_": store.hash_rihs01(t)
              for t in ("geometry_msgs/msg/Twist", "nav_msgs/msg/Odometry",
                        "sensor_msgs/msg/LaserScan", "rosgraph_msgs/msg/Clock")}
    node = StandInNav2(zenoh_router, type_hash=hashes).start()
    robot = Ros2Controller(parse_options(f"router={zenoh_router},distro=jazzy,cmd-wait=10",
                                         {}))
    try:
        robot.reset(CONTEXT)
        wait_for(lambda: False, 0.3)  # let the subscriptions meet
        command = robot.step(observation(0.1, (0.0, 0.0, 0.0)))
        # The stand-in answers /cmd_vel on the odometry: the scan and the clock of the same
        # tick may be decoded on its other subscribers' threads just after (seen under load).
        wait_for(lambda: node.counts["scan"] >= 1 and node.counts["clock"] >= 1, 10.0)
        assert node.counts["odom"] == 1 and node.counts["scan"] == 1
        # every beam of observation()'s scan is at range_max: no return, +inf (REP 117)
        assert node.scan_no_return == 36 and node.scan_at_max == 0
        assert node.counts["clock"] == 1 and node.clock_ns == [100_000_000]
        assert robot.cmd_sub.received.messages == 1 and command.linear == 0.0
    finally:
        robot.close()
        node.close()


def test_goals_follow_the_action_and_a_cancel_preempts(
        zenoh_router: str, standin: StandInNav2) -> None:
    with adapter(f"router={zenoh_router},distro=humble,cmd-wait=10") as robot:
        robot.send_goal(NavGoal("east", 1.0, 0.0, None, 0.25, 30.0))
        # send_goal waited (cmd-wait) for the server, which accepted it
        assert robot.feedback().state == NavState.ACTIVE
        states, pose, time = [], [0.0, 0.0, 0.0], 0.0
        for _ in range(400):
            time += 0.1
            command = robot.step(observation(time, (pose[0], pose[1], pose[2])))
            pose[2] += command.angular * 0.1
            pose[0] += command.linear * 0.1 * math.cos(pose[2])
            pose[1] += command.linear * 0.1 * math.sin(pose[2])
            states.append(robot.feedback().state)
            if states[-1] == NavState.SUCCEEDED:
                break
        assert states[-1] == NavState.SUCCEEDED, states[-20:]
        assert NavState.ACTIVE in states and math.hypot(pose[0] - 1.0, pose[1]) <= 0.25
        robot.send_goal(NavGoal("back", 0.0, 0.0, None, 0.25, 30.0))
        assert wait_for(lambda: standin.counts["goals"] == 2, 5)
        robot.cancel_goal()
        assert reaches(robot, NavState.PREEMPTED, time, (pose[0], pose[1], pose[2]))
        assert standin.counts["cancels"] == 1


def test_a_goal_nobody_serves_is_aborted_with_what_to_check(zenoh_router: str) -> None:
    with adapter(f"router={zenoh_router},domain=7,cmd-wait=0,server-wait=0.5") as robot:
        robot.send_goal(NavGoal("g", 1.0, 0.0, None, 0.25, 30.0))
        assert reaches(robot, NavState.ABORTED)
        message = robot.feedback().message
        assert "no navigate_to_pose action server" in message and "ROS_DOMAIN_ID=7" in message
        assert "no such server in the ROS graph of domain 7" in message
        # no cmd_vel either: the base stays stopped
        assert robot.step(observation(0.2, (0.0, 0.0, 0.0))).linear == 0.0


@pytest.mark.parametrize(("text", "message"), [
    ("domian=1", "unknown option 'domian'"),
    ("domain=300", "expected a ROS domain id 0..232, found '300'"),
    ("distro=iron", "expected one of humble, jazzy, found 'iron'"),
    ("cmd-wait=nan", "expected seconds >= 0, found 'nan'"),
    ("namespace=robot1", "namespace: expected '/'"),
    ("goals=service", "expected action or topic"),
    ("router", "expected key=value"),
])
def test_bad_options_are_named(text: str, message: str) -> None:
    with pytest.raises(Ros2Error, match=re.escape(message)):
        parse_options(text, {})


def test_ros_domain_id_of_the_environment_is_the_default() -> None:
    assert parse_options("", {"ROS_DOMAIN_ID": "5"}).domain == 5
    assert parse_options("domain=2", {"ROS_DOMAIN_ID": "5"}).domain == 2


def test_rei_run_names_a_bad_option_and_exits_2(tmp_path: Path) -> None:
    run = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run",
                          str(REPO / "examples/simple_wall/simple_wall.mission"), "-o",
                          str(tmp_path / "out"), "--controller", "ros2:distro=iron"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2, run.stderr
    assert "distro: expected one of humble, jazzy, found 'iron'" in run.stderr


def test_an_unreachable_router_is_a_run_error_with_the_address(tmp_path: Path) -> None:
    from rei.runtime.bus.router import free_port
    port = free_port("127.0.0.1")
    run = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run",
                          str(REPO / "examples/simple_wall/simple_wall.mission"), "-o",
                          str(tmp_path / "out"), "--controller",
                          f"ros2:router=tcp/127.0.0.1:{port}"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 3, (run.stdout, run.stderr)
    assert f"tcp/127.0.0.1:{port}" in run.stdout + run.stderr + (
        tmp_path / "out" / "summary.json").read_text()


def test_the_adapter_passes_the_controller_conformance_checker(
        zenoh_router: str, standin: StandInNav2) -> None:
    # REI's own checker of the robot contract, with the stand-in stack answering: the goal
    # states, cancel, and two runs after reset() giving the same commands.
    from rei.runtime.robot.conformance import check_controller
    robot = Ros2Controller(parse_options(f"router={zenoh_router},distro=humble,cmd-wait=10",
                                         {}))
    try:
        assert check_controller(robot, steps=300) == []
    finally:
        robot.close()


def test_a_goal_on_the_simple_topic_ends_when_odometry_is_there(
        zenoh_router: str, standin: StandInNav2) -> None:
    with adapter(f"router={zenoh_router},distro=humble,cmd-wait=10,goals=topic") as robot:
        robot.send_goal(NavGoal("east", 0.6, 0.0, None, 0.25, 30.0))
        assert robot.feedback().state == NavState.ACTIVE
        assert wait_for(lambda: standin.counts["goal_pose"] == 1, 5)
        pose, time, states = [0.0, 0.0, 0.0], 0.0, []
        for _ in range(200):
            time += 0.1
            command = robot.step(observation(time, (pose[0], pose[1], pose[2])))
            pose[0] += command.linear * 0.1
            states.append(robot.feedback().state)
            if states[-1] == NavState.SUCCEEDED:
                break
        assert states[-1] == NavState.SUCCEEDED and abs(pose[0] - 0.6) <= 0.25
        assert standin.counts["goals"] == 0  # the action was not used


def test_a_stack_that_answers_in_time_gives_byte_identical_runs(
        zenoh_router: str, standin: StandInNav2, tmp_path: Path) -> None:
    # Not lock-stepped, but REI waits (cmd-wait) for each answer: a stack that answers in
    # time is driven by the same messages at the same simulated times, run after run.
    outputs = []
    for name in ("a", "b"):
        run, summary = run_mission(zenoh_router, tmp_path / name)
        assert run.returncode == 0, (run.stdout[-2000:], run.stderr[-2000:])
        outputs.append(tuple((tmp_path / name / f).read_bytes()
                             for f in ("events.csv", "trace.jsonl")))
    assert outputs[0] == outputs[1]


def test_malformed_or_non_finite_commands_are_refused_at_the_edge(
        zenoh_router: str, standin: StandInNav2) -> None:
    from tests.ros2.standin import attachment
    robot = Ros2Controller(parse_options(f"router={zenoh_router},distro=humble,cmd-wait=0.3",
                                         {}))
    robot.reset(CONTEXT)
    t = standin.store.types
    vector = t["geometry_msgs/msg/Vector3"]

    def twist(linear: float) -> bytes:
        return bytes(standin.store.serialize_cdr(
            t["geometry_msgs/msg/Twist"](vector(linear, 0.0, 0.0), vector(0.0, 0.0, 0.0)),
            "geometry_msgs/msg/Twist"))

    try:
        wait_for(lambda: False, 0.3)
        robot.step(observation(0.1, (0.0, 0.0, 0.0)))
        # The stand-in answers that tick's /odom with one /cmd_vel; on a loaded machine it
        # may arrive after the step's cmd-wait: count from after it, so only the bad
        # messages below can change the counts.
        assert wait_for(lambda: robot.cmd_sub.received.messages
                        == standin.counts["cmd_vel"] >= 1, 5)
        before = robot.cmd_sub.received.messages
        # no attachment, and a truncated payload: dropped and counted, never a crash
        standin.cmd_pub.put(twist(0.1))
        standin.cmd_pub.put(twist(0.1)[:10], attachment=attachment(99, standin.gid))
        assert wait_for(lambda: robot.cmd_sub.received.dropped == 2, 5)
        assert robot.cmd_sub.received.messages == before
        # a NaN command ends the run as an error naming it
        standin.cmd_pub.put(twist(math.nan), attachment=attachment(100, standin.gid))
        assert wait_for(lambda: robot.cmd_sub.received.messages == before + 1, 5)
        with pytest.raises(Ros2Error, match="non-finite cmd_vel"):
            robot.step(observation(0.2, (0.0, 0.0, 0.0)))
    finally:
        robot.close()


def test_a_namespaced_robot_meets_its_stack_and_the_clock_stays_global(
        zenoh_router: str) -> None:
    node = StandInNav2(zenoh_router, namespace="robot1/").start()
    robot = Ros2Controller(parse_options(
        f"router={zenoh_router},distro=humble,cmd-wait=10,namespace=/robot1", {}))
    try:
        robot.reset(CONTEXT)
        wait_for(lambda: False, 0.3)
        robot.send_goal(NavGoal("east", 1.0, 0.0, None, 0.25, 30.0))
        robot.step(observation(0.1, (0.0, 0.0, 0.0)))
        wait_for(lambda: node.counts["clock"] >= 1, 10.0)  # decoded beside the odometry
        assert node.counts["odom"] == 1 and node.counts["clock"] == 1
        assert node.counts["goals"] == 1 and robot.cmd_sub.received.messages == 1
        assert robot.feedback().state == NavState.ACTIVE
    finally:
        robot.close()
        node.close()


def test_a_distro_mismatch_is_named_when_the_goal_is_aborted(
        zenoh_router: str, standin: StandInNav2) -> None:
    # The stand-in is a Humble stack (TypeHashNotSupported); REI told distro=jazzy: the keys
    # never meet, and the abort says why from the ROS graph.
    with adapter(f"router={zenoh_router},distro=jazzy,cmd-wait=0,server-wait=0.5") as robot:
        robot.send_goal(NavGoal("g", 1.0, 0.0, None, 0.25, 30.0))
        assert reaches(robot, NavState.ABORTED)
        message = robot.feedback().message
        assert "node standin_nav2 serves /navigate_to_pose/_action/send_goal with type hash " \
               "TypeHashNotSupported, REI speaks RIHS01_" in message
        assert "distro" in message


def test_a_jazzy_stack_with_independently_computed_hashes_drives_the_mission(
        zenoh_router: str, tmp_path: Path) -> None:
    # The stand-in as a Jazzy stack: every key carries the RIHS01 hash it computed itself
    # (standin.rihs01, written from REP 2011, services included), the action's result is
    # Jazzy's (error_code, error_msg). REI with distro=jazzy meets it on every key.
    from tests.ros2.standin import jazzy_hashes
    hashes = jazzy_hashes()
    assert all(h.startswith("RIHS01_") for h in hashes.values())
    node = StandInNav2(zenoh_router, jazzy=True).start()
    try:
        run, summary = run_mission(zenoh_router, tmp_path / "out", distro="jazzy")
    finally:
        node.close()
    assert run.returncode == 0, (run.stdout[-2000:], run.stderr[-2000:], summary)
    assert summary["verdict"] == "pass" and node.counts["goals"] == 2
    assert node.counts["bad_attachment"] == 0 and node.counts["scan"] > 5


def test_the_action_client_reads_goal_status_codes_through_the_shared_mapping() -> None:
    # accepted counts as active for the mission (the server has the goal); STATUS_UNKNOWN
    # ("not properly set") and codes action_msgs does not define report nothing
    from rei.runtime.bus.ros2.nav2 import _state  # noqa: PLC0415

    status = get_typestore(Stores.ROS2_HUMBLE).types["action_msgs/msg/GoalStatus"]
    assert [_state(c) for c in range(8)] == [
        None, NavState.ACTIVE, NavState.ACTIVE, NavState.ACTIVE, NavState.SUCCEEDED,
        NavState.PREEMPTED, NavState.ABORTED, None]
    assert status.STATUS_ACCEPTED == 1 and status.STATUS_ABORTED == 6
