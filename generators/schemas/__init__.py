"""Package data: schemas (jinja2 templates / XML schemas); no code."""
