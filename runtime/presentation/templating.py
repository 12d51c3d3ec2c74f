"""The jinja2 environment both report pages render with, and the filters they share.

This module must never write files; it only turns values into (autoescaped) markup.
"""

from __future__ import annotations

import jinja2
from markupsafe import Markup, escape


def breakable(name: object) -> Markup:
    """A name that may wrap after its underscores and nowhere else (``GEOM_CLOSE`` never
    becomes ``GEO`` / ``M_CLOSE``): a ``<wbr>`` after each underscore."""
    return Markup("_<wbr>").join(escape(part) for part in str(name).split("_"))


def environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("rei.runtime.presentation", "templates"),
        autoescape=jinja2.select_autoescape(["html", "j2"], default=True),
        undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True)
    env.filters["breakable"] = breakable
    return env
