"""A trace read back: each line's JSON checked (UTF-8, every field named once, no lone
surrogate), ``TraceDecoder`` applying the rules to the header, the samples and the end
line, ``read_trace`` (lazy: a damaged line is found when it is read), ``read_trace_end``
and ``open_regular`` (a regular file only). This module never writes a file, must never
import ``encode``, nor the simulation or pybullet.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from rei.lang.source import file_kind, repeated_key
from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.trace.format import TraceError
from rei.runtime.trace.rules import _header, _number, _show
from rei.runtime.trace.sample_rules import _end, _StreamRules

# ---- reading --------------------------------------------------------------------------------


def _load(raw: bytes, where: str) -> Any:
    """One line's JSON value; a line that is not JSON text is a located error."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise TraceError(f"{where}: expected UTF-8 text, found the bytes "
                         f"{raw[exc.start:exc.start + 8]!r} at column {exc.start + 1}") from None
    if not text.strip():
        raise TraceError(f"{where}: expected a JSON object, found an empty line")
    try:
        value = json.loads(text, object_pairs_hook=_unique_fields)
    except _RepeatedField as exc:
        raise TraceError(f"{where}: expected each field once, found {_show(exc.key)} "
                         f"{exc.count} times") from None
    except json.JSONDecodeError as exc:
        raise TraceError(f"{where}: expected a JSON object, found {_show(text.strip())} "
                         f"({exc.msg} at column {exc.colno})") from None
    except (ValueError, RecursionError) as exc:  # a 5000-digit number, [[[[... nested
        raise TraceError(f"{where}: expected a JSON object, found a line JSON cannot hold "
                         f"({type(exc).__name__}: {_show(str(exc))})") from None
    if _ESCAPED_SURROGATE.search(text):
        try:
            json.dumps(value, ensure_ascii=False).encode("utf-8")
        except UnicodeEncodeError:
            raise TraceError(f"{where}: expected text, found a lone surrogate escape "
                             f"(\\ud800-\\udfff without its pair), which no file or "
                             f"terminal can show") from None
    return value


class _RepeatedField(ValueError):
    def __init__(self, key: str, count: int) -> None:
        super().__init__(key)
        self.key, self.count = key, count


