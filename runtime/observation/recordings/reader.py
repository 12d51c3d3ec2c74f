"""Reading an MCAP recording back: its /rei/trace channel, through the trace's own rules.

``read_recording`` reads the file front to back with mcap's non-seeking reader (chunk CRCs
checked), so it needs no index: a recording cut short by a crash gives every sample of its
complete chunks, and then ends, saying so in ``RecordedSamples.cut_short`` (never an
exception, never a traceback). Each /rei/trace message is one trace line, decoded and
checked by ``TraceDecoder`` exactly as a trace.jsonl line is: a replay from a recording
sees the same samples as from the trace. ``read_stream`` opens either kind of file.

Refused with a ``RecordingError`` naming the file: a file that is not MCAP, a damaged one
(a CRC that does not match, a record that cannot be parsed before the end of the file), one
without a /rei/trace channel or whose channel is not REI's trace. This module must never
import pybullet.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

from mcap.exceptions import EndOfFile, RecordLengthLimitExceeded
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Footer, McapRecord, Message
from mcap.stream_reader import StreamReader, get_chunk_data_stream

from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.messages.ros import trace_line
from rei.runtime.observation.recordings.errors import RecordingError
from rei.runtime.observation.recordings.evidence import EvidenceAudit, EvidenceError
from rei.runtime.observation.recordings.writer import TRACE_TOPIC
from rei.runtime.trace import TraceDecoder, TraceError, open_regular, read_trace, read_trace_end

MAGIC = b"\x89MCAP0\r\n"
_MESSAGE_FIELDS = 20
"""Bytes of a message record between its channel id and its data: sequence (4), log time
(8), publish time (8)."""
End = tuple[float, str, str]


def is_recording(path: str | Path) -> bool:
    """The file starts with MCAP's magic bytes (False for anything unreadable: the trace
    reader then says why)."""
    try:
        with open_regular(Path(path)) as handle:
            return handle.read(len(MAGIC)) == MAGIC
    except TraceError:
        return False


class _Tracked:
    """The file as the MCAP reader reads it, noting whether a read came back short: the
    reader then hit the end of a file cut inside a record."""

    def __init__(self, handle: IO[bytes]) -> None:
        self.handle = handle
        self.short = False

    def read(self, n: int = -1) -> bytes:
        data = self.handle.read(n)
        if n > 0 and len(data) < n:
            self.short = True
        return data

    def tell(self) -> int:
        return self.handle.tell()


class RecordedSamples(Iterator[Sample]):
    """The samples of a recording, read lazily; after the last one, ``end`` is the end
    record's (end time, outcome, reason), or None when the recording was cut short before
    it, and ``cut_short`` says where a cut-short recording ends ("" when complete)."""

    def __init__(self, path: Path, handle: IO[bytes]) -> None:
        self.path = path
        self._handle = handle
        self._tracked = _Tracked(handle)
        size = os.fstat(handle.fileno()).st_size
        # A record longer than the file is a cut one (and never worth allocating for).
        self._records = self._opened(StreamReader(
            self._tracked, validate_crcs=True, emit_chunks=True,  # type: ignore[arg-type]
            record_size_limit=size).records)
        self._channel: int | None = None
        self._cdr = True
        self._topics: list[str] = []
        self._decoder: TraceDecoder | None = None
        self._messages = 0
        self.samples = 0
        self.end: End | None = None
        self.cut_short = ""
        self._done = False
        self._footer = False
        self._cut_at = 0

    # ---- records of the file -----------------------------------------------------------------

    def _opened(self, records: Iterator[McapRecord]) -> Iterator[McapRecord | bytes]:
        """The file's records with each chunk opened (mcap decompresses it and checks its
        CRC): its channels, and the data of each /rei/trace message as bytes; the other
        messages are skipped unparsed (a replay reads only the trace)."""
        for record in records:
            if not isinstance(record, Chunk):
                yield record
                continue
            stream, length = get_chunk_data_stream(record, validate_crc=True)
            while stream.count < length:
                opcode, size = stream.read1(), stream.read8()
                if opcode == Opcode.MESSAGE:
                    channel = stream.read2()
                    rest = stream.read(size - 2)
                    if channel == self._channel:
                        yield rest[_MESSAGE_FIELDS:]
                elif opcode == Opcode.CHANNEL:
                    yield Channel.read(stream)
                else:
                    stream.read(size)

    def _next_record(self) -> McapRecord | bytes | None:
        """The next record, or None at the end of the file (``cut_short`` set if it was cut)."""
        if self._done:
            return None
        at = self._tracked.tell()
        try:
            record = next(self._records)
        except StopIteration:
            self._close()
            return None
        except (EndOfFile, RecordLengthLimitExceeded) as exc:
            self._cut(at, exc)
            return None
        except Exception as exc:  # noqa: BLE001  (mcap's parser, on hostile bytes: any error)
            if self._tracked.short:
                self._cut(at, exc)
                return None
            self._close()
            raise RecordingError(
                f"{self.path}: damaged MCAP recording: the record at byte {at} cannot be read "
                f"({type(exc).__name__}{': ' + str(exc) if str(exc) else ''})") from None
        if isinstance(record, Footer):
            self._footer = True
        return record

    def _cut(self, at: int, exc: BaseException) -> None:
        del exc
        self._close()
        self._cut_at = at
        if self._footer:
            self.cut_short = (f"{self.path}: the file ends inside its closing magic bytes "
                              f"(every record was read)")
            return
        self.cut_short = (f"{self.path}: the recording was cut short (a run that crashed or "
                          f"was killed leaves this): its last complete chunk ends before "
                          f"byte {at}, after {self.samples} sample(s)")

    def _close(self) -> None:
        self._done = True
        self._handle.close()

    def close(self) -> None:
        if not self._done:
            self._close()

    # ---- the trace channel -------------------------------------------------------------------

    def _next_trace(self) -> bytes | None:
        """The data of the next /rei/trace message, or None at the end of the recording."""
        while True:
            record = self._next_record()
            if record is None:
                return None
            if isinstance(record, Channel):
                self._topics.append(record.topic)
                if record.topic == TRACE_TOPIC and self._channel is None:
                    if record.message_encoding not in ("cdr", "json"):
                        self._close()
                        raise RecordingError(
                            f"{self.path}: channel {TRACE_TOPIC}: expected the message "
                            f"encoding 'cdr' (REI's trace lines as std_msgs/msg/String; "
                            f"'json' in older recordings), found "
                            f"{record.message_encoding!r}")
                    self._channel = record.id
                    self._cdr = record.message_encoding == "cdr"
            elif isinstance(record, bytes):  # a /rei/trace message of a chunk
                self._messages += 1
                return self._line(record)
            elif isinstance(record, Message) and record.channel_id == self._channel:
                self._messages += 1  # a message outside chunks (other writers)
                return self._line(record.data)

    def _line(self, data: bytes) -> bytes:
        """The trace line a /rei/trace message carries."""
        if not self._cdr:
            return data
        line = trace_line(data)
        if line is None:
            self._close()
            raise RecordingError(f"{self._where()}: expected a CDR std_msgs/msg/String "
                                 f"holding a trace line, found {len(data)} byte(s) starting "
                                 f"{data[:12]!r}")
        return line

    def _where(self) -> str:
        return f"{self.path}: {TRACE_TOPIC} message {self._messages}"

    def header(self) -> StreamHeader:
        """The trace's header record (the first /rei/trace message)."""
        data = self._next_trace()
        if data is None:
            if self.cut_short:
                raise RecordingError(
                    f"{self.path}: the recording was cut short before its first complete "
                    f"chunk ended (at byte {self._cut_at} of the file; a run that crashed or "
                    f"was killed at its start leaves this): no REI trace to read")
            topics = ", ".join(sorted(set(self._topics))) or "none"
            raise RecordingError(f"{self.path}: expected a {TRACE_TOPIC} channel carrying the "
                                 f"REI trace (recorded by `rei run --record`), found the "
                                 f"topics: {topics} (a ROS 2 recording REI did not make is "
                                 f"judged with --mission M.mission)")
        try:
            self._decoder = TraceDecoder(data, self._where())
        except TraceError:
            self.close()
            raise
        return self._decoder.header

    def __next__(self) -> Sample:
        assert self._decoder is not None, "header() first"
        if self.end is not None:
            data = self._next_trace()
            if data is not None:
                self.close()
                raise RecordingError(f"{self._where()}: expected nothing after the end record "
                                     f"(message {self._messages - 1}), found another record")
            raise StopIteration
        data = self._next_trace()
        if data is None:
            if not self.cut_short:
                raise RecordingError(
                    f"{self.path}: expected the end record {{\"end\": time, \"outcome\": ..., "
                    f"\"reason\": ...}} on {TRACE_TOPIC} after the last sample, found the end "
                    f"of the recording")
            raise StopIteration
        try:
            record = self._decoder.line(data, self._where())
        except TraceError:
            self.close()
            raise
        if isinstance(record, Sample):
            self.samples += 1
            return record
        self.end = record
        return self.__next__()


