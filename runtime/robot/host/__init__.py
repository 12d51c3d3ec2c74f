"""The controller host: the robot under test runs in its own process, behind messages.

A controller is a user's program, called every control tick. Inside the simulation's process
it could falsify its own test: patch REI's evaluator in memory, register an ``atexit`` hook
that rewrites summary.json, write a fake exit status into the supervisor's pipe. So
``HostedController`` runs it in a child process (``rei.runtime.robot.host.answerer.main``,
started with ``rei.runtime.platform.processes.start_child``: its own process group, dead with the
thread that started it, no file descriptor but its two pipe ends and stderr, its working
folder a fresh temporary one) and talks to it only through messages:

* requests (simulation -> host) are pickles, length-prefixed: the simulation trusts its own
  side; a step's scan is sent once (the laser is slower than the control loop): the host
  keeps the controller's read-only copy for the next steps that carry the same scan;
* answers (host -> simulation) are one JSON line each, never a pickle (unpickling would let
  the controller run code in the simulation): plain numbers, strings and bools, decoded with
  NaN and Infinity refused, at most ``MAX_ANSWER`` bytes, then checked again by
  ``checked_command`` / ``checked_feedback`` as an in-process answer would be. The host's
  ``print`` goes to stderr, so a chatty controller cannot break the framing.

One round trip per control tick: the host answers ``step`` and ``send_goal`` (when they
return normally), then calls the controller's ``feedback()`` itself and sends its answer as a
second line (``FEEDBACK_AFTER``). ``feedback()`` on this side reads that line when it is
asked for, and keeps the feedback until the next call that can change the controller's state
(``reset``, ``send_goal``, ``cancel_goal``, ``step``); only when it holds none does it ask
the host. This relies on the ``Controller`` contract that ``feedback()`` is a pure function of
the controller's state. A feedback line nobody asked for before the next request is read and
dropped: what it says is no fault (no feedback was asked for), but a host that does not
finish it within the watchdog, dies or floods the pipe meanwhile is, named ``feedback()``.

Each answer is awaited at most ``timeout`` wall seconds (select on the pipe): a hang, even in
C holding the interpreter lock, stalls only the host, and the fault names the call. A host
that dies (``os._exit``, a signal, ``sys.exit`` from a thread) is a ``ControllerFault``
naming how it died. Every fault, and ``close``, kills the host's whole process group and
reaps it, so nothing the controller started writes anything after the run. The host's side
is ``serve``; it runs the same ``load_controller`` the in-process path runs. This module
must never import pybullet.
"""

from rei.runtime.robot.host.answerer import HostSide, main, serve
from rei.runtime.robot.host.caller import HostedController, RemoteController, built_in
from rei.runtime.robot.host.wire import (
    command_of,
    decode_answer,
    describe_status,
    feedback_of,
)

__all__ = ["HostSide", "HostedController", "RemoteController", "built_in", "command_of",
           "decode_answer", "describe_status", "feedback_of", "main", "serve"]
