"""A real Zenoh router on loopback for the ROS 2 profile's tests (started and stopped here).

The router is Zenoh's own, opened from Python in a child process (mode "router", listening
on 127.0.0.1 at a free port, multicast scouting off): the same router `rei bus` runs.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator

import pytest

from rei.runtime.bus.router import free_port

ROUTER = """
import sys, zenoh
config = zenoh.Config()
config.insert_json5("mode", '"router"')
config.insert_json5("listen/endpoints", '["%s"]' % sys.argv[1])
config.insert_json5("scouting/multicast/enabled", "false")
session = zenoh.open(config)
print("ready", flush=True)
sys.stdin.read()  # until the test closes our stdin
session.close()
"""


@pytest.fixture
def zenoh_router() -> Iterator[str]:
    """The endpoint (tcp/127.0.0.1:PORT) of a Zenoh router running for this test."""
    pytest.importorskip("zenoh")
    endpoint = f"tcp/127.0.0.1:{free_port('127.0.0.1')}"
    process = subprocess.Popen([sys.executable, "-c", ROUTER, endpoint],
                               stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        assert line.strip() == "ready", f"the router did not start: {line!r}"
        yield endpoint
    finally:
        assert process.stdin is not None
        process.stdin.close()
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        if process.stdout is not None:
            process.stdout.close()
