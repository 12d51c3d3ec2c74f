"""One run as a session: ``session`` (``run_into``, the library's way to run a mission, and the
supervised child's work), ``config`` (`rei run --config`, format rei-run/1), ``supervisor``
(the simulation in a child process the robot under test cannot reach), ``cache`` (generated
artifacts reused by content), ``fork_server`` (warm workers of a campaign).

It may import observation, simulation, bus, robot, the platform and the contracts; it must
never import the command line or the presentation wing (a run's page is handed in by `rei run`).
"""

from rei.runtime.runs.session import run_into

__all__ = ["run_into"]
