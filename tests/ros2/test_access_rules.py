"""The ROS 2 profile under the bus's router rules: the robot role may drive, never forge.

A real router started by the bus (`rei.runtime.bus.router.start`, authentication and access
control on) with ``with_ros2`` added: REI's adapter joins with the simulation role's
credentials, the stand-in ROS 2 node with the robot role's. The stack's cmd_vel reaches
REI; its forged odometry and clock never reach a reader; the monitor role reads the
profile's topics; a late TRANSIENT_LOCAL reader still gets /tf_static through the rules.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Any

import zenoh

from rei.runtime.bus.access import DEFAULT_ACCESS
from rei.runtime.bus.ros2.adapter import Ros2Controller, parse_options
from rei.runtime.bus.ros2.names import Distro
from rei.runtime.bus.ros2.profile import access_rules, endpoints, with_ros2
from rei.runtime.bus.router import start
from tests.ros2.standin import StandInNav2, attachment, wait_for
from tests.ros2.test_nav2_over_router import CONTEXT, observation


def session_as(endpoint: str, folder: Path, role: str) -> Any:
    secret = json.loads((folder / f"{role}.json").read_text())
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", f'["{endpoint}"]')
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("transport/auth/usrpwd/user", f'"{secret["user"]}"')
    config.insert_json5("transport/auth/usrpwd/password", f'"{secret["password"]}"')
    return zenoh.open(config)


def test_the_router_lets_the_stack_drive_and_refuses_its_forgeries(tmp_path: Path) -> None:
    folder = tmp_path / "bus"
    keys = endpoints(distro=Distro.HUMBLE)
    with start(folder, access=with_ros2(DEFAULT_ACCESS, distro=Distro.HUMBLE)) as router:
        endpoint = router.bus.endpoint
        robot_secret = json.loads((folder / "robot.json").read_text())
        stack = StandInNav2(endpoint, auth=(robot_secret["user"], robot_secret["password"]))
        stack.start()
        monitor = session_as(endpoint, folder, "monitor")
        seen: list[bytes] = []
        reader = monitor.declare_subscriber(keys["odom"].keyexpr,
                                            lambda s: seen.append(s.attachment.to_bytes()))
        adapter = Ros2Controller(parse_options(
            f"router={endpoint},distro=humble,cmd-wait=10,credentials={folder}", {}))
        try:
            adapter.reset(CONTEXT)
            wait_for(lambda: False, 0.3)
            adapter.step(observation(0.1, (0.0, 0.0, 0.0)))
            # allowed: REI's sensors reach the stack and the monitor; the stack's cmd_vel
            # reaches REI
            assert stack.counts["odom"] == 1 and adapter.cmd_sub.received.messages == 1
            assert wait_for(lambda: len(seen) == 1, 5)
            # refused by the router: the robot role publishing what the simulation measures
            forger = session_as(endpoint, folder, "robot")
            try:
                for name in ("odom", "clock"):
                    forger.put(keys[name].keyexpr, b"\x00\x01\x00\x00",
                               attachment=attachment(1, bytes(16)))
                time.sleep(0.5)
            finally:
                forger.close()
            adapter.step(observation(0.2, (0.0, 0.0, 0.0)))
            assert wait_for(lambda: len(seen) == 2, 5)
            time.sleep(0.3)
            assert len(seen) == 2 and bytes(16) not in (a[17:] for a in seen)
            assert stack.counts["clock"] == 2  # REI's two, not the forged one
            # a late TRANSIENT_LOCAL reader of /tf_static (the stack's tf listener, started
            # after REI published it once) gets REI's cached transform through the rules
            late: list[bytes] = []
            tf_reader = session_as(endpoint, folder, "robot")
            listener = zenoh.ext.declare_advanced_subscriber(
                tf_reader, keys["tf_static"].keyexpr,
                lambda s: late.append(s.payload.to_bytes()),
                history=zenoh.ext.HistoryConfig(detect_late_publishers=True))
            try:
                assert wait_for(lambda: len(late) == 1, 5), "no cached /tf_static"
            finally:
                listener.undeclare()
                tf_reader.close()
        finally:
            adapter.close()
            reader.undeclare()
            monitor.close()
            stack.close()


def test_access_rules_split_the_profile_by_role() -> None:
    rules = access_rules(domain=3, namespace="/robot1", distro=Distro.JAZZY)
    robot, sim = rules["robot"], rules["simulation"]
    cmd = next(k for k in robot.put if "/cmd_vel/" in k)
    assert cmd.startswith("3/robot1/cmd_vel/geometry_msgs::msg::dds_::Twist_/RIHS01_")
    assert cmd in sim.subscribe and cmd not in sim.put
    assert set(robot.deny_put) == set(sim.put)
    assert any(k.startswith("3/clock/") for k in sim.put)  # /clock is absolute
    assert all("/navigate_to_pose/_action/" in k for k in robot.reply)
    assert robot.liveliness == "@ros2_lv/3/**" and math.isfinite(len(robot.graph))
