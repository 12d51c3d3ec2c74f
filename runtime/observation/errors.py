"""The monitor's error: automata that cannot be loaded or a specification the run cannot
satisfy (a user function that was not registered). Bad samples are never errors: they are
counted and make the verdicts they touch inconclusive.

Every stage has an errors.py of its own (one error class per stage, all under
``rei.lang.errors.ReiError``, as STYLE.md asks), so this file name repeats on purpose.
"""

from rei.runtime.errors import RunError


class MonitorError(RunError):
    """The event automata could not be set up for this run."""
