"""Package data: mission (jinja2 templates / XML schemas); no code."""
