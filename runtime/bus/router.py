"""`rei bus`'s router: a Zenoh router in this process, with generated credentials and rules.

``prepare`` writes the bus's folder (mode 0700): ``users.txt`` (the router's user/password
dictionary), one ``<role>.json`` per role (that role's user, password, endpoint and CA
certificate: what a component is given to join) and ``router.json5`` (the configuration the
router runs with), every file mode 0600. Passwords are fresh per ``rei bus`` (``secrets``),
unless the folder holds an earlier bus's: a restarted bus keeps them, so its components can
join again.
``Router`` opens Zenoh in router mode on that configuration: listening on one endpoint only
(loopback unless told), multicast and gossip scouting off (nothing announces the bus or
joins it uninvited), authentication always on, the access rules of ``rei.runtime.bus.access``
enforced by the router, TLS when a certificate and key are given. This module must never
write outside the bus's folder, nor listen anywhere but the one endpoint.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import socket
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rei.runtime.bus.access import DEFAULT_ACCESS, AccessRules
from rei.runtime.bus.errors import BusError, zenoh_module
from rei.runtime.bus.schema import WIRE_VERSION


@dataclass(frozen=True)
class Tls:
    """The router's certificate and key (PEM), and the CA clients check it against."""

    certificate: Path
    key: Path
    ca: Path


@dataclass(frozen=True)
class BusFolder:
    """What ``prepare`` wrote."""

    path: Path
    endpoint: str
    """The locator clients connect to: ``tcp/127.0.0.1:PORT`` (``tls/...`` with TLS)."""
    config: Path
    credentials: dict[str, Path]
    """Role -> its credentials file."""


def user_of(role: str) -> str:
    return f"rei-{role}"


def free_port(host: str) -> int:
    """A TCP port free on ``host`` now (the kernel's choice)."""
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as s:
        s.bind((host, 0))
        port: int = s.getsockname()[1]
        return port


def _private_folder(path: Path) -> None:
    """``path`` as a folder only its owner can enter (created, or made so)."""
    path.mkdir(mode=0o700, parents=True, exist_ok=True)
    info = path.stat()
    if info.st_uid != os.getuid():
        raise BusError(f"{path}: a folder of this user expected for the bus's credentials, "
                       f"found one of user id {info.st_uid}")
    os.chmod(path, 0o700)


def _write_private(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` readable by the owner only, from its first byte."""
    with contextlib.suppress(FileNotFoundError):
        path.unlink()
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as out:
        out.write(text)


def router_config(endpoint: str, users: Path, access: AccessRules,
                  tls: Tls | None) -> dict[str, Any]:
    config: dict[str, Any] = {
        "mode": "router",
        "listen": {"endpoints": [endpoint]},
        "connect": {"endpoints": []},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
        "transport": {"auth": {"usrpwd": {"dictionary_file": str(users)}}},
        "access_control": access.router_acl({r.role: user_of(r.role) for r in access.roles}),
        # The router's own admin space stays closed: it would tell anyone the rules.
        "adminspace": {"enabled": False},
        "timestamping": {"enabled": {"router": False}},
    }
    if tls is not None:
        config["transport"]["link"] = {"tls": {
            "listen_certificate": str(tls.certificate),
            "listen_private_key": str(tls.key)}}
    return config


def prepare(folder: Path, host: str, port: int, access: AccessRules = DEFAULT_ACCESS,
            tls: Tls | None = None) -> BusFolder:
    """Write the bus's folder for a router on ``host:port``."""
    if host.startswith("[") or any(c in host for c in "/ "):
        raise BusError(f"--host: an address expected (127.0.0.1, ::1, 0.0.0.0), found {host!r}")
    scheme = "tls" if tls is not None else "tcp"
    address = f"[{host}]" if ":" in host else host
    endpoint = f"{scheme}/{address}:{port}"
    _private_folder(folder)
    # A bus restarted on its folder keeps its users: the components that were joined can
    # join again (Zenoh clients reconnect by themselves).
    passwords = {r.role: _kept_password(folder / f"{r.role}.json", r.role)
                 or secrets.token_urlsafe(24) for r in access.roles}
    users = folder / "users.txt"
    _write_private(users, "".join(f"{user_of(r)}:{p}\n" for r, p in passwords.items()))
    credentials = {}
    for role, password in passwords.items():
        path = folder / f"{role}.json"
        _write_private(path, json.dumps({
            "wire": WIRE_VERSION, "role": role, "user": user_of(role), "password": password,
            "endpoint": endpoint, "ca": str(tls.ca) if tls is not None else None},
            indent=2) + "\n")
        credentials[role] = path
    config = folder / "router.json5"
    _write_private(config, json.dumps(router_config(endpoint, users, access, tls),
                                      indent=2) + "\n")
    return BusFolder(folder, endpoint, config, credentials)


def _kept_password(path: Path, role: str) -> str | None:
    """The password a role's credentials file of an earlier `rei bus` holds, if any."""
    try:
        check_private(path)
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, BusError):
        return None
    password = data.get("password") if isinstance(data, dict) else None
    ok = isinstance(password, str) and len(password) >= 24 and data.get("role") == role
    return password if ok else None


def check_private(path: Path) -> None:
    """``BusError`` unless ``path`` is readable by its owner only (credentials must be)."""
    mode = path.stat().st_mode
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise BusError(f"{path}: credentials readable by the owner only expected (mode 0600), "
                       f"found mode {stat.S_IMODE(mode):04o}")


class Router:
    """A running Zenoh router (this process's); ``close`` stops it (again: nothing)."""

    def __init__(self, bus: BusFolder) -> None:
        zenoh: Any = zenoh_module()
        self.bus = bus
        try:
            config = zenoh.Config.from_file(str(bus.config))
            self._session: Any = zenoh.open(config)
        except Exception as exc:  # noqa: BLE001  (zenoh raises ZError for every cause)
            raise BusError(f"cannot start the router on {bus.endpoint}: "
                           f"{str(exc).split(' at ')[0]}") from None

    def close(self) -> None:
        session, self._session = self._session, None
        if session is not None:
            session.close()

    def __enter__(self) -> Router:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def start(folder: Path, host: str = "127.0.0.1", port: int | None = None,
          access: AccessRules = DEFAULT_ACCESS, tls: Tls | None = None) -> Router:
    """Prepare ``folder`` and start the router; a port chosen free unless given (a port
    taken meanwhile by another program is tried again with another, three times)."""
    attempts = 1 if port is not None else 3
    for attempt in range(attempts):
        bus = prepare(folder, host, port if port is not None else free_port(host), access, tls)
        try:
            return Router(bus)
        except BusError:
            if attempt == attempts - 1:
                raise
    raise AssertionError("unreachable")
