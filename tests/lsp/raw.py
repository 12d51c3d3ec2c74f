"""The real ``rei-lsp`` as a subprocess fed raw bytes: for the tests of malformed protocol
input, which no LSP client library would send."""

from __future__ import annotations

import json
import queue
import subprocess
import threading
from typing import Any, BinaryIO

from tests.lsp.conftest import SERVER_COMMAND, WAIT_SECONDS


def frame(message: dict[str, Any]) -> bytes:
    body = json.dumps(message).encode("utf-8")
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


def _read_frames(stream: BinaryIO, out: queue.Queue[dict[str, Any] | None]) -> None:
    while True:
        length = None
        while True:
            line = stream.readline()
            if not line:
                out.put(None)
                return
            if line.strip() == b"":
                break
            name, _, value = line.partition(b":")
            if name.lower() == b"content-length":
                length = int(value)
        assert length is not None
        out.put(json.loads(stream.read(length)))


class RawServer:
    """``rei-lsp`` on pipes; ``send`` writes bytes, ``response`` waits for an answer by id."""

    def __init__(self, log_level: str = "WARNING") -> None:
        self.process = subprocess.Popen([*SERVER_COMMAND, "--log-level", log_level],
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=subprocess.PIPE)
        assert self.process.stdin is not None and self.process.stdout is not None
        self.messages: queue.Queue[dict[str, Any] | None] = queue.Queue()
        self.reader = threading.Thread(target=_read_frames,
                                       args=(self.process.stdout, self.messages), daemon=True)
        self.reader.start()
        self.seen: list[dict[str, Any]] = []
        self.stderr = bytearray()
        # Drained all along: a full stderr pipe would stop the server mid-write.
        self.drain = threading.Thread(target=self._drain, daemon=True)
        self.drain.start()

    def _drain(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.stderr += line

    def send(self, data: bytes) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(data)
        self.process.stdin.flush()

    def request(self, message_id: int, method: str, params: Any = None) -> None:
        self.send(frame({"jsonrpc": "2.0", "id": message_id, "method": method,
                         "params": params if params is not None else {}}))

    def notify(self, method: str, params: Any) -> None:
        self.send(frame({"jsonrpc": "2.0", "method": method, "params": params}))

    def response(self, message_id: int | None) -> dict[str, Any]:
        """The answer with this id (id None: an error answer to an unreadable message)."""
        while True:
            for message in self.seen:
                if "method" not in message and message.get("id") == message_id:
                    self.seen.remove(message)
                    return message
            message = self.messages.get(timeout=WAIT_SECONDS)  # a guard against a hang only
            assert message is not None, "the server closed its output"
            self.seen.append(message)

    def initialize(self) -> None:
        self.request(1, "initialize", {"processId": None, "rootUri": None,
                                       "capabilities": {}})
        assert "result" in self.response(1)
        self.notify("initialized", {})

    def peak_memory_kb(self) -> int:
        with open(f"/proc/{self.process.pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
        raise AssertionError("no VmHWM in /proc")

    def stop(self) -> int:
        """shutdown + exit, as an editor ends a session; the exit status."""
        if self.process.poll() is None:
            try:
                self.request(999_999, "shutdown")
                self.response(999_999)
                self.notify("exit", None)
            except (BrokenPipeError, AssertionError):
                pass
        try:
            return self.process.wait(timeout=WAIT_SECONDS)
        finally:
            if self.process.poll() is None:
                self.process.kill()
                self.process.wait()
            self.drain.join(timeout=WAIT_SECONDS)
            for stream in (self.process.stdin, self.process.stdout, self.process.stderr):
                if stream is not None:
                    stream.close()

    def log(self) -> str:
        return self.stderr.decode("utf-8", errors="replace")
