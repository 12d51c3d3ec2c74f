"""The bus stage's one error class: a bus that cannot be started, joined or used.

Everything a user can cause (a wrong endpoint, missing or wrong credentials, an action the
role may not take, a port in use) is a ``BusError`` whose message is one line naming what
was expected and what was found. A message from the wire that cannot be decoded is never an
exception to the receiver: it is dropped and counted (``BusSession.dropped``).

Every stage has an errors.py of its own (one error class per stage, all under
``rei.lang.errors.ReiError``, as STYLE.md asks), so this file name repeats on purpose.
"""

from __future__ import annotations

from rei.lang.errors import ReiError


class BusError(ReiError):
    """The bus could not be started, joined or used as asked."""


class NoAnswer(BusError):
    """A call found nobody to answer it before its deadline (the answerer not joined yet,
    gone, or the router's rules keep the caller from asking): worth asking again."""


INSTALL_HINT = ("the bus needs the Zenoh client library: "
                "pip install 'rei-testbed[bus]' (PyPI eclipse-zenoh)")


def zenoh_module() -> object:
    """The ``zenoh`` module, imported on first use; ``BusError`` with the install hint when
    it is missing (the bus is an optional back end: REI runs in one process without it)."""
    try:
        import zenoh  # noqa: PLC0415
    except ImportError:
        raise BusError(INSTALL_HINT) from None
    return zenoh
