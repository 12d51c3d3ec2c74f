"""The error of the campaign stage: a campaign could not be planned, resumed or stored.

A failed, crashed or hung *run* is never an error here: it is a recorded outcome.

Every stage has an errors.py of its own (one error class per stage, all under
``rei.lang.errors.ReiError``, as STYLE.md asks), so this file name repeats on purpose.
"""

from __future__ import annotations

from rei.lang.errors import ReiError


class CampaignError(ReiError):
    """The campaign's input or results folder is unusable (named, with what was expected)."""
