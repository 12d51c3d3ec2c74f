"""Errors of the generation stage."""

from rei.lang.errors import ReiError


class GenerationError(ReiError):
    """An artifact could not be generated or written; nothing was left half-written."""