def read_recording(path: str | Path) -> tuple[StreamHeader, RecordedSamples]:
    """The header and a lazy iterator over the samples of an MCAP recording's trace.

    ``RecordingError`` (a ``TraceError``) for a file that is not MCAP, a damaged one, one
    without the trace, or a bad header here; a damaged record when the iterator reaches it.
    """
    path = Path(path)
    handle = open_regular(path)
    try:
        magic = handle.read(len(MAGIC))
        if magic != MAGIC:
            raise RecordingError(f"{path}: expected an MCAP recording (starting with the MCAP "
                                 f"magic bytes {MAGIC!r}), found {_start(magic)}")
        handle.seek(0)
        samples = RecordedSamples(path, handle)
    except BaseException:
        handle.close()
        raise
    return samples.header(), samples


def _start(data: bytes) -> str:
    if not data:
        return "an empty file"
    return f"a file starting with {data!r}"


class AuditedSamples(Iterator[Sample]):
    """A stream's samples passed through an ``EvidenceAudit``: the k-th sample record
    (0-based) is located as ``where(k + 2)`` (the trace's line, the recording's /rei/trace
    message: the header is 1). ``end()`` checks the end record as well."""

    def __init__(self, header: StreamHeader, samples: Iterator[Sample],
                 read_end: Callable[[], End | None], where: Callable[[int], str]) -> None:
        self.audit = EvidenceAudit(header)
        self._samples = samples
        self._read_end = read_end
        self._where = where
        self._count = 0

    def __next__(self) -> Sample:
        sample = next(self._samples)
        try:
            self.audit.sample(sample, self._where(self._count + 2))
        except EvidenceError:
            self.close()
            raise
        self._count += 1
        return sample

    def close(self) -> None:
        close = getattr(self._samples, "close", None)
        if close is not None:
            close()

    @property
    def cut_short(self) -> str:
        return str(getattr(self._samples, "cut_short", ""))

    def end(self) -> End | None:
        end = self._read_end()
        if end is not None:
            self.audit.end(end, self._where(self._count + 2))
        return end


