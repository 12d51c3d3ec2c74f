"""Malformed protocol input on the real server's stdin (issue 27.1): every case is answered
with an error or dropped with a log line, memory stays bounded, and the server goes on
answering the next well-formed request."""

from __future__ import annotations

import json

from tests.lsp.raw import RawServer, frame

METHOD_NOT_FOUND = -32601


def answers_next_request(server: RawServer, message_id: int) -> None:
    """A well-formed request after the damage is answered (unknown method: its error)."""
    server.request(message_id, "rei/noSuchMethod")
    answer = server.response(message_id)
    assert answer["error"]["code"] == METHOD_NOT_FOUND


def test_absurd_negative_and_missing_lengths_are_dropped_and_logged() -> None:
    server = RawServer()
    try:
        server.initialize()
        body = json.dumps({"jsonrpc": "2.0", "id": 2, "method": "shutdown"}).encode()
        # The length that killed pygls's reader (a MemoryError), then the next message.
        server.send(b"Content-Length: 99999999999\r\n\r\n" + body)
        answers_next_request(server, 3)
        server.send(b"Content-Length: -5\r\n\r\n" + body)
        answers_next_request(server, 4)
        server.send(b"Content-Length: twelve\r\n\r\n" + body)
        answers_next_request(server, 5)
        server.send(b"Content-Type: application/json\r\n\r\n" + body)
        answers_next_request(server, 6)
        assert server.peak_memory_kb() < 400_000
        assert server.stop() == 0
        log = server.log()
        assert "found 99999999999" in log and "found -5" in log
        assert "expected a number after Content-Length" in log
        assert "Traceback" not in log
    finally:
        server.stop()


def test_invalid_json_and_non_messages_are_answered_with_errors() -> None:
    server = RawServer()
    try:
        server.initialize()
        server.send(b"Content-Length: 9\r\n\r\n{not json")
        assert server.response(None)["error"]["code"] == -32700
        server.send(b"Content-Length: 7\r\n\r\n[1,2,3]")
        assert server.response(None)["error"]["code"] == -32600
        server.send(b"Content-Length: 3\r\n\r\n\xff\xfe\xfd")
        assert server.response(None)["error"]["code"] == -32700
        # An unknown request is an error answer; an unknown notification is ignored.
        server.notify("rei/noSuchNotification", {"x": 1})
        answers_next_request(server, 7)
        # Wrong params for a known method: an error answer with the request's id.
        server.send(frame({"jsonrpc": "2.0", "id": 8, "method": "textDocument/hover",
                           "params": {"textDocument": 5}}))
        assert "error" in server.response(8)
        answers_next_request(server, 9)
        assert server.stop() == 0
    finally:
        server.stop()


def test_huge_messages_and_header_lines_keep_memory_bounded() -> None:
    server = RawServer()
    try:
        server.initialize()
        # A 200 kB header line, then a message bigger than the server reads (64 MiB + 1),
        # sent for real: both are skipped a line at a time.
        server.send(b"X-Junk: " + b"j" * 200_000 + b"\r\n\r\n{}")
        answers_next_request(server, 2)
        huge = 64 * 1024 * 1024 + 1
        server.send(b"Content-Length: %d\r\n\r\n" % huge)
        chunk = b"x" * (1024 * 1024)
        for _ in range(65):
            server.send(chunk)
        answers_next_request(server, 3)
        # A large message within the bound (a 3 MB file opened) is read and handled.
        text = "// " + "a" * 3_000_000 + "\nroom r { floor a robot b : turtlebot3_waffle on a }\n"
        server.notify("textDocument/didOpen", {"textDocument": {
            "uri": "file:///tmp/rei-raw-big.room", "languageId": "room", "version": 1,
            "text": text}})
        answers_next_request(server, 4)
        assert server.peak_memory_kb() < 400_000
        assert server.stop() == 0
        assert "skipping" in server.log() or "dropped a message" in server.log()
    finally:
        server.stop()


def slow_vepl(blocks: int) -> str:
    """A .vepl whose parse takes tens of seconds (issue 27: 50,000 ``{+}`` in 150 kB)."""
    return ("query q() { mission_state == ended }\nqueryEvent a() as q found\n"
            "complexEvent c() { as a" + "{+}" * blocks + " }\n")


def test_a_slow_check_never_blocks_requests_and_stops_when_the_text_changes() -> None:
    server = RawServer(log_level="INFO")
    try:
        server.initialize()
        room = "file:///tmp/rei-raw-quick.room"
        server.notify("textDocument/didOpen", {"textDocument": {
            "uri": room, "languageId": "room", "version": 1,
            "text": "room r {\n  floor a\n  robot b : turtlebot3_waffle on a\n}\n"}})
        slow = "file:///tmp/rei-raw-slow.vepl"
        server.notify("textDocument/didOpen", {"textDocument": {
            "uri": slow, "languageId": "vepl", "version": 1, "text": slow_vepl(50_000)}})
        # While the slow file is checked, requests about another file are answered.
        for n in range(3):
            server.request(10 + n, "textDocument/hover", {
                "textDocument": {"uri": room}, "position": {"line": 2, "character": 34}})
            assert "floor" in server.response(10 + n)["result"]["contents"]["value"]
        server.send(frame({"jsonrpc": "2.0", "method": "textDocument/didChange", "params": {
            "textDocument": {"uri": slow, "version": 2},
            "contentChanges": [{"text": "query q() { mission_state == ended }\n"}]}}))
        versions = []
        while 2 not in versions:
            message = server.messages.get(timeout=120)
            assert message is not None
            params = message.get("params") or {}
            if message.get("method") == "textDocument/publishDiagnostics" and \
                    params.get("uri") == slow:
                versions.append(params.get("version"))
        assert versions == [2]  # the stale version was never published
        assert server.stop() == 0
        assert "stopped the check of file:///tmp/rei-raw-slow.vepl" in server.log()
    finally:
        server.stop()
