"""Top-down pictures of rooms and missions (used by `rei-gen show`).

``draw_world`` draws one concrete world (and mission) into a matplotlib Axes; ``render_file``
and ``render_sheet`` produce PNG or SVG bytes for one file or a contact sheet of many.
"""

from rei.generators.picture.draw import draw_world
from rei.generators.picture.render import (
    FORMATS,
    render_concrete,
    render_file,
    render_sheet,
    sheet_entries,
)

__all__ = ["FORMATS", "draw_world", "render_concrete", "render_file", "render_sheet",
           "sheet_entries"]