def read_stream(path: str | Path, audit: bool = True
                ) -> tuple[StreamHeader, Iterator[Sample], Callable[[], End | None]]:
    """The header, the samples and a function giving the end record (None when there is
    none; call it after the samples) of a trace (trace.jsonl) or an MCAP recording (a file
    named .mcap, or starting with MCAP's magic bytes).

    With ``audit`` (the default: whatever judges the stream wants it), the samples and the
    end record are checked against the stream's own evidence (``EvidenceAudit``): a claim
    the ground truth contradicts is an ``EvidenceError`` located at its line or message."""
    path = Path(path)
    if path.suffix == ".mcap" or is_recording(path):
        header, samples = read_recording(path)
        stream: Iterator[Sample] = samples
        read_end: Callable[[], End | None] = lambda: samples.end  # noqa: E731
        where = f"{path}: {TRACE_TOPIC} message {{}}"
    else:
        header, stream = read_trace(path)
        read_end = lambda: read_trace_end(path)  # noqa: E731
        where = f"{path}:{{}}"
    if not audit:
        return header, stream, read_end
    audited = AuditedSamples(header, stream, read_end, where.format)
    return header, audited, audited.end


__all__ = ["MAGIC", "AuditedSamples", "RecordedSamples", "is_recording", "read_recording",
           "read_stream"]
