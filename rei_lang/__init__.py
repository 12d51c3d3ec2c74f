"""REI's languages: .room, .mission (and .vepl), their checks, and the command line.

Public API::

    Workspace        check and load files (rooms imported by missions are read once)
    load_room        a valid RoomDocument, or LanguageError with every diagnostic
    load_mission     a valid MissionDocument (with its room), or LanguageError
    Diagnostic       FILE:LINE:COL: RULE-ID: message
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("rei-testbed")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
