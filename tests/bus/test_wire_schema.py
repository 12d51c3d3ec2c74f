"""The wire schema without a router: every loop message round-trips through its payload,
keys name their topics, and the access rules' key matching agrees with Zenoh's."""

from __future__ import annotations

import numpy as np
import pytest

from rei.runtime.bus import DEFAULT_ACCESS, ROLES, BusError
from rei.runtime.bus.access import key_includes
from rei.runtime.bus.schema import (
    MAX_PAYLOAD,
    decode_message,
    encode_message,
    topic_key,
    topic_of,
)
from rei.runtime.messages import (
    LOOP_MESSAGES,
    BodyStates,
    BodyVelocities,
    CommandIssued,
    LaserScan,
    LoopMessage,
    MissionEvent,
    MissionStatus,
    NavState,
    OdometryReading,
    RobotTruth,
    RobotView,
    ScanReading,
    SignalFired,
    TrackedBodies,
)

SCAN = LaserScan(-1.5, 0.01, 0.1, 3.5, np.linspace(0.1, 3.5, 301))
EVERY_MESSAGE: list[LoopMessage] = [
    RobotTruth(1, 0.004, (1.0, 2.0, 0.1), (3, 7)),
    BodyStates(2, 0.1, (0.1, 0.0, 0.2), np.arange(9.0).reshape(3, 3),
               np.zeros((3, 3)), (1,)),
    TrackedBodies(3, 0.05, ((1.0, 1.0, 0.0),), (0.0, 0.0, 0.0), (0.1, 0.0, 0.0)),
    BodyVelocities(4, 0.05, (((5, 0.1, 0.2, 0.0),), ((5, 0.1, 0.2, 0.1),))),
    ScanReading(5, 0.2, SCAN),
    OdometryReading(6, 0.05, (0.1, 0.2, 0.3), (0.26, -1.0)),
    RobotView(7, 0.05, SCAN, 0.2, (0.1, 0.2, 0.3), (0.26, -1.0)),
    RobotView(8, 0.05, None, None, (0.1, 0.2, 0.3), (0.0, 0.0)),
    CommandIssued(9, 0.05, (2.0, 0.0), (0.26, 0.0)),
    MissionStatus(10, 1.0, (MissionEvent("begin", 1.0), MissionEvent("task_start", 1.0, "g",
                                                                      0)),
                  NavState.ACTIVE, "g"),
    SignalFired(11, 1.0, "SIG_MISSION_BEGIN"),
]


def test_every_topic_is_covered() -> None:
    assert {type(m) for m in EVERY_MESSAGE} == set(LOOP_MESSAGES.values())


@pytest.mark.parametrize("message", EVERY_MESSAGE, ids=lambda m: m.TOPIC)
def test_every_message_round_trips(message: LoopMessage) -> None:
    key = topic_key(message.TOPIC)
    assert key == f"rei/v1/{message.TOPIC}" and topic_of(key) == message.TOPIC
    back = decode_message(key, encode_message(message))
    assert type(back) is type(message)
    assert encode_message(back) == encode_message(message)  # field by field, arrays too


def test_a_message_on_another_topics_key_is_refused() -> None:
    payload = encode_message(SignalFired(0, 0.0, "X"))
    with pytest.raises(BusError, match="rei/v1/sensor/laser: a message of topic "
                                       "'sensor/laser' expected, found 'monitor/signal'"):
        decode_message("rei/v1/sensor/laser", payload)


def test_payload_size_is_limited() -> None:
    big = ScanReading(0, 0.0, LaserScan(0.0, 0.001, 0.1, 3.5, np.full(500_000, 1.234567891)))
    with pytest.raises(BusError, match=f"more than the bus's {MAX_PAYLOAD}"):
        encode_message(big)


def test_unknown_topics_are_named() -> None:
    with pytest.raises(BusError, match="a topic expected to be one of animator/velocities"):
        topic_key("sensor/camera")
    assert topic_of("rei/v1/config/world") is None and topic_of("ros/odom") is None


@pytest.mark.parametrize(("pattern", "key", "included"), [
    ("rei/v1/**", "rei/v1/sensor/laser", True),
    ("rei/v1/**", "rei/v1", True),
    ("rei/v1/sensor/**", "rei/v1/sensor/laser", True),
    ("rei/v1/sensor/**", "rei/v1/truth/robot", False),
    ("rei/v1/*/laser", "rei/v1/sensor/laser", True),
    ("rei/v1/*/laser", "rei/v1/a/b/laser", False),
    ("rei/v1/robot/view", "rei/v1/robot/view", True),
    ("rei/v1/robot/view", "rei/v1/robot/*", False),
    ("rei/v1/sensor/**", "rei/v1/**", False),
    ("rei/v1/**", "rei/v1/**", True),
])
def test_key_inclusion(pattern: str, key: str, included: bool) -> None:
    assert key_includes(pattern, key) is included


def test_profiles_extend_a_role() -> None:
    ros = DEFAULT_ACCESS.with_keys("robot", "publish", ["*/cmd_vel/**"])
    assert ros.role("robot").allows("publish", "0/cmd_vel/geometry_msgs::msg::dds_::Twist_/x")
    assert not DEFAULT_ACCESS.role("robot").allows("publish", "0/cmd_vel/x")
    assert ros.role("robot").allows("publish", "rei/v1/robot/out/x")  # kept
    acl = ros.router_acl({r: f"rei-{r}" for r in ROLES})
    (rule,) = [r for r in acl["rules"] if r["id"] == "robot-publish-ingress"]
    assert rule["key_exprs"] == ["rei/v1/robot/out/**", "*/cmd_vel/**"]
    with pytest.raises(BusError, match="an action expected to be one of publish"):
        DEFAULT_ACCESS.with_keys("robot", "delete", ["x"])


def test_a_role_says_what_it_may_not_do() -> None:
    with pytest.raises(BusError, match=r"^the robot role may not publish on "
                                       r"rei/v1/sensor/odometry \(it may publish on: "
                                       r"rei/v1/robot/out/\*\*\)$"):
        DEFAULT_ACCESS.role("robot").check("publish", "rei/v1/sensor/odometry")
