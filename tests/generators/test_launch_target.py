"""The `launch` target: run.json that `rei run --config` consumes, the sources it names, the
full Gazebo world and a ROS 2 launch file naming only programs that exist."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from lxml import etree

from rei.generators.errors import GenerationError
from rei.generators.targets import check_target
from rei.generators.targets.launch import BUILT_IN_CONTROLLERS, TARGET
from rei.runtime.robot import BUILT_IN
from tests.conftest import EXAMPLES
from tests.generators.conftest import RequestFor, Write

LAUNCH_TAGS = {"launch", "arg", "include", "node", "param", "let", "set_env", "group",
               "executable", "remap"}
"""Elements of ROS 2's XML launch front end (launch_xml) this file may use."""
ROS_PACKAGES = {"ros_gz_sim", "ros_gz_bridge", "tf2_ros"}
"""Packages of ROS 2 (Humble and later) and ros_gz that the launch file may start."""


def files_of(request) -> dict[str, bytes]:
    return dict(TARGET.generate(request).files)


def test_target_conforms() -> None:
    assert check_target(TARGET) == []


def test_controllers_are_rei_runs_built_in_ones() -> None:
    assert set(BUILT_IN_CONTROLLERS) == set(BUILT_IN)


def test_a_mission_gets_run_json_with_its_sources(request_for: RequestFor) -> None:
    files = files_of(request_for(EXAMPLES / "navigation" / "navigation.mission"))
    assert sorted(files) == ["rei_bag_map.toml", "rei_test.launch.xml", "run.json",
                             "sources/navigation.mission", "sources/navigation.room",
                             "world.sdf"]
    assert files["sources/navigation.room"] == (
        EXAMPLES / "navigation" / "navigation.room").read_bytes()
    run = json.loads(files["run.json"])
    assert run == {"format": "rei-run/1", "mission": "sources/navigation.mission",
                   "vepl": None, "controller": "reference", "seed": 0, "duration": None,
                   "physics_rate": 100.0, "odom_drift": 0.0, "laser_noise": None,
                   "variation": True, "monitor": True}
    assert list(run) == sorted(run)  # sorted keys: stable diffs


def test_options_reach_run_json_and_the_vepl_is_copied(request_for: RequestFor) -> None:
    files = files_of(request_for(EXAMPLES / "navigation" / "navigation.mission", seed="7",
                                 monitor="human_safety.vepl", controller="teleop:circle",
                                 duration="12.5"))
    run = json.loads(files["run.json"])
    assert (run["seed"], run["controller"], run["duration"]) == (7, "teleop:circle", 12.5)
    assert run["vepl"] == "sources/human_safety.vepl" and run["vepl"] in files


def test_sources_keep_their_relative_layout(write: Write, request_for: RequestFor) -> None:
    """A mission that names its room in another folder, and a room with its own catalogue:
    the copies still find each other."""
    write("types/extra.toml", '[types.crate]\nkind = "static"\n'
                              'footprint = { shape = "box", size = [0.4, 0.4] }\nheight = 0.5\n')
    write("rooms/r.room", 'room r {\n catalogue "../types/extra.toml"\n grid g {\n'
                          '  "#####"\n  "#...#"\n  "#####"\n }\n'
                          ' robot bot : turtlebot3_waffle on g_1_1\n'
                          ' object c : crate on g_1_3\n}\n')
    mission = write("missions/m.mission", 'mission m in "../rooms/r.room" {\n'
                                          ' goal a at g_1_1\n goal b at g_1_2\n}\n')
    files = files_of(request_for(mission))
    assert {"sources/missions/m.mission", "sources/rooms/r.room",
            "sources/types/extra.toml"} <= set(files)
    assert json.loads(files["run.json"])["mission"] == "sources/missions/m.mission"


def test_a_room_gets_no_run_json_and_refuses_run_options(request_for: RequestFor) -> None:
    room = EXAMPLES / "navigation" / "navigation.room"
    assert sorted(files_of(request_for(room))) == ["rei_bag_map.toml", "rei_test.launch.xml",
                                                   "world.sdf"]
    with pytest.raises(GenerationError, match="option seed: expected a .mission file"):
        TARGET.generate(request_for(room, seed="3"))


@pytest.mark.parametrize("name", ["navigation/navigation.mission", "navigation/navigation.room",
                                  "small_dense/small_dense.mission"])
