"""Package data: launch (jinja2 templates / XML schemas); no code."""
