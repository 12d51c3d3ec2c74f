"""The bus: REI's components in separate processes (or machines) over a Zenoh router.

In one process the board (``rei.runtime.simulation.loop.board``) carries the run's messages; across
processes the same stamped messages travel over the bus, with the wire schema of
``schema`` (docs/bus.md), the roles and access rules of ``access``, the router of
``router`` (`rei bus`) and the client of ``client``. Zenoh is an optional dependency
(``pip install 'rei-testbed[bus]'``), imported only when a bus is used.

Errors: ``BusError`` (one line, naming what was expected and found).

The ROS 2 profile (``ros2/``) puts a ROS 2 stack on rmw_zenoh's wire as the robot under test.
The bus may import the robot wing (the robot contract travels over it), the platform and the
contracts; it must never import the simulation, pybullet, observation or anything above.
"""

from rei.runtime.bus.access import (
    ACTIONS,
    DEFAULT_ACCESS,
    ROLES,
    AccessRules,
    RoleAccess,
)
from rei.runtime.bus.client import BusSession, Message, Subscription, connect
from rei.runtime.bus.errors import BusError
from rei.runtime.bus.schema import CONFIG_NAMES, MAX_PAYLOAD, PREFIX, WIRE_VERSION

__all__ = [
    "ACTIONS",
    "CONFIG_NAMES",
    "DEFAULT_ACCESS",
    "MAX_PAYLOAD",
    "PREFIX",
    "ROLES",
    "WIRE_VERSION",
    "AccessRules",
    "BusError",
    "BusSession",
    "Message",
    "RoleAccess",
    "Subscription",
    "connect",
]
