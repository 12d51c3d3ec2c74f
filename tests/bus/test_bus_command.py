"""`rei bus` as users run it: a router process that prints its endpoint and credentials,
is joined by a component, and stops cleanly on SIGTERM and on SIGINT (Ctrl-C)."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest

from rei.runtime.bus import connect
from rei.runtime.bus.router import free_port
from rei.runtime.messages import OdometryReading
from tests.bus.conftest import SAFETY, Inbox


def _start(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "rei.runtime.commands", "bus", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.mark.parametrize("stop", [signal.SIGTERM, signal.SIGINT])
def test_rei_bus_serves_until_told_to_stop(tmp_path: Path, stop: signal.Signals) -> None:
    process = _start("--dir", str(tmp_path / "bus"))
    try:
        assert process.stdout is not None
        endpoint = process.stdout.readline().split()
        folder = process.stdout.readline().split()
        assert endpoint[0] == "endpoint" and endpoint[1].startswith("tcp/127.0.0.1:")
        assert folder == ["credentials", str((tmp_path / "bus").resolve())]
        with connect(endpoint[1], role="simulation", credentials=Path(folder[1])) as sim, \
                connect(endpoint[1], role="viewer", credentials=Path(folder[1])) as viewer:
            inbox = Inbox()
            viewer.subscribe(["sensor/odometry"], inbox)
            assert sim.await_readers("sensor/odometry", SAFETY)
            sim.publish(OdometryReading(0, 0.0, (1.0, 2.0, 0.5), (0.1, 0.0)))
            assert inbox.wait(1)[0][1].pose == (1.0, 2.0, 0.5)
        process.send_signal(stop)
        _, err = process.communicate(timeout=SAFETY)
        assert process.returncode == 0, err
        assert err.rstrip().endswith("rei bus: stopped")
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()


def test_rei_bus_refuses_a_port_in_use(tmp_path: Path) -> None:
    port = free_port("127.0.0.1")
    first = _start("--dir", str(tmp_path / "a"), "--port", str(port))
    try:
        assert first.stdout is not None
        assert first.stdout.readline().startswith("endpoint")
        second = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "bus", "--dir",
                                 str(tmp_path / "b"), "--port", str(port)],
                                capture_output=True, text=True, timeout=SAFETY)
        assert second.returncode == 3
        assert second.stderr.startswith(f"rei bus: error: cannot start the router on "
                                        f"tcp/127.0.0.1:{port}")
        assert len(second.stderr.splitlines()) == 1
    finally:
        first.terminate()
        first.communicate(timeout=SAFETY)


def test_rei_bus_refuses_bad_options(tmp_path: Path) -> None:
    bad = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "bus", "--port", "70000"],
                         capture_output=True, text=True, timeout=SAFETY)
    assert (bad.returncode, bad.stderr.strip()) == (
        2, "rei bus: error: --port: a port 1..65535 expected, found 70000")
    tls = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "bus", "--dir",
                          str(tmp_path), "--tls-cert", str(tmp_path / "no.pem")],
                         capture_output=True, text=True, timeout=SAFETY)
    assert tls.returncode == 2
    assert "--tls-cert, --tls-key, --tls-ca missing" in tls.stderr


def test_components_say_a_refusal_in_one_line(tmp_path: Path) -> None:
    from rei.runtime.bus.router import start

    with start(tmp_path / "bus") as router:
        (tmp_path / "wrong").mkdir(mode=0o700)
        forged = tmp_path / "wrong" / "robot.json"
        forged.write_text('{"user": "rei-robot", "password": "guess"}')
        forged.chmod(0o600)
        for command in (["robot", "--controller", "reference"], ["monitor", "-o",
                                                                  str(tmp_path / "m")]):
            done = subprocess.run([sys.executable, "-m", "rei.runtime.commands", *command, "--bus",
                                   router.bus.endpoint, "--credentials", str(forged)],
                                  capture_output=True, text=True, timeout=SAFETY)
            role = command[0]
            assert done.returncode == 2, done.stderr
            assert done.stderr == (f"rei {role}: error: the bus at {router.bus.endpoint} "
                                   f"refused the {role} role's credentials (user "
                                   f"rei-robot)\n")
