"""TLS when certificates are given: the router listens on tls/ only, a client checks the
router's certificate against the CA its credentials name, and one that trusts another CA
cannot join. Certificates are made by the real `openssl`."""

from __future__ import annotations

import json
import subprocess
import threading
from pathlib import Path

import pytest

from rei.runtime.bus import BusError, connect
from rei.runtime.bus.router import Tls, start
from rei.runtime.messages import OdometryReading
from tests.bus.conftest import SAFETY
from tests.conftest import require_tool


def _authority(folder: Path, name: str) -> tuple[Path, Path]:
    openssl = require_tool("openssl")
    folder.mkdir()
    key, ca = folder / "ca.key", folder / "ca.pem"
    subprocess.run([openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout",
                    str(key), "-out", str(ca), "-days", "2", "-subj", f"/CN={name}"],
                   check=True, capture_output=True, timeout=SAFETY)
    return key, ca


def _server(folder: Path, ca_key: Path, ca: Path) -> tuple[Path, Path]:
    openssl = require_tool("openssl")
    key, csr, cert = folder / "server.key", folder / "server.csr", folder / "server.pem"
    subprocess.run([openssl, "req", "-newkey", "rsa:2048", "-nodes", "-keyout", str(key),
                    "-out", str(csr), "-subj", "/CN=localhost"],
                   check=True, capture_output=True, timeout=SAFETY)
    (folder / "ext.cnf").write_text("subjectAltName=IP:127.0.0.1,DNS:localhost\n")
    subprocess.run([openssl, "x509", "-req", "-in", str(csr), "-CA", str(ca), "-CAkey",
                    str(ca_key), "-CAcreateserial", "-out", str(cert), "-days", "2",
                    "-extfile", str(folder / "ext.cnf")],
                   check=True, capture_output=True, timeout=SAFETY)
    return cert, key


@pytest.mark.slow
def test_tls_bus(tmp_path: Path) -> None:
    ca_key, ca = _authority(tmp_path / "ca", "REI test CA")
    cert, key = _server(tmp_path / "ca", ca_key, ca)
    _, other_ca = _authority(tmp_path / "other", "Someone else")
    with start(tmp_path / "bus", tls=Tls(cert, key, ca)) as router:
        assert router.bus.endpoint.startswith("tls/127.0.0.1:")
        credentials = json.loads((router.bus.path / "viewer.json").read_text())
        assert credentials["ca"] == str(ca)
        with connect(router.bus.endpoint, role="simulation", credentials=router.bus.path) \
                as sim, connect(router.bus.endpoint, role="viewer",
                                credentials=router.bus.path) as viewer:
            heard = threading.Event()
            viewer.subscribe(["sensor/odometry"], lambda topic, message: heard.set())
            assert sim.await_readers("sensor/odometry", SAFETY)
            sim.publish(OdometryReading(0, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0)))
            assert heard.wait(SAFETY)
        # plain TCP is not spoken there
        with pytest.raises(BusError, match="refused"):
            connect(router.bus.endpoint.replace("tls/", "tcp/"), role="viewer",
                    credentials=router.bus.path)
        # a client that trusts another CA does not trust this router
        forged = tmp_path / "viewer.json"
        forged.write_text(json.dumps({**credentials, "ca": str(other_ca)}))
        forged.chmod(0o600)
        with pytest.raises(BusError, match="refused"):
            connect(router.bus.endpoint, role="viewer", credentials=forged)
