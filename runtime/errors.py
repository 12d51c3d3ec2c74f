"""Errors of the run stage: a simulation run could not be set up.

A run that breaks *while running* (a controller that raises, hangs or answers outside its
contract; under `rei run`, also a simulation process that dies or stops responding) is not an
exception to the caller: it ends with outcome ``error`` and a reason.

Every stage has an errors.py of its own (one error class per stage, all under
``rei.lang.errors.ReiError``, as STYLE.md asks), so this file name repeats on purpose.
"""

from rei.lang.errors import ReiError


class RunError(ReiError):
    """A run could not be set up: a missing or invalid world, configuration or controller."""
