"""The `launch` target: a ROS 2 launch file, a robot-less world, animator config and run.json."""

from __future__ import annotations

import json
import math

import pytest
from lxml import etree

from rei.generators.errors import GenerationError
from rei.generators.targets import check_target
from rei.generators.targets.launch import TARGET
from tests.conftest import EXAMPLES
from tests.generators.conftest import RequestFor


def files_of(request) -> dict[str, bytes]:
    return dict(TARGET.generate(request).files)


def test_target_conforms() -> None:
    assert check_target(TARGET) == []


def test_launch_file_spawns_the_robot_at_its_start_pose(request_for: RequestFor) -> None:
    files = files_of(request_for(EXAMPLES / "small_dense" / "small_dense.mission"))
    assert sorted(files) == ["animator.json", "rei_test.launch.xml", "run.json", "world.sdf"]
    launch = etree.fromstring(files["rei_test.launch.xml"])
    spawn = next(n for n in launch.iter("node") if n.get("exec") == "create")
    # The robot of small_dense stands on its origin floor facing +y (heading 90).
    assert "-x 0 -y 0 -z 0.01 -Y 1.570796" in spawn.get("args", "")
    executables = [n.get("exec") for n in launch.iter("node")]
    assert {"animator", "data_collector", "mission_executor"} <= set(executables)
    mission = next(n for n in launch.iter("node") if n.get("exec") == "mission_executor")
    param = mission.find("param[@name='mission']")
    assert param is not None and param.get("value") == "$(dirname)/../mission/mission.xml"
    world = etree.fromstring(files["world.sdf"])
    assert "waffle" not in [m.get("name") for m in world.iter("model")]


def test_a_room_has_no_mission_executor(request_for: RequestFor) -> None:
    files = files_of(request_for(EXAMPLES / "navigation" / "navigation.room"))
    launch = etree.fromstring(files["rei_test.launch.xml"])
    assert "mission_executor" not in [n.get("exec") for n in launch.iter("node")]
    run = json.loads(files["run.json"])
    assert run["sources"]["mission"] is None and run["artifacts"]["mission_xml"] is None
    assert run["duration"] == 60.0


def test_run_configuration_names_world_mission_monitor_and_seed(request_for: RequestFor) -> None:
    files = files_of(request_for(EXAMPLES / "navigation" / "navigation.mission", seed="7",
                                 monitor="watch.vepl", controller="scripted", duration="12.5"))
    run = json.loads(files["run.json"])
    assert run["seed"] == 7 and run["controller"] == "scripted" and run["duration"] == 12.5
    assert run["sources"] == {
        "comment": "paths relative to the folder of the generated file's input",
        "room": "navigation.room", "mission": "navigation.mission", "monitor": "watch.vepl"}
    assert run["artifacts"]["gazebo_world"] == "world.sdf"
    assert run["robot"]["floor"] == "start"
    assert list(run) == sorted(run)  # sorted keys: stable diffs


def test_animator_gets_every_trajectory_in_the_world_frame(request_for: RequestFor) -> None:
    files = files_of(request_for(EXAMPLES / "navigation" / "navigation.room"))
    animator = json.loads(files["animator.json"])
    (walker,) = animator["objects"]
    assert walker["name"] == "walker" and walker["loop"] is True
    # lab_2_6 is 5 tiles right of and 1 below the robot's floor lab_1_1 ("start").
    assert walker["points"][0] == {"t": 0.0, "x": 5.0, "y": -1.0}
    assert walker["points"][-1]["x"] == 5.0 and walker["points"][-1]["y"] == -1.0


@pytest.mark.parametrize("key,value,message", [
    ("seed", "-1", "option seed: expected a whole number"),
    ("seed", "x", "option seed"),
    ("duration", "nan", "option duration: expected a finite"),
    ("duration", "0", "option duration"),
    ("controller", "", "option controller"),
])
def test_bad_options_are_reported_by_name(
    request_for: RequestFor, key: str, value: str, message: str,
) -> None:
    request = request_for(EXAMPLES / "navigation" / "navigation.mission", **{key: value})
    with pytest.raises(GenerationError, match=message):
        TARGET.generate(request)


def test_angles_in_run_json_are_normalised(request_for: RequestFor) -> None:
    run = json.loads(files_of(request_for(EXAMPLES / "small_dense" / "small_dense.room"))
                     ["run.json"])
    assert run["robot"]["yaw"] == round(math.pi / 2, 6)
