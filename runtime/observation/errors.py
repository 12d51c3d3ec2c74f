"""The monitor's error: automata that cannot be loaded or a specification the run cannot
satisfy (a user function that was not registered). Bad samples are never errors: they are
counted and make the verdicts they touch inconclusive."""

from rei.runtime.errors import RunError


class MonitorError(RunError):
    """The event automata could not be set up for this run."""
