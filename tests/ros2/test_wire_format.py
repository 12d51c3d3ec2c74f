"""The ROS 2 profile's wire format against rmw_zenoh's published design and ROS 2's own hashes.

Every expected string here is copied from a published source, cited where it is used:
ros2/rmw_zenoh docs/design.md at commit 99a6a2bd10b949052f4f12c5854825dc005e95a5 (key
expressions, liveliness tokens, attachment layout, type hashes of std_msgs/msg/String and
example_interfaces/srv/AddTwoInts as ROS 2 Jazzy computes them). The attachment is also
checked against Zenoh's own serializer (``zenoh.ext.z_serialize``), the Python twin of the
zenoh-cpp ``ext::Serializer`` rmw_zenoh_cpp writes it with.
"""

from __future__ import annotations

import struct

import pytest

from rei.runtime.bus.ros2 import attachment as wire
from rei.runtime.bus.ros2.errors import Ros2Error
from rei.runtime.bus.ros2.names import (
    Distro,
    EntityKind,
    EntityToken,
    QosProfile,
    Reliability,
    dds_type_name,
    parse_token,
    qualified,
    topic_keyexpr,
)
from rei.runtime.bus.ros2.types import register_service, type_hash, typestore

# ros2/rmw_zenoh docs/design.md @ 99a6a2bd10b949052f4f12c5854825dc005e95a5
STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
ADD_TWO_INTS_HASH = "RIHS01_e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a"
DESIGN_KEYS = {
    (0, "/chatter", "std_msgs/msg/String", STRING_HASH):
        "0/chatter/std_msgs::msg::dds_::String_/" + STRING_HASH,
    (0, "/robot1/chatter", "std_msgs/msg/String", STRING_HASH):
        "0/robot1/chatter/std_msgs::msg::dds_::String_/" + STRING_HASH,
    (2, "/add_two_ints", "example_interfaces/srv/AddTwoInts", ADD_TWO_INTS_HASH):
        "2/add_two_ints/example_interfaces::srv::dds_::AddTwoInts_/" + ADD_TWO_INTS_HASH,
}
DESIGN_TOKENS = [
    "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener",
    "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/10/MS/%/%/listener/%chatter/"
    "std_msgs::msg::dds_::String_/" + STRING_HASH + "/::,10:,:,:,,",
    "@ros2_lv/2/8b20917502ee955ac4476e0266340d5c/0/10/MP/%/%/talker/%chatter/"
    "std_msgs::msg::dds_::String_/" + STRING_HASH + "/::,7:,:,:,,",
    "@ros2_lv/2/f9980ee0495eaafb3e38f0d19e2eae12/0/10/SS/%/%/add_two_ints_server/"
    "%add_two_ints/example_interfaces::srv::dds_::AddTwoInts_/" + ADD_TWO_INTS_HASH
    + "/::,10:,:,:,,",
    "@ros2_lv/2/e1dc8d1b45ae8717fce78689cc655685/0/10/SC/%/%/add_two_ints_client/"
    "%add_two_ints/example_interfaces::srv::dds_::AddTwoInts_/" + ADD_TWO_INTS_HASH
    + "/::,10:,:,:,,",
]


@pytest.mark.parametrize(("args", "expected"), list(DESIGN_KEYS.items()))
def test_topic_and_service_key_expressions_are_the_design_documents(
        args: tuple[int, str, str, str], expected: str) -> None:
    assert topic_keyexpr(*args) == expected


def test_type_hashes_are_the_ones_ros2_jazzy_publishes() -> None:
    assert type_hash("std_msgs/msg/String", Distro.JAZZY) == STRING_HASH
    # A service hash covers request, response and the synthesized _Event message: the
    # golden pins all three, and the char-as-uint8 description of ServiceEventInfo.
    register_service(Distro.JAZZY, "example_interfaces/srv/AddTwoInts", "int64 a\nint64 b\n",
                     "int64 sum\n")
    assert type_hash("example_interfaces/srv/AddTwoInts", Distro.JAZZY) == ADD_TWO_INTS_HASH


def test_humble_writes_type_hash_not_supported() -> None:
    for msgtype in ("std_msgs/msg/String", "geometry_msgs/msg/Twist",
                    "nav2_msgs/action/NavigateToPose_SendGoal"):
        assert type_hash(msgtype, Distro.HUMBLE) == "TypeHashNotSupported"


