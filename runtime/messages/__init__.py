"""The shared message types of a run: the typed, versioned sample stream (thesis 5.1.4, 9.1).

The data collector produces a ``StreamHeader`` once and then one ``Sample`` per collection
tick; the event automata and the evaluator consume them, live or replayed from a trace.
Per-object state travels as numpy arrays aligned with ``StreamHeader.objects`` so the monitor
can compute geometry for thousands of objects vectorised.

A contract at runtime's root, with ``ros`` (REI's one ROS 2 mapping) and ``sink`` (the
``SampleSink`` protocol the stream is published to): it may import only the languages' models,
the catalogue and numpy (rosbags in ``ros``), and must never import pybullet or any wing.

The records live in ``stream`` (the sample stream: header, samples, the belief and mission
events they carry) and ``loop`` (the messages the run loop's components exchange, and their
JSON form); this module re-exports every public name of both, where the code imports them.
"""

from rei.runtime.messages.loop import (
    LOOP_MESSAGES,
    BodyStates,
    BodyVelocities,
    CommandIssued,
    LoopMessage,
    MessageError,
    MissionStatus,
    OdometryReading,
    Pose,
    RobotTruth,
    RobotView,
    ScanReading,
    SignalFired,
    TrackedBodies,
    Velocity,
    message_from_json,
    message_to_json,
)
from rei.runtime.messages.stream import (
    BELIEF_DATA,
    FAILURE_CAUSES,
    MISSION_EVENT_KINDS,
    OBJECT_ROLES,
    SCHEMA_VERSION,
    TASK_EVENT_KINDS,
    UNCOLLECTED,
    GoalFacts,
    LaserScan,
    MissionEvent,
    MissionEventKind,
    MissionFacts,
    NavState,
    ObjectRole,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
    collected_belief,
)

__all__ = [
    "BELIEF_DATA",
    "BodyStates",
    "BodyVelocities",
    "CommandIssued",
    "FAILURE_CAUSES",
    "GoalFacts",
    "LOOP_MESSAGES",
    "LaserScan",
    "LoopMessage",
    "MISSION_EVENT_KINDS",
    "MessageError",
    "MissionEvent",
    "MissionEventKind",
    "MissionFacts",
    "MissionStatus",
    "NavState",
    "OBJECT_ROLES",
    "ObjectRole",
    "ObservedObject",
    "OdometryReading",
    "Pose",
    "RobotBelief",
    "RobotTruth",
    "RobotView",
    "SCHEMA_VERSION",
    "Sample",
    "ScanReading",
    "SignalFired",
    "StreamHeader",
    "TASK_EVENT_KINDS",
    "TrackedBodies",
    "UNCOLLECTED",
    "Velocity",
    "collected_belief",
    "message_from_json",
    "message_to_json",
]
