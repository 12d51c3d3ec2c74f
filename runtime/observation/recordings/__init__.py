"""Recordings: the sample stream as an MCAP file with ROS 2 message types (``McapRecorder``)
and its exact REI trace, read back for replay (``read_recording``, ``read_stream``).
See docs/recording.md."""

from rei.runtime.observation.recordings.errors import RecordingError
from rei.runtime.observation.recordings.reader import (
    RecordedSamples,
    is_recording,
    read_recording,
    read_stream,
)
from rei.runtime.observation.recordings.writer import RECORDING, TRACE_TOPIC, McapRecorder

__all__ = ["RECORDING", "TRACE_TOPIC", "McapRecorder", "RecordedSamples", "RecordingError",
           "is_recording", "read_recording", "read_stream"]
