"""Errors of the search stage."""

from rei.lang.errors import ReiError


class SearchError(ReiError):
    """A search cannot start or continue as asked (bad options, a folder of another search)."""