def _unique_fields(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object's fields, each named once: with a repeated field JSON keeps the last
    value, so `"contacts": [1], "contacts": []` would hide a contact."""
    repeated = repeated_key(pairs)
    if repeated is not None:
        raise _RepeatedField(*repeated)
    return dict(pairs)


_ESCAPED_SURROGATE = re.compile(r"\\[uU][dD][89a-fA-F]")


def open_regular(path: Path) -> BinaryIO:
    """The trace opened for reading: a regular file only (a FIFO would block, /dev/zero never
    ends a line), checked before it is opened and again through the descriptor."""
    try:
        kind = file_kind(os.stat(path).st_mode)
        if kind is None:
            fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
            kind = file_kind(os.fstat(fd).st_mode)
            if kind is None:
                os.set_blocking(fd, True)
                return os.fdopen(fd, "rb")
            os.close(fd)
    except OSError as exc:
        raise TraceError(f"cannot read the trace '{path}': {exc.strerror or exc}") from None
    raise TraceError(f"cannot read the trace '{path}': expected a regular file, found {kind}")


def _is_partial(path: Path) -> bool:
    """A killed run's trace (``NAME.partial``) may lack its end line; a finished one may not."""
    return path.name.endswith(".partial")


def _no_end(path: Path, lineno: int) -> TraceError:
    return TraceError(f"{path}:{lineno}: expected the end line {{\"end\": time, \"outcome\": "
                      f"..., \"reason\": ...}} after the last sample, found the end of the file "
                      f"(the trace was cut short; a killed run leaves only NAME.partial)")


class TraceDecoder:
    """Trace lines back into records, checked by the rules the writer applies: the header
    first (``header``), then a sample or the end record per line (``line``). What
    ``read_trace`` reads a trace file with, and ``rei.runtime.observation.recordings`` an MCAP
    recording's /rei/trace channel. ``where`` in every call names the line in errors."""

    def __init__(self, first: bytes, where: str) -> None:
        data = _load(first, where)
        if not isinstance(data, dict):
            raise TraceError(f"{where}: expected a REI trace header (a JSON object), found "
                             f"{_show(data)}")
        self.header = _header(data, where)
        self._rules = _StreamRules(len(self.header.objects), self.header.data,
                                   tuple(n for n, _ in self.header.faults))

    def resume_at(self, seq: int, poses: np.ndarray, twists: np.ndarray) -> None:
        """Accept the sample numbered ``seq`` next, on top of every object's pose and twist
        at that sample (a keyframe): a reader that missed the samples before it (a monitor
        on a bus) goes on. Rows are changes, so after a gap only a keyframe makes the next
        line readable."""
        if poses.shape != self._rules.poses.shape or twists.shape != self._rules.twists.shape:
            raise TraceError(f"a keyframe of {len(self._rules.poses)} rows expected, found "
                             f"{len(poses)} and {len(twists)}")
        self._rules.seq = seq
        self._rules.poses[:], self._rules.twists[:] = poses, twists
        if self._rules.time is None:  # not the first sample of the stream: rows are changes
            self._rules.time = 0.0

    def line(self, raw: bytes, where: str) -> Sample | tuple[float, str, str]:
        """The sample of a line, or (end time, outcome, reason) of the end line."""
        data = _load(raw, where)
        try:
            if isinstance(data, dict) and "end" in data:
                return self._rules.end(data, where)
            return self._rules.sample(data, where)
        except (KeyError, IndexError, TypeError, ValueError, OverflowError) as exc:
            # the rules name every field they refuse; this is a last line of defence
            raise TraceError(f"{where}: damaged line ({type(exc).__name__}: {exc})") from None


def _samples(handle: BinaryIO, decoder: TraceDecoder, path: Path) -> Iterator[Sample]:
    lineno = 1
    with handle:
        lines = enumerate(handle, start=2)
        for lineno, raw in lines:
            record = decoder.line(raw, f"{path}:{lineno}")
            if not isinstance(record, Sample):
                for later, _ in lines:
                    raise TraceError(f"{path}:{later}: expected nothing after the end "
                                     f"line (line {lineno}), found another line")
                return
            yield record
    if not _is_partial(path):
        raise _no_end(path, lineno + 1)


def read_trace(path: str | Path) -> tuple[StreamHeader, Iterator[Sample]]:
    """The header and a lazy iterator over the samples of a trace (or its .partial file).

    ``TraceError`` for a damaged header here, for a damaged line when the iterator reaches it
    (also a finished trace without its end line, or anything after it)."""
    path = Path(path)
    handle = open_regular(path)
    try:
        decoder = TraceDecoder(handle.readline(), f"{path}:1")
    except BaseException:
        handle.close()
        raise
    return decoder.header, _samples(handle, decoder, path)


def read_trace_end(path: str | Path) -> tuple[float, str, str] | None:
    """(end time, outcome, reason) of the trace's end line, checked as ``read_trace`` checks
    it: the only end line, the last line, no earlier than the last sample. None for a
    ``.partial`` file without one; ``TraceError`` for a finished trace without one."""
    path = Path(path)
    end: tuple[int, Any] | None = None
    last: tuple[int, Any] | None = None
    lineno = 1
    with open_regular(path) as handle:
        handle.readline()
        for lineno, raw in enumerate(handle, start=2):
            if end is not None:
                raise TraceError(f"{path}:{lineno}: expected nothing after the end line (line "
                                 f"{end[0]}), found another line")
            if raw.startswith(b'{"seq":'):  # a sample as the writer writes it: parsed if last
                last = (lineno, raw)
                continue
            data = _load(raw, f"{path}:{lineno}")
            if isinstance(data, dict) and "end" in data:
                end = (lineno, data)
            else:
                last = (lineno, data)
    if end is None:
        if _is_partial(path):
            return None
        raise _no_end(path, lineno + 1)
    last_time = None
    if last is not None:
        where = f"{path}:{last[0]}"
        data = _load(last[1], where) if isinstance(last[1], bytes) else last[1]
        time = data.get("time") if isinstance(data, dict) else None
        last_time = _number(time, where, "time", low=0.0)
    return _end(end[1], f"{path}:{end[0]}", last_time)
