"""The attachment rmw_zenoh_cpp puts on every message, request and reply.

ros2/rmw_zenoh docs/design.md ("Publishers", "Service Clients", "Service Servers") and
rmw_zenoh_cpp/src/detail/attachment_helpers.cpp: the sequence number (int64), the source
timestamp (int64 nanoseconds since the UNIX epoch) and the GID of the publisher or client
(16 bytes), written with zenoh-cpp's ``ext::Serializer`` -- two little-endian int64 and the
GID as a sequence, that is its length as one LEB128 byte (16) then the bytes: 33 bytes.
A reply carries the request's sequence number and the *client's* GID back.

This module only encodes and decodes; it must never touch a session.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from rei.runtime.bus.ros2.errors import Ros2Error

GID_SIZE = 16
"""RMW_GID_STORAGE_SIZE."""

_LAYOUT = struct.Struct(f"<qqB{GID_SIZE}s")
SIZE = _LAYOUT.size
"""33 bytes."""


@dataclass(frozen=True)
class Attachment:
    sequence_number: int
    source_timestamp: int
    """Nanoseconds since the UNIX epoch (wall clock, as rmw_zenoh stamps it)."""
    source_gid: bytes

    def encode(self) -> bytes:
        if len(self.source_gid) != GID_SIZE:
            raise Ros2Error(f"attachment: expected a GID of {GID_SIZE} bytes, found "
                            f"{len(self.source_gid)}")
        try:
            return _LAYOUT.pack(self.sequence_number, self.source_timestamp, GID_SIZE,
                                self.source_gid)
        except struct.error as exc:
            raise Ros2Error(f"attachment: expected int64 sequence number and timestamp, "
                            f"found {self.sequence_number}, {self.source_timestamp} ({exc})"
                            ) from None


def decode(data: bytes | None) -> Attachment:
    """The attachment of a message, request or reply; Ros2Error when it is not rmw_zenoh's."""
    if data is None:
        raise Ros2Error("attachment: expected rmw_zenoh's 33-byte attachment, found none")
    if len(data) != SIZE:
        raise Ros2Error(f"attachment: expected {SIZE} bytes (int64 sequence number, int64 "
                        f"timestamp, GID length 16, 16 bytes), found {len(data)}")
    sequence, stamp, length, gid = _LAYOUT.unpack(data)
    if length != GID_SIZE:
        raise Ros2Error(f"attachment: expected GID length {GID_SIZE}, found {length}")
    return Attachment(sequence, stamp, gid)
