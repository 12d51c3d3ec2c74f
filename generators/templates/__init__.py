"""Package data: templates (jinja2 templates / XML schemas); no code."""
