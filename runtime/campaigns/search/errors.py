"""Errors of the search stage.

Every stage has an errors.py of its own (one error class per stage, all under
``rei.lang.errors.ReiError``, as STYLE.md asks), so this file name repeats on purpose.
"""

from rei.lang.errors import ReiError


class SearchError(ReiError):
    """A search cannot start or continue as asked (bad options, a folder of another search)."""