def test_every_profile_type_has_a_distinct_rihs01_hash() -> None:
    from rei.runtime.bus.ros2.profile import endpoints
    hashes = {e.msgtype: type_hash(e.msgtype, Distro.JAZZY)
              for e in endpoints(distro=Distro.JAZZY).values()}
    assert all(h.startswith("RIHS01_") and len(h) == 7 + 64 for h in hashes.values())
    assert len(set(hashes.values())) == len(hashes)
    # NavigateToPose's result changed in Jazzy (error_code, error_msg): so do the hashes of
    # the services and messages that contain it, and only those.
    assert typestore(Distro.HUMBLE).fielddefs["nav2_msgs/action/NavigateToPose_Result"] \
        != typestore(Distro.JAZZY).fielddefs["nav2_msgs/action/NavigateToPose_Result"]


@pytest.mark.parametrize("token", DESIGN_TOKENS)
def test_liveliness_tokens_of_the_design_document_parse_and_rebuild(token: str) -> None:
    parsed = parse_token(token)
    assert parsed.keyexpr == token
    rebuilt = EntityToken(parsed.domain, parsed.session_id, parsed.node_id, parsed.entity_id,
                          parsed.kind, parsed.namespace, parsed.node_name, parsed.enclave,
                          parsed.topic, parsed.msgtype, parsed.type_hash,
                          None if parsed.qos_text is None else
                          QosProfile(depth=int(parsed.qos_text.split(",")[1].split(":")[0])))
    assert rebuilt.keyexpr == token


def test_a_token_built_from_parts_is_the_design_documents() -> None:
    token = EntityToken(2, "e1dc8d1b45ae8717fce78689cc655685", 0, 10, EntityKind.CLIENT, "/",
                        "add_two_ints_client", "/", "/add_two_ints",
                        "example_interfaces/srv/AddTwoInts", ADD_TWO_INTS_HASH, QosProfile())
    assert token.keyexpr == DESIGN_TOKENS[4]
    assert len(token.gid) == 16


def test_qos_compact_form_follows_qos_to_keyexpr() -> None:
    # rmw_zenoh_cpp/src/detail/liveliness_utils.cpp qos_to_keyexpr with the defaults of
    # qos.cpp (reliable, volatile, keep last 42): only what differs is written.
    assert QosProfile(depth=42).keyexpr() == "::,:,:,:,,"
    assert QosProfile(reliability=Reliability.BEST_EFFORT, depth=5).keyexpr() == "2::,5:,:,:,,"
    from rei.runtime.bus.ros2.names import LATCHED_QOS
    assert LATCHED_QOS.keyexpr() == ":1:,1:,:,:,,"


def test_names_are_qualified_and_bad_ones_named() -> None:
    assert qualified("/", "scan") == "/scan"
    assert qualified("/robot1", "scan") == "/robot1/scan"
    assert qualified("/robot1", "/clock") == "/clock"
    assert dds_type_name("nav2_msgs/action/NavigateToPose_SendGoal") \
        == "nav2_msgs::action::dds_::NavigateToPose_SendGoal_"
    with pytest.raises(Ros2Error, match="namespace: expected"):
        qualified("robot1", "scan")
    with pytest.raises(Ros2Error, match="found 'a//b'"):
        qualified("/", "a//b")
    with pytest.raises(Ros2Error, match="domain id"):
        topic_keyexpr(233, "/x", "std_msgs/msg/String", STRING_HASH)
    for bad in ("@ros2_lv/0/z/0/0/XX/%/%/n", "@ros2_lv/0/z/0/0/MP/%/%/n", "0/chatter"):
        with pytest.raises(Ros2Error, match="liveliness token"):
            parse_token(bad)


def test_attachment_is_the_33_bytes_of_the_design_document() -> None:
    gid = bytes(range(1, 17))
    data = wire.Attachment(7, 1_700_000_000_123_456_789, gid).encode()
    # "8 bytes for the sequence number (int64_t), encoded as a little-endian; 8 bytes for
    # the timestamp ... little-endian; 1 byte for the length of the publisher GID (currently
    # always 16); 16 bytes for the publisher GID"
    assert data == struct.pack("<q", 7) + struct.pack("<q", 1_700_000_000_123_456_789) \
        + b"\x10" + gid
    assert wire.decode(data) == wire.Attachment(7, 1_700_000_000_123_456_789, gid)