def test_launch_file_names_only_programs_that_exist(request_for: RequestFor, name: str) -> None:
    files = files_of(request_for(EXAMPLES / name))
    launch = etree.fromstring(files["rei_test.launch.xml"])
    assert launch.tag == "launch"
    assert {e.tag for e in launch.iter() if isinstance(e.tag, str)} <= LAUNCH_TAGS
    assert {n.get("pkg") for n in launch.iter("node")} <= ROS_PACKAGES
    args = {a.get("name") for a in launch.findall("arg")}
    text = files["rei_test.launch.xml"].decode()
    assert set(re.findall(r"\$\(var (\w+)\)", text)) <= args
    assert set(re.findall(r"\$\(find-pkg-share (\w+)\)", text)) <= ROS_PACKAGES
    assert "rei_ros" not in text and "navigator" not in text
    includes = [i.get("file") for i in launch.iter("include")]
    assert includes == ["$(find-pkg-share ros_gz_sim)/launch/gz_sim.launch.py",
                        "$(var navigation_launch)"]
    # The navigation stack is the user's: a required argument, no default to guess.
    nav = launch.find("arg[@name='navigation_launch']")
    assert nav is not None and nav.get("default") is None
    # The bridge carries the topics the generated world's robot publishes and listens on.
    world = etree.fromstring(files["world.sdf"])
    drive = next(world.iter("plugin"), None)
    assert drive is not None
    bridge = next(n for n in launch.iter("node") if n.get("pkg") == "ros_gz_bridge")
    topics = {arg.split("@")[0] for arg in bridge.get("args", "").split()}
    assert {"/cmd_vel", "/odom", "/scan", "/clock", "/tf"} == topics
    sdf_topics = {e.text for e in world.iter("topic", "odom_topic", "tf_topic")}
    assert {"cmd_vel", "odom", "scan", "tf"} <= sdf_topics


def test_the_world_is_the_gazebo_targets(request_for: RequestFor) -> None:
    from rei.generators.targets.gazebo import TARGET as GAZEBO

    request = request_for(EXAMPLES / "navigation" / "navigation.mission")
    assert files_of(request)["world.sdf"] == GAZEBO.generate(request).files["world.sdf"]


@pytest.mark.parametrize("key,value,message", [
    ("seed", "-1", "option seed: expected a whole number"),
    ("seed", "x", "option seed"),
    ("duration", "nan", "option duration: expected a finite"),
    ("duration", "0", "option duration"),
    ("controller", "", "option controller: expected one of reference"),
    ("controller", "navigator", "option controller: expected one of reference"),
    ("controller", "refrence", "did you mean 'reference'"),
    ("monitor", "missing.vepl", "option monitor: expected a .vepl file"),
    ("monitor", "navigation.room", "option monitor: expected a .vepl file"),
])
def test_bad_options_are_reported_by_name(
    request_for: RequestFor, key: str, value: str, message: str,
) -> None:
    request = request_for(EXAMPLES / "navigation" / "navigation.mission", **{key: value})
    with pytest.raises(GenerationError, match=message):
        TARGET.generate(request)


def test_the_launch_file_records_exactly_what_rei_replay_reads(request_for: RequestFor,
                                                              tmp_path: Path) -> None:
    """Issue 24.4: `ros2 bag record` (MCAP) of the topics
    rei.runtime.observation.recordings.foreign reads,
    the ground truth bridged from Gazebo's poses, and the --map file that reads the bag."""
    from rei.generators.targets.launch import GROUND_TRUTH, RECORDED_TOPICS  # noqa: PLC0415
    from rei.runtime.messages.ros import ROBOT_TOPICS  # noqa: PLC0415
    from rei.runtime.observation.recordings.foreign import load_topic_map  # noqa: PLC0415

    files = files_of(request_for(EXAMPLES / "navigation" / "navigation.mission"))
    launch = etree.fromstring(files["rei_test.launch.xml"])
    commands = [e.get("cmd", "") for e in launch.iter("executable")]
    assert len(commands) == 1
    words = commands[0].split()
    assert words[:3] == ["ros2", "bag", "record"]
    assert words[words.index("--storage") + 1] == "mcap"
    assert "--include-hidden-topics" in words and "--use-sim-time" in words
    recorded = [w for w in words if w.startswith("/")]
    assert recorded == list(RECORDED_TOPICS)
    mapping_file = tmp_path / "rei_bag_map.toml"
    mapping_file.write_bytes(files["rei_bag_map.toml"])
    mapping = load_topic_map(mapping_file)
    # every topic REI reads, under the name it is recorded by
    # /tf itself is recorded too: the stack's own frames, for people looking at the bag
    assert {mapping.topic(t) for t in ROBOT_TOPICS} | {"/tf"} == set(RECORDED_TOPICS)
    assert mapping.topic("/tf") == GROUND_TRUTH and mapping.frame("map") == "navigation"
    bridges = [n for n in launch.iter("node") if n.get("name") == "rei_ground_truth"]
    assert bridges and bridges[0].get("args") == \
        "/world/navigation/dynamic_pose/info@tf2_msgs/msg/TFMessage[gz.msgs.Pose_V"
    remap = bridges[0].find("remap")
    assert remap is not None and remap.get("to") == GROUND_TRUTH
    world = etree.fromstring(files["world.sdf"])
    assert next(world.iter("world")).get("name") == "navigation"
