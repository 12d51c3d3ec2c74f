"""The LSP base protocol on stdin, read with bounded memory and no trust in the client.

pygls's own reader believes every ``Content-Length`` (``99999999999`` made it allocate until
a MemoryError killed the server), reads header lines of any length, and ignores a message
whose header it cannot read without saying so. This reader replaces it for ``rei-lsp``:

- a header line longer than MAX_HEADER_LINE, a missing, negative or non-numeric
  ``Content-Length``: the message is dropped with a log line, and reading resumes at the next
  ``Content-Length`` header it finds (the body of the broken message is skipped);
- a ``Content-Length`` above MAX_MESSAGE_BYTES: dropped with a log line, and reading resumes
  at the next header, so a client that sends more messages after a wrong length is still
  heard (the bytes between are read a line of at most MAX_HEADER_LINE bytes at a time);
- a body that is not JSON, or JSON that is not a JSON-RPC message: an error answer
  (ParseError / InvalidRequest, id null or the request's id) and a log line;
- a message whose handler fails is logged; the server goes on.

It must never hold more than one message (at most MAX_MESSAGE_BYTES) in memory, never
raise out of the loop on anything the client sends, and never interpret a message itself:
valid messages go to pygls's protocol unchanged.
"""

from __future__ import annotations

import asyncio
import json
import logging
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Any, BinaryIO

from lsprotocol import types
from pygls.protocol import JsonRPCProtocol

log = logging.getLogger("rei.lsp")

MAX_HEADER_LINE = 8192
"""Bytes of one header line (real ones are under 100)."""
MAX_MESSAGE_BYTES = 64 * 1024 * 1024
"""Bytes of one message body: a 32 MB file (the largest REI reads) as JSON, escaped."""
_CHUNK = 64 * 1024
PARSE_ERROR = -32700
INVALID_REQUEST = -32600
_LENGTH = b"content-length:"


class BoundedStdin:
    """stdin read off the event loop, a line or a chunk at a time, never more than asked."""

    def __init__(self, stream: BinaryIO, executor: ThreadPoolExecutor) -> None:
        self.stream = stream
        self.executor = executor

    async def readline(self, limit: int) -> bytes:
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self.executor, self.stream.readline, limit)

    async def read(self, size: int) -> bytes:
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self.executor, self.stream.read, size)


async def _rest_of_line(reader: BoundedStdin, line: bytes) -> bool:
    """Skip what remains of an overlong line; False at the end of the stream."""
    while not line.endswith(b"\n"):
        line = await reader.readline(MAX_HEADER_LINE)
        if not line:
            return False
    return True


async def _read_headers(reader: BoundedStdin, pending: bytes | None
                        ) -> tuple[int | None, str, bytes | None] | None:
    """(content length or None, what was wrong, a header line found while skipping) of the
    next message; None at the end of the stream."""
    length: int | None = None
    problem = ""
    seen = False
    while True:
        line = pending if pending is not None else await reader.readline(MAX_HEADER_LINE)
        pending = None
        if not line:
            return None
        if not line.endswith(b"\n"):
            if not await _rest_of_line(reader, line):
                return None
            problem = problem or f"a header line longer than {MAX_HEADER_LINE} bytes"
            seen = True
            continue
        text = line.strip()
        if not text:
            if seen:
                return length, problem, None
            continue  # blank lines between messages
        seen = True
        name, _, value = text.partition(b":")
        if name.strip().lower() == b"content-length":
            try:
                length = int(value.strip())
            except ValueError:
                length = None
                problem = f"expected a number after Content-Length, found {value[:40]!r}"
                continue
            if length < 0:
                problem = f"expected a Content-Length of 0 or more bytes, found {length}"
                length = None


async def _resynchronise(reader: BoundedStdin) -> bytes | None:
    """After a message whose length is unknown or refused: skip to the next
    ``Content-Length`` header (a JSON body has no newline, so the next header follows it on
    the same line). A header cut in two by the line limit is still found."""
    carry = b""
    while True:
        line = await reader.readline(MAX_HEADER_LINE)
        if not line:
            return None
        text = carry + line
        at = text.lower().find(_LENGTH)
        if at >= 0:
            found = text[at:]
            if found.endswith(b"\n"):
                return found
            rest = await reader.readline(MAX_HEADER_LINE)  # the header's own end
            return found + rest
        carry = b"" if line.endswith(b"\n") else text[-len(_LENGTH):]


def _answer_error(protocol: JsonRPCProtocol, message_id: Any, code: int, text: str) -> None:
    try:
        protocol._send_response(message_id, None, types.ResponseError(code=code, message=text))
    except Exception:
        log.exception("answering a malformed message failed")


def _request_id(body: bytes) -> Any:
    try:
        raw = json.loads(body)
    except ValueError:
        return None
    if isinstance(raw, dict) and isinstance(raw.get("id"), (int, str)):
        return raw["id"]
    return None


def dispatch(protocol: JsonRPCProtocol, body: bytes) -> None:
    """Hand one body to pygls, or answer why it cannot be."""
    try:
        message = json.loads(body, object_hook=protocol.structure_message)
    except (ValueError, UnicodeDecodeError) as exc:
        log.warning("dropped a message that is not JSON (%s): %r", exc, body[:80])
        _answer_error(protocol, None, PARSE_ERROR, f"expected a JSON message, found: {exc}")
        return
    except Exception as exc:  # pygls could not structure it (wrong params)
        log.warning("dropped a message pygls cannot read (%s): %r", exc, body[:80])
        _answer_error(protocol, _request_id(body), INVALID_REQUEST,
                      f"expected a JSON-RPC message with valid params, found: {exc}")
        return
    if not hasattr(message, "jsonrpc"):
        log.warning("dropped a JSON value that is not a JSON-RPC message: %r", body[:80])
        _answer_error(protocol, _request_id(body), INVALID_REQUEST,
                      "expected a JSON-RPC 2.0 object with 'jsonrpc', 'method' or 'id'")
        return
    try:
        protocol.handle_message(message)
    except Exception:
        log.exception("handling a message failed: %r", body[:80])


async def read_messages(stop: threading.Event, reader: BoundedStdin,
                        protocol: JsonRPCProtocol) -> None:
    """The server's read loop: until the end of stdin or until ``stop`` is set."""
    pending: bytes | None = None
    while not stop.is_set():
        headers = await _read_headers(reader, pending)
        pending = None
        if headers is None:
            return
        length, problem, _ = headers
        if length is None or length > MAX_MESSAGE_BYTES:
            log.warning("dropped a message: %s; reading on at the next Content-Length header",
                        problem or f"expected a Content-Length of at most {MAX_MESSAGE_BYTES} "
                                   f"bytes, found {length}")
            pending = await _resynchronise(reader)
            if pending is None:
                return
            continue
        chunks: list[bytes] = []
        missing = length
        while missing > 0:
            chunk = await reader.read(min(missing, _CHUNK * 16))
            if not chunk:
                return
            chunks.append(chunk)
            missing -= len(chunk)
        dispatch(protocol, b"".join(chunks))