def test_attachment_matches_zenohs_own_serializer() -> None:
    zenoh = pytest.importorskip("zenoh")
    zenoh_ext = pytest.importorskip("zenoh.ext")
    gid = bytes(range(100, 116))
    theirs = zenoh_ext.z_serialize((zenoh_ext.Int64(-3), zenoh_ext.Int64(42),
                                    [zenoh_ext.UInt8(b) for b in gid])).to_bytes()
    assert wire.Attachment(-3, 42, gid).encode() == theirs
    back = zenoh_ext.z_deserialize(tuple[zenoh_ext.Int64, zenoh_ext.Int64,
                                         list[zenoh_ext.UInt8]],
                                   zenoh.ZBytes(wire.Attachment(5, 6, gid).encode()))
    assert (int(back[0]), int(back[1]), bytes(int(b) for b in back[2])) == (5, 6, gid)


@pytest.mark.parametrize("bad", [None, b"", b"\x00" * 32, b"\x00" * 34,
                                 b"\x00" * 16 + b"\x0f" + b"\x00" * 16])
def test_a_malformed_attachment_is_refused_with_the_reason(bad: bytes | None) -> None:
    with pytest.raises(Ros2Error, match="attachment: expected"):
        wire.decode(bad)


def test_action_messages_round_trip_through_cdr() -> None:
    import numpy as np
    for distro in Distro:
        store = typestore(distro)
        t = store.types
        stamp = t["builtin_interfaces/msg/Time"](12, 500)
        pose = t["geometry_msgs/msg/PoseStamped"](
            t["std_msgs/msg/Header"](stamp, "map"),
            t["geometry_msgs/msg/Pose"](t["geometry_msgs/msg/Point"](1.5, -2.0, 0.0),
                                        t["geometry_msgs/msg/Quaternion"](0, 0, 0, 1)))
        uuid = t["unique_identifier_msgs/msg/UUID"](np.arange(16, dtype=np.uint8))
        request = t["nav2_msgs/action/NavigateToPose_SendGoal_Request"](
            uuid, t["nav2_msgs/action/NavigateToPose_Goal"](pose, ""))
        name = "nav2_msgs/action/NavigateToPose_SendGoal_Request"
        data = bytes(store.serialize_cdr(request, name))
        # CDR little-endian encapsulation header, then the 16 UUID bytes first
        assert data[:4] == b"\x00\x01\x00\x00" and data[4:20] == bytes(range(16))
        back = store.deserialize_cdr(data, name)
        assert back.goal.pose.pose.position.x == 1.5 and back.goal.pose.header.frame_id == "map"


def test_action_hashes_agree_with_an_independent_implementation() -> None:
    # Not ROS 2's own publication, a corroboration: values locked in an independent
    # rmw_zenoh-compatible implementation's tests ("Locked RIHS01 values for the Jazzy IDL")
    # for the ROS 2 tutorial action Fibonacci and for CancelGoal. They agree with what the
    # derivation here (rosidl's Action and Service, see rei.runtime.bus.ros2.types) gives.
    from rei.runtime.bus.ros2.types import register_action
    action = "action_tutorials_interfaces/action/Fibonacci"
    register_action(Distro.JAZZY, action, "int32 order\n", "int32[] sequence\n",
                    "int32[] partial_sequence\n")
    assert {t: type_hash(f"{action}_{t}", Distro.JAZZY)[7:15]
            for t in ("SendGoal", "GetResult", "FeedbackMessage")} \
        == {"SendGoal": "a0603060", "GetResult": "8b47e383", "FeedbackMessage": "50fc26b9"}
    assert type_hash("action_msgs/srv/CancelGoal", Distro.JAZZY) \
        == "RIHS01_573d8b0a534451d7bc2ac8c5ffde8ac14b8593b7001175d0cd6516dcbeb8689a"
    assert type_hash("action_msgs/msg/GoalStatusArray", Distro.JAZZY) \
        == "RIHS01_6c1684b00f177d37438febe6e709fc4e2b0d4248dca4854946f9ed8b30cda83e"
