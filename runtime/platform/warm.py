"""Warm processes: REI's child processes forked from a process that has already imported REI,
instead of a fresh interpreter importing it all again.

A run is three processes (the supervising `rei run`, the simulation, the robot's host), and a
campaign starts one run per mission: each fresh interpreter paid its start-up and REI's
imports (numpy, pybullet, textX, matplotlib, the navigator) again. Two pieces remove that:

* ``rei.runtime.platform.fork``: ``start_child(..., warm=entry)``
(``rei.runtime.platform.processes``)
  forks the calling process and runs ``entry`` in the child instead of executing a new
  interpreter, when that is safe (Linux, one thread alive, warm processes not turned off);
  the child is set up as ``start_child`` sets up an executed one (its own process group,
  death with the thread that started it, only the descriptors it is given, its own folder)
  and never returns into its parent's code;
* ``rei.runtime.runs.fork_server``: a fork server per campaign worker ("zygote"), a process that
  imports what a run needs once and forks a fresh `rei run` process per run; the campaign
  waits for, kills and reads the exit status of that process as it does for an executed
  one, and each run is still a process of its own (crashes and hangs stay its own).

``REI_WARM=off`` turns both off (every child a fresh interpreter, as before): for debugging,
and the "before" of ``bench/campaign.py``. This package must never let a forked child return
into its parent's code, nor fork while another thread is alive.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

WARM_VARIABLE = "REI_WARM"
"""``REI_WARM=off`` (or 0, no, false): every child process a fresh interpreter."""


def warm_enabled(env: Mapping[str, str] | None = None) -> bool:
    """Whether warm processes are allowed (``REI_WARM`` is not off) in ``env`` (default this
    process's environment)."""
    value = (os.environ if env is None else env).get(WARM_VARIABLE, "")
    return value.strip().lower() not in ("off", "0", "no", "false")
